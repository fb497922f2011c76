//! OpenEXR files with several layers (passes): the layers a file holds, and decoding one of them.
//!
//! A layer is what compositors call one: the channels sharing a name before their last dot
//! (`diffuse.R`, `diffuse.G`, `diffuse.B` are layer `diffuse`), in a single-part file or in any
//! part of a multi-part file, where a part's channels without a dot take the part's name as
//! Nuke reads them. Channels without a dot in a single-part file form the main layer, named ""
//! here and `rgba` in messages.

use std::path::Path;

use exr::meta::MetaData;
use exr::prelude::{AnyChannel, AnyChannels, Encoding, FlatSamples, Layer, LayerAttributes, WritableImage as _, f16};
use pyrograph_core::{Channels, Image};

use crate::media::IoError;

/// The layer and base name of a channel: its name before and after the last dot; without a dot,
/// the layer is `part`, the part's name in a multi-part file (None in a single-part file, whose
/// name attribute is not a layer).
fn layer_of(part: Option<&str>, channel: &str) -> (String, String) {
    match channel.rsplit_once('.') {
        Some((prefix, base)) => (prefix.to_string(), base.to_string()),
        None => (part.unwrap_or("").to_string(), channel.to_string()),
    }
}

/// The name a part gives its bare channels: its name attribute, in a file of several parts.
fn part_name(meta_parts: usize, name: Option<&exr::meta::attribute::Text>) -> Option<String> {
    name.filter(|_| meta_parts > 1).map(ToString::to_string)
}

/// The layers of a file's parts, in order, each once: (part index, layer name).
fn layers(meta: &MetaData) -> Vec<(usize, String)> {
    let mut out: Vec<(usize, String)> = Vec::new();
    for (i, header) in meta.headers.iter().enumerate() {
        let part = part_name(meta.headers.len(), header.own_attributes.layer_name.as_ref());
        for c in &header.channels.list {
            let (label, _) = layer_of(part.as_deref(), &c.name.to_string());
            if !out.iter().any(|(_, l)| *l == label) {
                out.push((i, label));
            }
        }
    }
    out
}

/// The part holding `layer` and the layer's name there. "" (or `rgba`, as compositors call it)
/// is the main layer: the channels without a dot; a file without them gives its first part's layer
/// when it has several parts (as readers of multi-part files do), or its only layer.
fn find_layer(meta: &MetaData, layer: &str, path: &Path) -> Result<(usize, String), IoError> {
    let all = layers(meta);
    let layer = if layer.eq_ignore_ascii_case("rgba") { "" } else { layer };
    let pick = match layer {
        "" => all
            .iter()
            .find(|(_, l)| l.is_empty())
            .or_else(|| (meta.headers.len() > 1 || all.len() == 1).then(|| all.first()).flatten()),
        want => all.iter().find(|(_, l)| l == want).or_else(|| all.iter().find(|(_, l)| l.eq_ignore_ascii_case(want))),
    };
    pick.cloned().ok_or_else(|| {
        let names: Vec<&str> = all.iter().map(|(_, l)| if l.is_empty() { "rgba" } else { l.as_str() }).collect();
        let asked = if layer.is_empty() { "no main (unnamed) layer".to_string() } else { format!("no layer '{layer}'") };
        IoError::Message(format!(
            "{}: the file has {asked}; its layers are {}; set layer to one of them",
            path.display(),
            names.join(", ")
        ))
    })
}

/// Width and height of every part of the file: each is decoded when one layer is read, so each is
/// checked against the pixel budget.
pub fn exr_part_sizes(path: &Path) -> Result<Vec<(u32, u32)>, IoError> {
    let meta = read_meta(path)?;
    meta.headers.iter().map(|h| Ok((to_u32(h.layer_size.0, path)?, to_u32(h.layer_size.1, path)?))).collect()
}

fn read_meta(path: &Path) -> Result<MetaData, IoError> {
    MetaData::read_from_file(path, false).map_err(|e| IoError::Message(format!("{}: {e}", path.display())))
}

/// Width and height of `layer`'s part, from the header alone.
pub fn exr_dimensions(path: &Path, layer: &str) -> Result<(u32, u32), IoError> {
    let meta = read_meta(path)?;
    let (part, _) = find_layer(&meta, layer, path)?;
    let size = meta.headers[part].layer_size;
    Ok((to_u32(size.0, path)?, to_u32(size.1, path)?))
}

fn to_u32(v: usize, path: &Path) -> Result<u32, IoError> {
    u32::try_from(v).map_err(|_| IoError::Message(format!("{}: image too large ({v} pixels wide or high)", path.display())))
}

/// Decodes `layer` of an OpenEXR file (its header checked against the budget by the caller): `Y`
/// only → gray, else R, G, B (and A, default 1).
pub fn decode_exr_layer(path: &Path, layer: &str) -> Result<Image, IoError> {
    let named = |e: &dyn std::fmt::Display| IoError::Message(format!("{}: {e}", path.display()));
    let meta = read_meta(path)?;
    let (part, label) = find_layer(&meta, layer, path)?;
    let file = exr::prelude::read_all_flat_layers_from_file(path).map_err(|e| named(&e))?;
    let data = file.layer_data.get(part).ok_or_else(|| named(&"the layer's part is missing"))?;
    let (w, h) = (to_u32(data.size.0, path)?, to_u32(data.size.1, path)?);
    let pixels = w as usize * h as usize;
    let bare = part_name(file.layer_data.len(), data.attributes.layer_name.as_ref());
    // Subsampled channels (chroma) hold fewer samples than pixels; they are treated as absent.
    let channel = |base: &str| -> Option<Vec<f32>> {
        let c = data
            .channel_data
            .list
            .iter()
            .find(|c| layer_of(bare.as_deref(), &c.name.to_string()) == (label.clone(), base.to_string()))?;
        let samples: Vec<f32> = c.sample_data.values_as_f32().collect();
        (samples.len() == pixels).then_some(samples)
    };
    let image = match (channel("R"), channel("G"), channel("B"), channel("Y")) {
        (Some(r), Some(g), Some(b), _) => {
            let a = channel("A").unwrap_or_else(|| vec![1.0; pixels]);
            let data = (0..pixels).flat_map(|i| [r[i], g[i], b[i], a[i]]).collect();
            Image::from_vec(w, h, Channels::Rgba, data)
        }
        (_, _, _, Some(y)) => Image::from_vec(w, h, Channels::Gray, y),
        _ => {
            let shown = if label.is_empty() { "rgba".to_string() } else { format!("'{label}'") };
            return Err(named(&format!("layer {shown} has neither R, G, B nor Y channels")));
        }
    };
    image.ok_or_else(|| named(&"channel sizes do not match the image size"))
}

/// The longest channel name written (`layer.R`): OpenEXR's long-name limit is 255 bytes.
pub const MAX_NAME: usize = 250;

/// What a channel name may hold, said when one does not.
pub const NAME_RULE: &str = "an OpenEXR channel name holds at most 250 bytes of Latin-1 characters (letters, digits, \
                             punctuation; no other scripts)";

/// One layer to write: its name ("" = the main layer, channels R, G, B, A or Y), its pixels and
/// whether its samples are 16-bit halves (else 32-bit floats).
pub struct LayerOut<'a> {
    /// Layer name: channels are written as `name.R`… (bare `R`… for "").
    pub name: &'a str,
    /// The layer's pixels: RGBA gives R, G, B, A; gray gives Y.
    pub image: &'a Image,
    /// Half (16-bit) samples instead of float (32-bit).
    pub half: bool,
}

/// Encodes `layers` (all one size) as one single-part OpenEXR file whose channels are named
/// `layer.channel`, as Nuke, Fusion and Resolve write and read passes. Chunks are compressed one
/// after another so one frame written twice gives the same bytes (see `encode_exr`).
pub fn encode_exr_layers(layers: &[LayerOut<'_>]) -> Result<Vec<u8>, IoError> {
    let first = layers.first().ok_or_else(|| IoError::Message("no layer to write".into()))?;
    let size = first.image.size();
    let mut channels: Vec<AnyChannel<FlatSamples>> = Vec::new();
    for layer in layers {
        if layer.image.size() != size {
            let (w, h) = layer.image.size();
            return Err(IoError::Message(format!(
                "layer '{}' is {w}×{h} but the main layer is {}×{}; every layer of a file has one size",
                layer.name, size.0, size.1
            )));
        }
        let names: &[&str] = match layer.image.channels() {
            Channels::Rgba => &["R", "G", "B", "A"],
            Channels::Gray => &["Y"],
        };
        let n = names.len();
        for (c, base) in names.iter().enumerate() {
            let values = layer.image.data().iter().skip(c).step_by(n).copied();
            let samples = if layer.half {
                FlatSamples::F16(values.map(f16::from_f32).collect())
            } else {
                FlatSamples::F32(values.collect())
            };
            let name = if layer.name.is_empty() { (*base).to_string() } else { format!("{}.{base}", layer.name) };
            let text = exr::prelude::Text::new_or_none(name.as_str())
                .filter(|_| name.len() <= MAX_NAME)
                .ok_or_else(|| IoError::Message(format!("layer '{}': {}", layer.name, NAME_RULE)))?;
            channels.push(AnyChannel::new(text, samples));
        }
    }
    let (w, h) = (size.0 as usize, size.1 as usize);
    let layer = Layer::new((w, h), LayerAttributes::default(), Encoding::FAST_LOSSLESS, AnyChannels::sort(channels.into()));
    let mut bytes = Vec::new();
    exr::image::Image::from_layer(layer)
        .write()
        .non_parallel()
        .to_buffered(std::io::Cursor::new(&mut bytes))
        .map_err(|e| IoError::Message(format!("encoding EXR: {e}")))?;
    Ok(bytes)
}

#[cfg(test)]
mod tests {
    use exr::prelude::{AnyChannel, AnyChannels, Encoding, FlatSamples, Layer, LayerAttributes, SmallVec, WritableImage as _};

    use super::*;

    const W: usize = 6;
    const H: usize = 4;

    /// A channel whose sample at pixel i is `seed + i / 100`.
    fn channel(name: &str, seed: f32) -> AnyChannel<FlatSamples> {
        AnyChannel::new(name, FlatSamples::F32((0..W * H).map(|i| seed + i as f32 / 100.0).collect()))
    }

    fn layer(name: &str, channels: Vec<AnyChannel<FlatSamples>>) -> Layer<AnyChannels<FlatSamples>> {
        Layer::new(
            (W, H),
            LayerAttributes::named(name),
            Encoding::FAST_LOSSLESS,
            AnyChannels::sort(channels.into_iter().collect()),
        )
    }

    /// One part (named `render`, a name that is not a layer) holding the main RGBA, a `diffuse`
    /// RGB and a `depth.Y` layer, as renderers write legacy multi-layer files.
    fn single_part(path: &Path) {
        let channels = vec![
            channel("R", 1.0),
            channel("G", 2.0),
            channel("B", 3.0),
            channel("A", 0.5),
            channel("diffuse.R", 10.0),
            channel("diffuse.G", 20.0),
            channel("diffuse.B", 30.0),
            channel("depth.Y", 7.0),
        ];
        exr::image::Image::from_layer(layer("render", channels)).write().to_file(path).unwrap();
    }

    /// Two parts, `beauty` and `spec`, each with bare R, G, B channels, as Nuke writes multi-part.
    fn multi_part(path: &Path) {
        let beauty = layer("beauty", vec![channel("R", 1.0), channel("G", 2.0), channel("B", 3.0)]);
        let spec = layer("spec", vec![channel("R", 4.0), channel("G", 5.0), channel("B", 6.0)]);
        let attributes = exr::prelude::ImageAttributes::new(exr::prelude::IntegerBounds::from_dimensions((W, H)));
        exr::image::Image::from_layers(attributes, SmallVec::from_vec(vec![beauty, spec])).write().to_file(path).unwrap();
    }

    fn px(img: &Image, i: usize) -> Vec<f32> {
        let n = img.channels().count();
        img.data()[i * n..(i + 1) * n].to_vec()
    }

    #[test]
    fn each_layer_of_a_single_part_file_reads_apart() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("passes.exr");
        single_part(&path);
        let main = decode_exr_layer(&path, "").unwrap();
        assert_eq!(px(&main, 5), vec![1.05, 2.05, 3.05, 0.55]);
        assert_eq!(decode_exr_layer(&path, "RGBA").unwrap().data(), main.data(), "rgba names the main layer");
        let diffuse = decode_exr_layer(&path, "diffuse").unwrap();
        assert_eq!(px(&diffuse, 23), vec![10.23, 20.23, 30.23, 1.0], "no alpha in the layer: opaque");
        let depth = decode_exr_layer(&path, "Depth").unwrap();
        assert_eq!((depth.channels(), px(&depth, 1)), (Channels::Gray, vec![7.01]), "names match case-blind");
        assert_eq!(exr_dimensions(&path, "diffuse").unwrap(), (W as u32, H as u32));
        let e = decode_exr_layer(&path, "specular").unwrap_err().to_string();
        assert!(e.contains("passes.exr: the file has no layer 'specular'; its layers are rgba, depth, diffuse"), "{e}");
    }

    #[test]
    fn the_parts_of_a_multi_part_file_are_its_layers() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("parts.exr");
        multi_part(&path);
        assert_eq!(px(&decode_exr_layer(&path, "spec").unwrap(), 2), vec![4.02, 5.02, 6.02, 1.0]);
        assert_eq!(px(&decode_exr_layer(&path, "beauty").unwrap(), 2), vec![1.02, 2.02, 3.02, 1.0]);
        // No main layer: the first part, as readers of multi-part files take it.
        assert_eq!(px(&decode_exr_layer(&path, "").unwrap(), 2), vec![1.02, 2.02, 3.02, 1.0]);
        let e = decode_exr_layer(&path, "diffuse").unwrap_err().to_string();
        assert!(e.contains("no layer 'diffuse'; its layers are beauty, spec; set layer"), "{e}");
    }

    #[test]
    fn written_layers_read_back_by_name_in_half_and_float() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("out.exr");
        let px = |i: usize| i as f32 / 10.0 + 0.123_456_7;
        let rgba = Image::from_vec(3, 2, Channels::Rgba, (0..24).map(px).collect()).unwrap();
        let gray = Image::from_vec(3, 2, Channels::Gray, (0..6).map(|i| px(i) * 3.0).collect()).unwrap();
        let layers = [
            LayerOut { name: "", image: &rgba, half: true },
            LayerOut { name: "emission", image: &rgba, half: false },
            LayerOut { name: "depth", image: &gray, half: false },
        ];
        let bytes = encode_exr_layers(&layers).unwrap();
        assert_eq!(bytes, encode_exr_layers(&layers).unwrap(), "one frame, one file, byte for byte");
        std::fs::write(&path, bytes).unwrap();
        let main = decode_exr_layer(&path, "").unwrap();
        let emission = decode_exr_layer(&path, "emission").unwrap();
        assert_eq!(emission.data(), rgba.data(), "float layers are exact");
        let half_err = main.data().iter().zip(rgba.data()).map(|(a, b)| (a - b).abs()).fold(0.0, f32::max);
        assert!(half_err > 0.0 && half_err < 2e-3, "half samples round: {half_err}");
        assert_eq!(decode_exr_layer(&path, "depth").unwrap().data(), gray.data());
        let small = Image::from_vec(1, 1, Channels::Gray, vec![0.0]).unwrap();
        let e = encode_exr_layers(&[
            LayerOut { name: "", image: &rgba, half: true },
            LayerOut { name: "mask", image: &small, half: true },
        ]);
        assert!(e.unwrap_err().to_string().contains("layer 'mask' is 1×1 but the main layer is 3×2"));
    }

    #[test]
    fn a_sequence_reads_the_layer_asked_for() {
        use crate::io::{LoadSequence, SequenceOptions, open_sequence};
        let dir = tempfile::tempdir().unwrap();
        for n in 1..=3 {
            single_part(&dir.path().join(format!("shot_{n:04}.exr")));
        }
        let ctx = pyrograph_core::CookCtx::new();
        let open = |layer: &str| {
            let options = SequenceOptions { layer: layer.into(), ..SequenceOptions::default() };
            open_sequence(&dir.path().join("shot_####.exr"), &options, &ctx, LoadSequence::node_error)
        };
        let diffuse = open("diffuse").unwrap();
        let main = open("").unwrap();
        assert_eq!(diffuse.len(), 3);
        assert_ne!(diffuse.fingerprint(), main.fingerprint(), "another layer is another clip for the caches");
        assert_eq!(px(&diffuse.image(2, &ctx).unwrap(), 0), vec![10.0, 20.0, 30.0, 1.0]);
        let e = LoadSequence::node_error(open("nope").unwrap_err()).to_string();
        assert!(e.contains("shot_0001.exr: the file has no layer 'nope'"), "{e}");
        std::fs::write(dir.path().join("a.png"), b"").unwrap();
        let png = crate::io::files::image_dimensions(&dir.path().join("a.png"), "diffuse").unwrap_err().to_string();
        assert!(png.contains("only OpenEXR files have layers"), "{png}");
    }

    #[test]
    fn channel_names_give_layers_under_their_part() {
        assert_eq!(layer_of(None, "R"), (String::new(), "R".into()));
        assert_eq!(layer_of(None, "diffuse.R"), ("diffuse".into(), "R".into()));
        assert_eq!(layer_of(None, "light.key.B"), ("light.key".into(), "B".into()));
        assert_eq!(layer_of(Some("beauty"), "R"), ("beauty".into(), "R".into()));
        assert_eq!(layer_of(Some("diffuse"), "diffuse.G"), ("diffuse".into(), "G".into()));
        assert_eq!(layer_of(Some("aov"), "spec.A"), ("spec".into(), "A".into()));
    }
}
