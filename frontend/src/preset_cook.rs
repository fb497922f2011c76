//! Cooking a preset on its own (issue 30): `pyrograph preset NAME` renders one into frames, and
//! `pyrograph presets --thumbnails` cooks each at thumbnail size. Both wrap the preset in a small
//! graph, as an artist would: a `graph.include` node with the parameters set, a source for every
//! input it needs (given, else the preset's own `samples`), and for a render a writer on its
//! picture output.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use pyrograph_core::builtin::{INCLUDE_PATH, INCLUDE_TYPE};
use pyrograph_core::document::{GraphDoc, NodeDoc, ParamValue};
use pyrograph_core::graph::{BuildOptions, Graph, expand_vars, preset_desc};
use pyrograph_core::{Channels, CookCtx, Evaluator, Image, NodeDesc, PortType, Registry, Value};
use pyrograph_nodes_imaging::resize::{ResizeFilter, resize};

/// Thumbnail size: 16:9, small enough that the whole catalogue cooks in a test.
pub const THUMB_SIZE: (u32, u32) = (256, 144);

/// What thumbnails are laid over where a preset's frame is transparent (a dark studio gray).
pub const THUMB_BACKGROUND: [f32; 4] = [0.04, 0.04, 0.045, 1.0];

/// The id of the preset's node in the wrapper graph.
pub const PRESET_NODE: &str = "preset";

/// A preset wrapped for cooking.
pub struct Wrapped {
    /// The wrapper document.
    pub doc: GraphDoc,
    /// The preset's picture output (a clip of images, or an image).
    pub picture: String,
    /// Whether the picture is a clip.
    pub is_clip: bool,
}

/// The output a preset's picture comes out of: `clip`, `image` or `sheet` when it has one of
/// those, else its first image or clip of images.
pub fn picture_output(desc: &NodeDesc) -> Option<(String, bool)> {
    let is_picture = |t: &PortType| match t {
        PortType::Image => Some(false),
        PortType::Clip(inner) if **inner == PortType::Image => Some(true),
        _ => None,
    };
    let pictures: Vec<(String, bool)> =
        desc.outputs.iter().filter_map(|p| is_picture(&p.ty).map(|clip| (p.name.clone(), clip))).collect();
    ["clip", "image", "sheet"]
        .iter()
        .find_map(|want| pictures.iter().find(|(n, _)| n == want).cloned())
        .or_else(|| pictures.first().cloned())
}

/// Wraps the preset `file`: its include node gets `params`, each input it needs a source from
/// `inputs` (input name → a graph file whose picture output is fed in, or an image, video or
/// folder of frames; relative to the current folder) or else from the preset's `samples`
/// (relative to the preset). Sources of inputs it does not have are an error.
pub fn wrap(
    registry: &Registry,
    file: &Path,
    params: &[(String, ParamValue)],
    inputs: &BTreeMap<String, PathBuf>,
) -> Result<Wrapped, String> {
    let file = std::fs::canonicalize(file).map_err(|e| format!("cannot open preset {}: {e}", file.display()))?;
    let doc = GraphDoc::load(&file).map_err(|d| d.to_string())?;
    let desc = preset_desc(&file, registry).map_err(|d| d.to_string())?;
    let iface = doc.interface.clone().unwrap_or_default();
    let meta = doc.preset.clone().unwrap_or_default();
    let (picture, is_clip) = match &meta.preview {
        Some(name) => {
            let port = desc.outputs.iter().find(|p| &p.name == name);
            let clip = port.map(|p| matches!(&p.ty, PortType::Clip(inner) if **inner == PortType::Image));
            match (port.map(|p| &p.ty), clip) {
                (Some(PortType::Image), _) => (name.clone(), false),
                (_, Some(true)) => (name.clone(), true),
                _ => return Err(format!("{}: preview '{name}' is not an image or clip output", file.display())),
            }
        }
        None => picture_output(&desc).ok_or_else(|| format!("{}: the preset has no image or clip output", file.display()))?,
    };
    let mut node = NodeDoc::new(INCLUDE_TYPE).param(INCLUDE_PATH, ParamValue::String(file.display().to_string()));
    for (name, value) in params {
        if !iface.params.contains_key(name) {
            let known: Vec<&str> = iface.params.keys().map(String::as_str).collect();
            return Err(format!("the preset has no parameter '{name}' (it exposes: {})", known.join(", ")));
        }
        node = node.param(name, value.clone());
    }
    let mut wrapper = GraphDoc::new();
    wrapper.add_node(PRESET_NODE, node);
    for name in inputs.keys() {
        if !iface.inputs.contains_key(name) {
            let known: Vec<&str> = iface.inputs.keys().map(String::as_str).collect();
            return Err(format!("the preset has no input '{name}' (its inputs: {})", known.join(", ")));
        }
    }
    let dir = file.parent().map(Path::to_path_buf).unwrap_or_default();
    for name in iface.inputs.keys() {
        let source = match (inputs.get(name), meta.samples.get(name)) {
            (Some(given), _) => PathBuf::from(expand_vars(&given.to_string_lossy()).map_err(|m| format!("input '{name}': {m}"))?),
            (None, Some(sample)) => dir.join(expand_vars(sample).map_err(|m| format!("sample for input '{name}': {m}"))?),
            (None, None) if meta.requires.contains(name) => {
                return Err(format!("the preset needs its input '{name}' connected (give it with --input {name}=FILE)"));
            }
            (None, None) => continue,
        };
        let ty = desc.inputs.iter().find(|p| &p.name == name).map(|p| p.ty.clone()).unwrap_or(PortType::Image);
        let id = format!("input_{name}");
        let from = source_node(registry, &mut wrapper, &id, &source, &ty)?;
        wrapper.connect(&from, &format!("{PRESET_NODE}.{name}"));
    }
    Ok(Wrapped { doc: wrapper, picture, is_clip })
}

/// Adds a node `id` reading `source` to `doc`; returns its output endpoint.
fn source_node(registry: &Registry, doc: &mut GraphDoc, id: &str, source: &Path, ty: &PortType) -> Result<String, String> {
    let text = ParamValue::String(source.display().to_string());
    if source.extension().is_some_and(|e| e == "ron") {
        let desc = preset_desc(source, registry).map_err(|d| d.to_string())?;
        let (out, _) =
            picture_output(&desc).ok_or_else(|| format!("{}: the graph has no image or clip output", source.display()))?;
        doc.add_node(id, NodeDoc::new(INCLUDE_TYPE).param(INCLUDE_PATH, text));
        return Ok(format!("{id}.{out}"));
    }
    // A frame pattern (`shot/frame_####.png`) names files that exist, not itself.
    let pattern = source.to_string_lossy().contains(['#', '%']);
    if !pattern && !source.exists() {
        return Err(format!("input source {} does not exist", source.display()));
    }
    // A single picture feeds an image input as it is; anything else is read as a clip, and a
    // clip on an image input cooks the preset once per frame.
    let single = source.is_file() && pyrograph_nodes_imaging::io::IMAGE_EXTENSIONS.iter().any(|x| has_ext(source, x));
    if single && *ty == PortType::Image {
        doc.add_node(id, NodeDoc::new("imaging.load_image").param("path", text));
        Ok(format!("{id}.image"))
    } else {
        doc.add_node(id, NodeDoc::new("imaging.load_sequence").param("path", text));
        Ok(format!("{id}.clip"))
    }
}

fn has_ext(p: &Path, ext: &str) -> bool {
    p.extension().and_then(|e| e.to_str()).is_some_and(|e| e.eq_ignore_ascii_case(ext))
}

/// A preset's thumbnail.
pub struct Thumbnail {
    /// The picture, [`THUMB_SIZE`], opaque RGBA.
    pub image: Image,
    /// The frame shown and the clip's length (`None` for an image output).
    pub frame: Option<(usize, usize)>,
}

/// Cooks the preset `file` at thumbnail size: `width` and `height` set to [`THUMB_SIZE`] where it
/// exposes them, inputs from its `samples`, the middle frame of its picture (or its metadata's
/// `thumbnail_frame`), fitted into
/// [`THUMB_SIZE`] over [`THUMB_BACKGROUND`].
pub fn thumbnail(registry: &Registry, file: &Path) -> Result<Thumbnail, String> {
    let doc = GraphDoc::load(file).map_err(|d| d.to_string())?;
    let pick = doc.preset.as_ref().and_then(|m| m.thumbnail_frame);
    let exposed = doc.interface.map(|i| i.params).unwrap_or_default();
    let (w, h) = THUMB_SIZE;
    let params: Vec<(String, ParamValue)> = [("width", w), ("height", h)]
        .into_iter()
        .filter(|(n, _)| exposed.contains_key(*n))
        .map(|(n, v)| (n.to_string(), ParamValue::Int(v.into())))
        .collect();
    let wrapped = wrap(registry, file, &params, &BTreeMap::new())?;
    let graph = Graph::build(&wrapped.doc, registry, Path::new("."), &BuildOptions::default()).map_err(|d| d.to_string())?;
    let ctx = CookCtx::new();
    let endpoint = format!("{PRESET_NODE}.{}", wrapped.picture);
    let value = Evaluator::new().output(&graph, &endpoint, &ctx).map_err(|e| pyrograph_check_explain(&e))?;
    let (image, frame) = match value {
        Value::Image(img) => (img, None),
        Value::Clip(clip) if !clip.is_empty() => {
            let at = pick.map_or(clip.len() / 2, |f| (f as usize).min(clip.len() - 1));
            (clip.image(at, &ctx).map_err(|e| pyrograph_check_explain(&e))?, Some((at, clip.len())))
        }
        Value::Clip(_) => return Err(format!("{endpoint}: the clip has no frames")),
        other => return Err(format!("{endpoint}: expected a picture, got {}", other.summary())),
    };
    Ok(Thumbnail { image: fit(&image, w, h, THUMB_BACKGROUND)?, frame })
}

fn pyrograph_check_explain(e: &pyrograph_core::NodeError) -> String {
    crate::check::explain(PRESET_NODE, e)
}

/// `img` scaled to fit inside `width` × `height` (aspect kept, centred) and laid over `background`
/// by its alpha (straight), as an opaque RGBA image.
pub fn fit(img: &Image, width: u32, height: u32, background: [f32; 4]) -> Result<Image, String> {
    let rgba = img.to_rgba();
    let (iw, ih) = rgba.size();
    if iw == 0 || ih == 0 {
        return Err("the picture is empty".into());
    }
    let scale = (width as f64 / iw as f64).min(height as f64 / ih as f64);
    let (sw, sh) = (((iw as f64 * scale).round() as u32).clamp(1, width), ((ih as f64 * scale).round() as u32).clamp(1, height));
    let scaled = if (sw, sh) == (iw, ih) {
        rgba
    } else {
        resize(&rgba, sw, sh, ResizeFilter::Bilinear.filter_type()).map_err(|e| e.to_string())?
    };
    let (x0, y0) = ((width - sw) / 2, (height - sh) / 2);
    let mut data: Vec<f32> = std::iter::repeat_n(background, width as usize * height as usize).flatten().collect();
    for y in 0..sh {
        for x in 0..sw {
            let p = scaled.pixel(x, y);
            let a = p[3].clamp(0.0, 1.0);
            let at = (((y + y0) * width + x + x0) * 4) as usize;
            for c in 0..3 {
                data[at + c] = p[c] * a + background[c] * (1.0 - a);
            }
            data[at + 3] = 1.0;
        }
    }
    Image::from_vec(width, height, Channels::Rgba, data).ok_or_else(|| "thumbnail size overflow".into())
}

/// The thumbnail file of a preset: its metadata's `thumbnail` (relative to it), else
/// `thumbs/<file stem>.png` beside it.
pub fn thumbnail_path(file: &Path, declared: Option<&str>) -> PathBuf {
    let dir = file.parent().map(Path::to_path_buf).unwrap_or_default();
    match declared {
        Some(t) => dir.join(t),
        None => {
            let stem = file.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
            dir.join("thumbs").join(format!("{stem}.png"))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fit_letterboxes_and_lays_alpha_over_the_background() {
        // A 4×1 image, half transparent: scaled to 8 wide into 8×4, rows 1–2 hold it.
        let img = Image::from_vec(4, 1, Channels::Rgba, [1.0, 0.0, 0.0, 0.5].repeat(4)).unwrap();
        let out = fit(&img, 8, 4, [0.0, 0.0, 1.0, 1.0]).unwrap();
        assert_eq!(out.size(), (8, 4));
        assert_eq!(out.pixel(3, 0), &[0.0, 0.0, 1.0, 1.0], "letterbox keeps the background");
        let p = out.pixel(3, 2);
        assert!((p[0] - 0.5).abs() < 1e-6 && (p[2] - 0.5).abs() < 1e-6 && p[3] == 1.0, "{p:?}");
    }

    #[test]
    fn the_picture_output_prefers_clip_then_the_first_image() {
        use pyrograph_core::PortDesc;
        let mut d = NodeDesc::new("graph.include", "Graph", pyrograph_core::TimeDep::WholeClip, "");
        d.outputs.push(PortDesc::new("angle", PortType::Float, ""));
        d.outputs.push(PortDesc::new("gray", PortType::Clip(Box::new(PortType::Image)), ""));
        assert_eq!(picture_output(&d), Some(("gray".into(), true)));
        d.outputs.push(PortDesc::new("clip", PortType::Clip(Box::new(PortType::Image)), ""));
        assert_eq!(picture_output(&d), Some(("clip".into(), true)));
        d.outputs.clear();
        assert_eq!(picture_output(&d), None);
    }
}
