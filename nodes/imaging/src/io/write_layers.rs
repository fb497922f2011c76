//! `imaging.write_exr_layers`: passes as the named layers of one OpenEXR file per frame, the way a
//! compositor (Nuke, Fusion, Resolve) takes a render: colour, alpha, a mask, emission, motion,
//! each a layer, one file a frame.

use std::sync::Arc;

use pyrograph_core::{Clip, ClipOf, Cook, CookCtx, Image, NodeError, OutputPath, port};

use super::IoError;
use super::exr_layers::{LayerOut, encode_exr_layers};
use super::files::{ExrType, OutputFormat};
use super::sequence::{WriteOptions, write_frames};
use crate::color::{AlphaMode, premultiply};
use crate::media::no_images;

pyrograph_core::node! {
    /// Writes a clip and up to four more as the named layers of one OpenEXR file per frame: the multi-layer files compositors read as passes.
    ///
    /// `main` is the main layer (channels R, G, B, A; a gray clip writes Y). Each connected `layerN` is written as
    /// `nameN.R`, `nameN.G`, `nameN.B`, `nameN.A` (a gray clip as `nameN.Y`), in half or float samples as `typeN`
    /// says; every layer needs a name, its own, and the main clip's frame count and size. Writes the render's frame
    /// range (`--frames`) or every frame, in parallel, each file atomically, and refuses to replace existing files
    /// unless `overwrite` is on. RGBA layers are written premultiplied by default, as compositors expect of EXR.
    /// `imaging.load_sequence` reads any layer back by its name.
    #[node("imaging.write_exr_layers", "Input/Output", Sink)]
    pub struct WriteExrLayers {
        /// The main layer (R, G, B, A).
        main: ClipOf<Arc<Image>>,
        /// A second layer (optional).
        layer1: ClipOf<Arc<Image>> = no_images(),
        /// The second layer's name (emission, mask, motion…).
        name1: String = String::new(),
        /// Sample type of the second layer.
        type1: ExrType = ExrType::Half,
        /// A third layer (optional).
        layer2: ClipOf<Arc<Image>> = no_images(),
        /// The third layer's name.
        name2: String = String::new(),
        /// Sample type of the third layer.
        type2: ExrType = ExrType::Half,
        /// A fourth layer (optional).
        layer3: ClipOf<Arc<Image>> = no_images(),
        /// The fourth layer's name.
        name3: String = String::new(),
        /// Sample type of the fourth layer.
        type3: ExrType = ExrType::Half,
        /// A fifth layer (optional).
        layer4: ClipOf<Arc<Image>> = no_images(),
        /// The fifth layer's name.
        name4: String = String::new(),
        /// Sample type of the fifth layer.
        type4: ExrType = ExrType::Half,
        /// Output files: `####` or `%04d` is the frame number; .exr.
        pattern: OutputPath = "passes_####.exr".into(),
        /// Sample type of the main layer.
        exr_type: ExrType = ExrType::Half,
        /// File number of the clip's frame 0 (frame i is written as start + i).
        #[range(0, 999_999_999)]
        start: u64 = 0,
        /// Replace files that already exist.
        overwrite: bool = false,
        /// Alpha convention of RGBA layers: premultiplied (colour × alpha, usual for EXR) or straight.
        alpha: AlphaMode = AlphaMode::Premultiplied,
    }
    pub struct WriteExrLayersOut {
        /// How many files were written.
        frames: usize,
        /// The first file written.
        first: OutputPath,
        /// The layers of each file, main first (rgba, then the names given).
        layers: String,
    }
}

/// A connected extra layer: its clip, name and sample type.
struct Extra<'a> {
    clip: &'a Clip,
    name: String,
    half: bool,
}

impl WriteExrLayers {
    /// The connected extra layers, checked: each named, names distinct, frame counts the main clip's.
    fn extras(&self) -> Result<Vec<Extra<'_>>, NodeError> {
        let main_len = self.main.len();
        let inputs: [(&Clip, &str, ExrType, &str, &str); 4] = [
            (&self.layer1, &self.name1, self.type1, port!(WriteExrLayers, layer1), port!(WriteExrLayers, name1)),
            (&self.layer2, &self.name2, self.type2, port!(WriteExrLayers, layer2), port!(WriteExrLayers, name2)),
            (&self.layer3, &self.name3, self.type3, port!(WriteExrLayers, layer3), port!(WriteExrLayers, name3)),
            (&self.layer4, &self.name4, self.type4, port!(WriteExrLayers, layer4), port!(WriteExrLayers, name4)),
        ];
        let mut out: Vec<Extra<'_>> = Vec::new();
        for (clip, name, ty, clip_port, name_port) in inputs {
            if clip.is_empty() {
                continue;
            }
            let name = name.trim();
            if let Some(why) = bad_layer_name(name) {
                return Err(NodeError::port(name_port, format!("{clip_port} is connected, but its layer name {why}")));
            }
            if out.iter().any(|e| e.name == name) {
                return Err(NodeError::port(name_port, format!("two layers are named '{name}'; every layer needs its own name")));
            }
            if clip.len() != main_len {
                return Err(NodeError::port(
                    clip_port,
                    format!("has {} frames but main has {main_len}; every layer needs one per frame", clip.len()),
                ));
            }
            out.push(Extra { clip, name: name.to_string(), half: ty == ExrType::Half });
        }
        Ok(out)
    }

    /// The node error for `e`, as `imaging.write_sequence` names its ports.
    fn node_error(e: IoError) -> NodeError {
        match e {
            IoError::Path(message) => NodeError::port(port!(WriteExrLayers, pattern), message),
            IoError::Exists(message) => NodeError::port(port!(WriteExrLayers, overwrite), message),
            e @ IoError::EmptyClip => NodeError::port(port!(WriteExrLayers, main), e.to_string()),
            e @ (IoError::Other(_) | IoError::Message(_) | IoError::Frame { .. }) => e.into(),
        }
    }
}

/// Why `name` cannot name a layer, if it cannot: empty, or not a dotted path of channel-name
/// characters (a dot nests layers, `light.key`).
fn bad_layer_name(name: &str) -> Option<String> {
    if name.is_empty() {
        return Some("is empty: name it (emission, mask, motion…)".to_string());
    }
    if name.split('.').any(str::is_empty) {
        return Some(format!("'{name}' has an empty part between dots"));
    }
    if name.chars().any(|c| c.is_control() || c.is_whitespace()) {
        return Some(format!("'{name}' has spaces or control characters"));
    }
    if exr::prelude::Text::new_or_none(name).is_none() || name.len() + 2 > super::exr_layers::MAX_NAME {
        return Some(format!("'{}' cannot be written: {}", pyrograph_core::error::shortened(name), super::exr_layers::NAME_RULE));
    }
    None
}

impl Cook for WriteExrLayers {
    fn cook(self, ctx: &CookCtx) -> Result<WriteExrLayersOut, NodeError> {
        let extras = self.extras()?;
        let is_exr = self.pattern.extension().is_some_and(|e| e.eq_ignore_ascii_case("exr"));
        if !is_exr {
            return Err(NodeError::port(
                port!(WriteExrLayers, pattern),
                format!("'{}' must end in .exr: only OpenEXR files hold layers", self.pattern.display()),
            ));
        }
        let options = WriteOptions {
            format: OutputFormat::Exr { half: self.exr_type == ExrType::Half },
            start: self.start,
            overwrite: self.overwrite || ctx.settings().overwrite,
            frames: ctx.settings().frames.clone(),
            skip_existing: ctx.settings().skip_existing,
            alpha: self.alpha,
            pattern: self.pattern.0.clone(),
        };
        let alpha = |img: Arc<Image>| match self.alpha {
            AlphaMode::Straight => img,
            AlphaMode::Premultiplied => Arc::new(premultiply(&img)),
        };
        let main_half = self.exr_type == ExrType::Half;
        let written = write_frames(self.main.len(), &options, ctx, |i| {
            let main = alpha(self.main.image(i, ctx)?);
            let images = extras.iter().map(|e| e.clip.image(i, ctx).map(alpha)).collect::<Result<Vec<_>, _>>()?;
            let mut layers = vec![LayerOut { name: "", image: &main, half: main_half }];
            layers.extend(extras.iter().zip(&images).map(|(e, img)| LayerOut { name: &e.name, image: img, half: e.half }));
            encode_exr_layers(&layers)
        })
        .map_err(WriteExrLayers::node_error)?;
        let names: Vec<&str> = std::iter::once("rgba").chain(extras.iter().map(|e| e.name.as_str())).collect();
        Ok(WriteExrLayersOut {
            frames: written.len(),
            first: OutputPath(written.first().cloned().unwrap_or_default()),
            layers: names.join(", "),
        })
    }
}

#[cfg(test)]
mod tests {
    use pyrograph_core::{Channels, PortType, Value};

    use super::*;
    use crate::io::{SequenceOptions, open_sequence};

    fn clip_of(frames: usize, channels: Channels, seed: f32) -> ClipOf<Arc<Image>> {
        let n = channels.count();
        let frames = (0..frames)
            .map(|f| {
                let data = (0..4 * 3 * n).map(|i| seed + f as f32 + i as f32 / 64.0).map(|v| v.fract()).collect();
                Value::Image(Arc::new(Image::from_vec(4, 3, channels, data).unwrap()))
            })
            .collect();
        ClipOf::new(Clip::from_frames(PortType::Image, 24.0, frames))
    }

    fn node(dir: &std::path::Path) -> WriteExrLayers {
        WriteExrLayers {
            main: clip_of(3, Channels::Rgba, 0.1),
            layer1: clip_of(3, Channels::Rgba, 0.3),
            name1: "emission".into(),
            type1: ExrType::Float,
            layer2: clip_of(3, Channels::Gray, 0.7),
            name2: "mask".into(),
            type2: ExrType::Half,
            layer3: no_images(),
            name3: String::new(),
            type3: ExrType::Half,
            layer4: no_images(),
            name4: String::new(),
            type4: ExrType::Half,
            pattern: OutputPath(dir.join("passes_####.exr")),
            exr_type: ExrType::Float,
            start: 1,
            overwrite: false,
            alpha: AlphaMode::Straight,
        }
    }

    /// The error of a cook that must fail.
    fn refused(n: WriteExrLayers, ctx: &CookCtx) -> String {
        match n.cook(ctx) {
            Ok(out) => panic!("wrote {} frames", out.frames),
            Err(e) => e.to_string(),
        }
    }

    #[test]
    fn each_frame_holds_every_layer_and_each_reads_back_by_name() {
        let dir = tempfile::tempdir().unwrap();
        let n = node(dir.path());
        let (main, emission) = (n.main.clone(), n.layer1.clone());
        let ctx = CookCtx::new();
        let out = n.cook(&ctx).unwrap();
        assert_eq!((out.frames, out.layers.as_str()), (3, "rgba, emission, mask"));
        assert!(out.first.ends_with("passes_0001.exr"));
        let read = |layer: &str| {
            let options = SequenceOptions { layer: layer.into(), ..SequenceOptions::default() };
            open_sequence(&dir.path().join("passes_####.exr"), &options, &ctx, crate::io::LoadSequence::node_error).unwrap()
        };
        for i in 0..3 {
            assert_eq!(read("").image(i, &ctx).unwrap().data(), main.image(i, &ctx).unwrap().data());
            assert_eq!(read("emission").image(i, &ctx).unwrap().data(), emission.image(i, &ctx).unwrap().data());
            assert_eq!(read("mask").image(i, &ctx).unwrap().channels(), Channels::Gray);
        }
        // Written again over the same files: refused, nothing lost.
        let e = refused(node(dir.path()), &ctx);
        assert!(e.contains("overwrite") && e.contains("already exists"), "{e}");
    }

    #[test]
    fn layers_without_names_twins_or_their_own_length_are_refused_naming_the_port() {
        let dir = tempfile::tempdir().unwrap();
        let ctx = CookCtx::new();
        let mut n = node(dir.path());
        n.name2 = " ".into();
        let e = refused(n, &ctx);
        assert!(e.contains("name2") && e.contains("layer2 is connected, but its layer name is empty"), "{e}");
        let mut n = node(dir.path());
        n.name2 = "emission".into();
        assert!(refused(n, &ctx).contains("two layers are named 'emission'"));
        let mut n = node(dir.path());
        n.layer2 = clip_of(2, Channels::Gray, 0.7);
        assert!(refused(n, &ctx).contains("has 2 frames but main has 3"));
        let mut n = node(dir.path());
        n.pattern = OutputPath(dir.path().join("p_####.png"));
        assert!(refused(n, &ctx).contains("must end in .exr"));
        assert!(bad_layer_name("a..b").is_some() && bad_layer_name("light.key").is_none());
        assert!(
            bad_layer_name("火").is_some_and(|w| w.contains("Latin-1")),
            "a name the format cannot hold is refused, not a panic"
        );
        assert!(bad_layer_name(&"x".repeat(300)).is_some());
        assert!(std::fs::read_dir(dir.path()).unwrap().next().is_none(), "nothing was written");
    }
}
