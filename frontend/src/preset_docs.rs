//! The preset catalogue (`docs/presets.md`, issue 30): every shipped preset with its thumbnail,
//! description, tags, exposed parameters and outputs and a one-line command that renders it.
//! Generated from `graphs/presets/`; a test keeps the file current, like `docs/nodes.md`.

use std::fmt::Write;
use std::path::Path;

use pyrograph_core::document::{GraphDoc, ParamValue, split_endpoint};
use pyrograph_core::graph::preset_desc;
use pyrograph_core::{PortType, Registry};

use crate::preset_cook::thumbnail_path;
use crate::presets::Library;
use crate::reference::{constraint_text, default_text, one_line};

/// `path` relative to `root`, with `/` separators (for links from `docs/`).
fn rel(path: &Path, root: &Path) -> String {
    let p = path.strip_prefix(root).unwrap_or(path);
    p.components().map(|c| c.as_os_str().to_string_lossy()).collect::<Vec<_>>().join("/")
}

/// The catalogue of `lib` (pyrograph's own presets) as Markdown, links relative to `docs/` under
/// the workspace `root`. A preset that does not load is an error naming it.
pub fn markdown(registry: &Registry, lib: &Library, root: &Path) -> Result<String, String> {
    let mut out = String::from(
        "# Preset catalogue\n\nGenerated from `graphs/presets/` by `cargo test --test preset_catalogue` \
         (`REGENERATE=1` rewrites it and the thumbnails); do not edit by hand.\n\n\
         Render a preset by name with `pyrograph preset NAME`; list presets with `pyrograph presets` \
         (`--tag`, `--search`, `--json`); include one in a graph as \
         `(type: \"graph.include\", params: {\"path\": \"presets/FILE.ron\", ...})`. \
         Thumbnails are the middle frame (or the frame the preset names) at 256×144 \
         (`pyrograph presets --thumbnails`).\n\n\
         ![Every preset's thumbnail](images/preset-catalogue.png)\n\n| preset | tags | needs |\n|---|---|---|\n",
    );
    for p in &lib.presets {
        let anchor = p.name.to_lowercase().replace(' ', "-");
        let needs = if p.meta.requires.is_empty() { "—".to_string() } else { p.meta.requires.join(", ") };
        let _ = writeln!(out, "| [{}](#{anchor}) | {} | {needs} |", p.name, p.meta.tags.join(", "));
    }
    for p in &lib.presets {
        let desc = preset_desc(&p.file, registry).map_err(|d| format!("{}: {d}", p.file.display()))?;
        let doc = GraphDoc::load(&p.file).map_err(|d| d.to_string())?;
        let iface = doc.interface.clone().unwrap_or_default();
        // Paths as the file writes them (`${PYROGRAPH_FOOTAGE}/…`, relative to the preset), not
        // as resolved on this machine.
        let literal = |name: &str| {
            let (node, param) = split_endpoint(iface.params.get(name)?)?;
            match doc.node(node)?.params.get(param)? {
                ParamValue::String(s) => Some(format!("`{s}`")),
                _ => None,
            }
        };
        let thumb = thumbnail_path(&p.file, p.meta.thumbnail.as_deref());
        let _ = writeln!(out, "\n## {}\n", p.name);
        if thumb.exists() {
            // `docs/images/preset-thumbs` links to `graphs/presets/thumbs`, so the book (which
            // serves only what is under docs/) shows the shipped thumbnails without a copy.
            let path = rel(&thumb, root);
            let shown =
                path.strip_prefix("graphs/presets/thumbs/").map_or(format!("../{path}"), |f| format!("images/preset-thumbs/{f}"));
            let _ = writeln!(out, "![{}]({shown})\n", p.name);
        }
        let _ = writeln!(out, "{}\n", p.description.trim());
        let m = &p.meta;
        let _ = writeln!(
            out,
            "*File:* `{}` · *tags:* {} · *revision:* {} · *author:* {} · *licence:* {}\n",
            rel(&p.file, root),
            m.tags.join(", "),
            m.revision,
            m.author,
            m.licence
        );
        let ports = |name: &String| desc.inputs.iter().find(|d| &d.name == name);
        let rows: Vec<_> = iface.inputs.keys().chain(iface.params.keys()).filter_map(ports).collect();
        if !rows.is_empty() {
            let _ = writeln!(out, "| input / parameter | type | default | range / options | doc |\n|---|---|---|---|---|");
            for d in rows {
                let default = match (m.requires.contains(&d.name), &d.ty) {
                    (true, _) => "required".into(),
                    (false, PortType::Path) => literal(&d.name).unwrap_or_else(|| default_text(d)),
                    _ => default_text(d),
                };
                let _ = writeln!(out, "| `{}` | {} | {default} | {} | {} |", d.name, d.ty, constraint_text(d), one_line(&d.doc));
            }
            out.push('\n');
        }
        let _ = writeln!(out, "| output | type | doc |\n|---|---|---|");
        for d in &desc.outputs {
            let _ = writeln!(out, "| `{}` | {} | {} |", d.name, d.ty, one_line(&d.doc));
        }
        let mut cmd = format!("pyrograph preset \"{}\"", p.name);
        if iface.params.contains_key("width") && iface.params.contains_key("height") {
            cmd.push_str(" --set width=1280 --set height=720");
        }
        for name in &m.requires {
            let sample = match m.samples.get(name) {
                Some(s) if s.contains("${") => format!("'{s}'"),
                Some(s) => rel(&p.file.parent().unwrap_or(root).join(s), root),
                None => "FILE".into(),
            };
            let _ = write!(cmd, " --input {name}={sample}");
        }
        let _ = writeln!(out, "\n```sh\n{cmd} --out renders\n```");
    }
    Ok(out)
}
