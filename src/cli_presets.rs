//! The preset side of the CLI (issue 30): `presets` lists a library and cooks its thumbnails,
//! `preset NAME` renders one preset into frames without writing a graph around it.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use pyrograph::{errln, outln};
use pyrograph_frontend::core::builtin::INCLUDE_PATH;
use pyrograph_frontend::core::{BuildOptions, Graph, GraphDoc, NodeDoc, ParamValue, Registry};
use pyrograph_frontend::preset_cook::{PRESET_NODE, thumbnail, thumbnail_path, wrap};
use pyrograph_frontend::presets::{Library, PRESET_PATH_VAR, Preset, builtin_dir, matches, search_path};
use pyrograph_frontend::text::printable_json;
use serde_json::json;

use crate::{Failure, RenderOpts, apply_sets, cook_graph};

/// What `pyrograph presets` lists, and whether it cooks thumbnails.
pub struct PresetQuery {
    pub dir: Option<PathBuf>,
    pub graph: Option<PathBuf>,
    pub tags: Vec<String>,
    pub search: Option<String>,
    /// Cook thumbnails: into this folder, or (`Some(None)`) beside each preset as its metadata says.
    pub thumbnails: Option<Option<PathBuf>>,
    pub overwrite: bool,
}

/// The search path of a query: `--dir` alone, else the graph's `presets/`, the studio folders and
/// pyrograph's own.
fn library(dir: Option<&Path>, graph: Option<&Path>) -> Result<Library, Failure> {
    let dirs = match dir {
        Some(d) => {
            if !d.is_dir() {
                return Err(Failure(format!("error: cannot read preset folder {}: not a folder", d.display())));
            }
            vec![d.to_path_buf()]
        }
        None => {
            let graph_dir = graph.map(|g| g.parent().map(Path::to_path_buf).unwrap_or_default());
            let env = std::env::var_os(PRESET_PATH_VAR);
            search_path(graph_dir.as_deref(), env.as_deref(), &builtin_dir())
        }
    };
    let lib = Library::scan(&dirs);
    for d in &lib.missing {
        if d == &builtin_dir() {
            errln!("note: pyrograph's own presets are not at {} (a binary moved away from its source tree)", d.display());
        } else {
            errln!("note: preset folder {} does not exist", d.display());
        }
    }
    for s in &lib.shadowed {
        errln!(
            "note: preset '{}' in {} is hidden by {} (earlier in the search path)",
            s.preset.name,
            s.preset.file.display(),
            s.by.display()
        );
    }
    for (file, why) in &lib.refused {
        errln!("error: {}: not a usable preset: {why}", file.display());
    }
    Ok(lib)
}

pub fn presets(registry: &Registry, q: &PresetQuery, json_out: bool) -> Result<(), Failure> {
    let lib = library(q.dir.as_deref(), q.graph.as_deref())?;
    let mut failed = !lib.refused.is_empty();
    let chosen: Vec<&Preset> = lib.presets.iter().filter(|p| matches(p, &q.tags, q.search.as_deref())).collect();
    if let Some(out) = &q.thumbnails {
        for p in &chosen {
            failed |= !cook_thumbnail(registry, p, out.as_deref(), q.overwrite);
        }
        return if failed { Err(Failure(String::new())) } else { Ok(()) };
    }
    let mut list = Vec::new();
    for p in chosen {
        match preset_entry(registry, &p.file) {
            Ok(mut entry) => {
                let hides: Vec<String> =
                    lib.shadowed.iter().filter(|s| s.by == p.file).map(|s| s.preset.file.display().to_string()).collect();
                let m = &p.meta;
                let extra = json!({"name": p.name, "description": p.description, "tags": m.tags, "revision": m.revision,
                    "author": m.author, "licence": m.licence, "thumbnail": m.thumbnail, "requires": m.requires,
                    "samples": m.samples, "hides": hides});
                if let (Some(e), serde_json::Value::Object(more)) = (entry.as_object_mut(), extra) {
                    e.extend(more);
                }
                list.push(entry);
            }
            Err(e) => {
                failed = true;
                errln!("{e}");
            }
        }
    }
    if json_out {
        println!("{}", printable_json(serde_json::Value::Array(list)));
    } else {
        for p in &list {
            print_entry(p);
        }
    }
    if failed { Err(Failure(String::new())) } else { Ok(()) }
}

fn print_entry(p: &serde_json::Value) {
    let tags: Vec<&str> = p["tags"].as_array().into_iter().flatten().filter_map(|t| t.as_str()).collect();
    let tags = if tags.is_empty() { String::new() } else { format!("  [{}]", tags.join(", ")) };
    outln!("{}  {}{tags}", p["name"].as_str().unwrap_or(""), p["file"].as_str().unwrap_or(""));
    outln!("    {}", p["description"].as_str().unwrap_or(""));
    for kind in ["inputs", "params", "outputs"] {
        for port in p[kind].as_array().into_iter().flatten() {
            outln!(
                "    {kind:<8} {:<18} {:<14} {}",
                port["name"].as_str().unwrap_or(""),
                port["type"].as_str().unwrap_or(""),
                port["default"].as_str().unwrap_or("")
            );
        }
    }
}

/// Cooks and writes one thumbnail; says what happened on stdout (or why not on stderr) and
/// returns whether it went well. An existing thumbnail is kept unless `overwrite`.
fn cook_thumbnail(registry: &Registry, p: &Preset, out: Option<&Path>, overwrite: bool) -> bool {
    let target = match out {
        Some(dir) => dir.join(format!("{}.png", p.file.file_stem().map(|s| s.to_string_lossy()).unwrap_or_default())),
        None => {
            // A library's preset names its own thumbnail: it may not point the writer elsewhere.
            let declared = p.meta.thumbnail.as_deref().map(Path::new);
            if declared.is_some_and(|t| t.is_absolute() || t.components().any(|c| c == std::path::Component::ParentDir)) {
                errln!(
                    "error: preset '{}' ({}): thumbnail \"{}\" leaves the preset's folder; name a file inside it, or use --out",
                    p.name,
                    p.file.display(),
                    p.meta.thumbnail.as_deref().unwrap_or_default()
                );
                return false;
            }
            thumbnail_path(&p.file, p.meta.thumbnail.as_deref())
        }
    };
    if target.exists() && !overwrite {
        outln!("{}: kept {} (it exists; --overwrite replaces it)", p.name, target.display());
        return true;
    }
    let started = std::time::Instant::now();
    let thumb = match thumbnail(registry, &p.file) {
        Ok(t) => t,
        Err(e) => {
            errln!("error: preset '{}' ({}): {}", p.name, p.file.display(), e.trim_start_matches("error: "));
            return false;
        }
    };
    let written = target
        .parent()
        .map_or(Ok(()), std::fs::create_dir_all)
        .map_err(|e| e.to_string())
        .and_then(|()| {
            pyrograph_frontend::imaging::io::files::encode_image(
                &thumb.image,
                pyrograph_frontend::imaging::io::files::OutputFormat::Png { sixteen_bit: false },
            )
            .map_err(|e| e.to_string())
        })
        .and_then(|bytes| pyrograph_frontend::core::document::write_atomic(&target, &bytes, true).map_err(|e| e.to_string()));
    if let Err(e) = written {
        errln!("error: preset '{}': writing {}: {e}", p.name, target.display());
        return false;
    }
    let frame = thumb.frame.map(|(f, n)| format!("frame {f} of {n}")).unwrap_or_else(|| "image".into());
    outln!("{}: {} ({frame}, {:.1} s)", p.name, target.display(), started.elapsed().as_secs_f64());
    true
}

/// A preset's exposed ports, read by including it the way a graph would.
fn preset_entry(registry: &Registry, file: &Path) -> Result<serde_json::Value, String> {
    let desc = pyrograph_frontend::core::graph::preset_desc(file, registry).map_err(|d| d.to_string())?;
    let iface = GraphDoc::load(file).ok().and_then(|d| d.interface).unwrap_or_default();
    let port = |p: &pyrograph_frontend::core::PortDesc| json!({"name": p.name, "type": p.ty.to_string(), "default": p.default.as_ref().map(|v| v.summary())});
    let inputs: Vec<_> = desc.inputs.iter().filter(|p| iface.inputs.contains_key(&p.name)).map(port).collect();
    let params: Vec<_> = desc.inputs.iter().filter(|p| iface.params.contains_key(&p.name)).map(port).collect();
    let outputs: Vec<_> = desc.outputs.iter().map(port).collect();
    Ok(
        json!({"file": file.display().to_string(), "description": desc.summary(), "inputs": inputs, "params": params, "outputs": outputs}),
    )
}

/// `pyrograph preset NAME`: the preset found by name on the search path (or a preset file),
/// its parameters set by `--set PARAM=VALUE`, its inputs fed by `--input NAME=SOURCE`, its picture
/// written as a PNG sequence (or one PNG) under `--out` (default `pyrograph-out`).
pub fn render_preset(
    registry: &Registry,
    name: &str,
    graph: Option<&Path>,
    inputs: &[String],
    o: &RenderOpts,
) -> Result<(), Failure> {
    if !o.wedges.wedge.is_empty() || !o.wedges.wedge_zip.is_empty() || o.sheet || o.wedges.wedge_index.is_some() {
        return Err(Failure(
            "error: preset renders one variant; for wedges, include the preset in a graph and render that".into(),
        ));
    }
    let as_file = Path::new(name);
    let (file, stem) = if as_file.extension().is_some_and(|e| e == "ron") && as_file.is_file() {
        (as_file.to_path_buf(), as_file.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default())
    } else {
        let lib = library(None, graph)?;
        // By its name, else by its file's stem (`candle-row` for "candle row").
        let by_stem = || lib.presets.iter().find(|p| p.file.file_stem().is_some_and(|s| s == name));
        let p = lib.find(name).or_else(by_stem).ok_or_else(|| {
            let known: Vec<&str> = lib.presets.iter().map(|p| p.name.as_str()).collect();
            Failure(format!("error: no preset named '{name}' on the search path (found: {})", known.join(", ")))
        })?;
        (p.file.clone(), p.file.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default())
    };
    let mut sources = BTreeMap::new();
    for i in inputs {
        let (k, v) = i.split_once('=').ok_or_else(|| Failure(format!("error: --input {i}: expected NAME=FILE")))?;
        sources.insert(k.to_string(), PathBuf::from(v));
    }
    let err = |m: String| Failure(format!("error: preset {}: {m}", file.display()));
    let mut wrapped = wrap(registry, &file, &[], &sources).map_err(err)?;
    let names_the_file =
        |l: &str| l == INCLUDE_PATH || l.strip_prefix(PRESET_NODE).and_then(|r| r.strip_prefix('.')) == Some(INCLUDE_PATH);
    if o.set.iter().any(|s| s.split_once('=').is_some_and(|(l, _)| names_the_file(l))) {
        return Err(err("`path` names the preset file itself; set the preset's exposed parameters".into()));
    }
    // `--set flames=200` sets the preset's own parameter; `--set node.param=v` any wrapper node.
    let sets: Vec<String> = o
        .set
        .iter()
        .map(|s| if s.split_once('=').is_some_and(|(l, _)| !l.contains('.')) { format!("{PRESET_NODE}.{s}") } else { s.clone() })
        .collect();
    apply_sets(&mut wrapped.doc, &sets)?;
    let picture = format!("{PRESET_NODE}.{}", wrapped.picture);
    let stem = stem.replace(' ', "-");
    let writer = if wrapped.is_clip {
        NodeDoc::new("imaging.write_sequence").param("pattern", ParamValue::String(format!("{stem}/{stem}_####.png")))
    } else {
        NodeDoc::new("imaging.write_image").param("path", ParamValue::String(format!("{stem}.png")))
    };
    let port = if wrapped.is_clip { "clip" } else { "image" };
    wrapped.doc.add_node("write", writer.param("overwrite", ParamValue::Bool(o.overwrite)));
    wrapped.doc.connect(&picture, &format!("write.{port}"));
    let out = o.out.clone().unwrap_or_else(|| PathBuf::from(pyrograph::demo::DEMO_OUT));
    let options =
        BuildOptions { output_dir: Some(out.clone()), allow_outside_out: o.allow_outside_out, ..BuildOptions::default() };
    let cwd = std::env::current_dir().unwrap_or_default();
    let g = Graph::build(&wrapped.doc, registry, &cwd, &options)?;
    cook_graph(&g, &file, o, &["write".to_string()])?;
    if !o.json {
        let what = if wrapped.is_clip { format!("{stem}/{stem}_####.png") } else { format!("{stem}.png") };
        outln!("frames in {}", out.join(what).display());
    }
    Ok(())
}
