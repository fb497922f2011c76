//! Preset libraries (issue 30): where presets are found, what a listing shows, and how a name
//! resolves when two libraries hold the same one.
//!
//! The search path, first to last: the `presets/` folder next to the open graph (a project's own
//! presets), every folder of `PYROGRAPH_PRESET_PATH` in order (a studio's shared libraries;
//! separated by `:`, as `PATH`), then the presets that come with pyrograph (`graphs/presets/`).
//! A preset's name is its metadata's `name`, else its file stem; when two folders hold the same
//! name the earlier one wins and the listing says which file it hides, as Houdini resolves an HDA
//! found twice on `HOUDINI_PATH`.

use std::ffi::OsStr;
use std::path::{Path, PathBuf};

use pyrograph_core::document::{GraphDoc, PresetDoc};

/// The environment variable naming a studio's preset folders.
pub const PRESET_PATH_VAR: &str = "PYROGRAPH_PRESET_PATH";

/// The presets that come with pyrograph: `graphs/presets/` of the source tree this crate was built
/// from (the folder above `frontend/`).
pub fn builtin_dir() -> PathBuf {
    let crate_dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    crate_dir.parent().unwrap_or(crate_dir).join("graphs/presets")
}

/// The folders searched, first to last: `<graph folder>/presets`, the folders of `env` (the value
/// of [`PRESET_PATH_VAR`]), then `builtin`. Empty entries are skipped and a folder listed twice
/// is searched once, at its first place.
pub fn search_path(graph_dir: Option<&Path>, env: Option<&OsStr>, builtin: &Path) -> Vec<PathBuf> {
    let mut dirs: Vec<PathBuf> = Vec::new();
    let mut push = |d: PathBuf| {
        if !d.as_os_str().is_empty() && !dirs.iter().any(|x| same_dir(x, &d)) {
            dirs.push(d);
        }
    };
    if let Some(g) = graph_dir {
        push(g.join("presets"));
    }
    for d in env.map(std::env::split_paths).into_iter().flatten() {
        push(d);
    }
    push(builtin.to_path_buf());
    dirs
}

fn same_dir(a: &Path, b: &Path) -> bool {
    match (a.canonicalize(), b.canonicalize()) {
        (Ok(x), Ok(y)) => x == y,
        _ => a == b,
    }
}

/// One preset found on the search path.
#[derive(Clone, Debug, PartialEq)]
pub struct Preset {
    /// The name it is found by.
    pub name: String,
    /// Its file.
    pub file: PathBuf,
    /// Its metadata (defaults when the file has none).
    pub meta: PresetDoc,
    /// The metadata's description, else the document's.
    pub description: String,
}

/// A preset hidden by an earlier one of the same name.
#[derive(Clone, Debug, PartialEq)]
pub struct Shadowed {
    /// The hidden preset.
    pub preset: Preset,
    /// The file that wins.
    pub by: PathBuf,
}

/// What a search path holds.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Library {
    /// Presets by name, in search-path order, each name once.
    pub presets: Vec<Preset>,
    /// Presets hidden by an earlier one of the same name.
    pub shadowed: Vec<Shadowed>,
    /// Files that could not be read as presets, with the reason (a newer document version, a
    /// syntax error, ...).
    pub refused: Vec<(PathBuf, String)>,
    /// Folders of the search path that do not exist.
    pub missing: Vec<PathBuf>,
}

impl Library {
    /// Reads every `*.ron` of every folder of `dirs`, in order (files by name within a folder).
    pub fn scan(dirs: &[PathBuf]) -> Library {
        let mut lib = Library::default();
        for dir in dirs {
            if let Err(why) = pyrograph_core::limits::may_read(dir) {
                lib.refused.push((dir.clone(), why));
                continue;
            }
            let Ok(entries) = std::fs::read_dir(dir) else {
                lib.missing.push(dir.clone());
                continue;
            };
            let mut files: Vec<PathBuf> =
                entries.filter_map(|e| e.ok().map(|e| e.path())).filter(|p| p.extension().is_some_and(|x| x == "ron")).collect();
            files.sort();
            for file in files {
                // A link in the folder may point anywhere: each file is checked where it leads.
                if let Err(why) = pyrograph_core::limits::may_read(&file) {
                    lib.refused.push((file, why));
                    continue;
                }
                match GraphDoc::load(&file) {
                    Ok(doc) => lib.add(preset_of(file, doc)),
                    Err(d) => lib.refused.push((file, d.to_string())),
                }
            }
        }
        lib
    }

    fn add(&mut self, p: Preset) {
        match self.presets.iter().find(|q| q.name == p.name) {
            Some(first) => self.shadowed.push(Shadowed { by: first.file.clone(), preset: p }),
            None => self.presets.push(p),
        }
    }

    /// The preset found by `name`.
    pub fn find(&self, name: &str) -> Option<&Preset> {
        self.presets.iter().find(|p| p.name == name)
    }
}

fn preset_of(file: PathBuf, doc: GraphDoc) -> Preset {
    let meta = doc.preset.unwrap_or_default();
    let stem = file.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    let name = if meta.name.trim().is_empty() { stem } else { meta.name.trim().to_string() };
    let description = if meta.description.is_empty() { doc.description.unwrap_or_default() } else { meta.description.clone() };
    Preset { name, file, meta, description }
}

/// Whether `p` carries every tag of `tags` and contains `text` (case-insensitive) in its name,
/// description or tags. Empty filters match everything.
pub fn matches(p: &Preset, tags: &[String], text: Option<&str>) -> bool {
    let has = |t: &String| p.meta.tags.iter().any(|x| x.eq_ignore_ascii_case(t));
    let text = text.map(str::to_lowercase).unwrap_or_default();
    let in_text = |s: &str| s.to_lowercase().contains(&text);
    tags.iter().all(has) && (in_text(&p.name) || in_text(&p.description) || p.meta.tags.iter().any(|t| in_text(t)))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(dir: &Path, file: &str, text: &str) {
        std::fs::write(dir.join(file), text).unwrap();
    }

    #[test]
    fn earlier_folders_win_a_name_and_later_ones_are_reported() {
        let (a, b) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
        write(a.path(), "torch.ron", r#"(version: 3, preset: (name: "torch", tags: ["fire"]), nodes: {})"#);
        write(b.path(), "my-torch.ron", r#"(version: 3, preset: (name: "torch", description: "b's"), nodes: {})"#);
        write(b.path(), "lantern.ron", r#"(version: 1, description: "from the document", nodes: {})"#);
        let lib = Library::scan(&[a.path().to_path_buf(), b.path().to_path_buf()]);
        assert_eq!(lib.presets.len(), 2);
        assert_eq!(lib.find("torch").unwrap().file, a.path().join("torch.ron"));
        assert_eq!(lib.shadowed.len(), 1);
        assert_eq!(lib.shadowed[0].preset.file, b.path().join("my-torch.ron"));
        assert_eq!(lib.shadowed[0].by, a.path().join("torch.ron"));
        // No metadata: named by the file, described by the document.
        assert_eq!(lib.find("lantern").unwrap().description, "from the document");
    }

    #[test]
    fn newer_documents_are_refused_and_missing_folders_noted() {
        let a = tempfile::tempdir().unwrap();
        write(a.path(), "future.ron", r#"(version: 9, preset: (name: "future"), nodes: {})"#);
        let gone = a.path().join("gone");
        let lib = Library::scan(&[a.path().to_path_buf(), gone.clone()]);
        assert!(lib.presets.is_empty());
        assert_eq!(lib.refused.len(), 1);
        assert!(lib.refused[0].1.contains("newer than this pyrograph"), "{}", lib.refused[0].1);
        assert_eq!(lib.missing, vec![gone]);
    }

    #[test]
    fn the_search_path_runs_graph_folder_env_then_builtin_without_repeats() {
        let env = std::env::join_paths(["/studio/a", "", "/studio/b", "/studio/a"]).unwrap();
        let dirs = search_path(Some(Path::new("/shows/x")), Some(&env), Path::new("/opt/p"));
        let want: Vec<PathBuf> = ["/shows/x/presets", "/studio/a", "/studio/b", "/opt/p"].iter().map(PathBuf::from).collect();
        assert_eq!(dirs, want);
    }

    #[test]
    fn filters_need_every_tag_and_find_text_anywhere() {
        let meta = PresetDoc { tags: vec!["fire".into(), "Candle".into()], ..PresetDoc::default() };
        let p = Preset { name: "candle row".into(), file: PathBuf::new(), meta, description: "Five candles in wind".into() };
        assert!(matches(&p, &[], None));
        assert!(matches(&p, &["candle".into()], Some("WIND")));
        assert!(!matches(&p, &["candle".into(), "smoke".into()], None));
        assert!(!matches(&p, &[], Some("torch")));
    }
}
