//! `particles.write_usd`: particles over time as a USD stage, so Houdini, Blender, Unreal or any
//! USD reader can render Perry's flames and embers with its own lights and camera, or place them in
//! a scene: one `UsdGeomPoints` prim with a time sample per frame.

use std::sync::Arc;

use openusd::{sdf, usd};
use pyrograph_core::document::write_atomic;
use pyrograph_core::{ClipOf, Cook, CookCtx, NodeError, OutputPath, port};
use pyrograph_render::particles::Particles;

pyrograph_core::node! {
    /// Writes particles over time as a USD stage: one UsdGeomPoints prim sampled at every frame (Perry 1994 §3.2.1 particles, for DCCs).
    ///
    /// `/World/<name>` holds `points`, `widths` (twice the particles' half width), `extent`, and the primvars
    /// `displayColor` and `displayOpacity` (the centre colour), `age` (the particle's weight: its age in
    /// steps for flame particles) and `flame` (which flame or group it belongs to), all per point ("vertex")
    /// and sampled at time codes 0, 1, … (one per frame; `timeCodesPerSecond` is the clip's rate). The stage
    /// says `upAxis = "Y"`, `metersPerUnit = 1`. `.usda` and `.usd` are written as text (binary `.usdc`
    /// is refused: convert with usdcat); the file is written atomically and never replaces one unless
    /// `overwrite` is on.
    #[node("particles.write_usd", "Particles", Sink)]
    pub struct WriteUsd {
        /// The particles over time (particles.particle_flame, particles.embers).
        particles: ClipOf<Arc<Particles>>,
        /// The stage file (.usda or .usd, text).
        path: OutputPath = "particles.usda".into(),
        /// The Points prim's name under /World.
        name: String = "flames".to_string(),
        /// Replace the file if it exists.
        overwrite: bool = false,
    }
    pub struct WriteUsdOut {
        /// The stage written.
        path: OutputPath,
        /// Frames (time samples) in it.
        frames: usize,
    }
}

/// USD's primvar interpolation for one value per point.
const VERTEX: &str = "vertex";
/// The metadata field that holds a primvar's interpolation.
const INTERPOLATION: &str = "interpolation";

impl Cook for WriteUsd {
    fn cook(self, ctx: &CookCtx) -> Result<WriteUsdOut, NodeError> {
        let path_port = port!(WriteUsd, path);
        let ext = self.path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).unwrap_or_default();
        match ext.as_str() {
            "usda" | "usd" => {}
            // openusd 0.6 writes a prim's children list as a token array where Pixar's reader wants
            // a token vector, so a nested prim is lost on load (usd-core: "Invalid children found
            // in primChildren field"); openusd 0.7 fixes it but needs a newer Rust than this build's.
            "usdc" => {
                return Err(NodeError::port(
                    path_port,
                    format!(
                        "'{}': binary .usdc is not written yet (the USD library pyrograph uses writes crate files \
                         Pixar's USD cannot open); write .usda or .usd (text, which every USD reader opens) and \
                         convert with `usdcat fire.usda -o fire.usdc` if you need binary",
                        self.path.display()
                    ),
                ));
            }
            _ => {
                return Err(NodeError::port(
                    path_port,
                    format!("'{}' must end in .usda or .usd (a USD text stage)", self.path.display()),
                ));
            }
        }
        if !valid_prim_name(&self.name) {
            return Err(NodeError::port(
                port!(WriteUsd, name),
                format!(
                    "'{}' is not a USD prim name: use letters, digits and underscores, not starting with a digit",
                    self.name.escape_default()
                ),
            ));
        }
        let overwrite = self.overwrite || ctx.settings().overwrite;
        if !overwrite && self.path.exists() {
            return Err(NodeError::port(
                port!(WriteUsd, overwrite),
                format!(
                    "{} already exists; nothing was written. Set overwrite to true or render with --overwrite",
                    self.path.display()
                ),
            ));
        }
        let clip = &self.particles;
        let mut frames = Vec::with_capacity(clip.len());
        for i in 0..clip.len() {
            ctx.check_cancel()?;
            let value = clip.get(i, ctx)?;
            let particles = value
                .downcast::<Particles>()
                .ok_or_else(|| NodeError::port(port!(WriteUsd, particles), format!("frame {i} holds no particles")))?;
            check_finite(&particles, i)?;
            frames.push(particles);
            ctx.frame_progress(i + 1, clip.len());
        }
        let bytes = stage_bytes(&frames, clip.fps(), &self.name)
            .map_err(|e| NodeError::port(path_port, format!("building the USD stage: {e:#}")))?;
        if let Some(dir) = self.path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir)
                .map_err(|e| NodeError::port(path_port, format!("cannot create {}: {e}", dir.display())))?;
        }
        write_atomic(&self.path, &bytes, overwrite)
            .map_err(|e| NodeError::port(path_port, format!("writing {}: {e}", self.path.display())))?;
        ctx.record_written(&self.path);
        Ok(WriteUsdOut { path: self.path, frames: clip.len() })
    }
}

/// A USD prim name: an identifier (letters, digits, underscores; not starting with a digit).
pub fn valid_prim_name(name: &str) -> bool {
    let mut chars = name.chars();
    chars.next().is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
        && chars.all(|c| c.is_ascii_alphanumeric() || c == '_')
        && name.len() <= 255
}

fn check_finite(p: &Particles, frame: usize) -> Result<(), NodeError> {
    match p.particles.iter().position(|q| q.position.iter().chain(&q.size).any(|v| !v.is_finite())) {
        Some(k) => Err(NodeError::port(
            port!(WriteUsd, particles),
            format!("frame {frame}: particle {k} has a non-finite position or size; USD cannot hold it"),
        )),
        None => Ok(()),
    }
}

/// The stage of `frames` (time code i = frame i) as `.usda` text.
pub fn stage_bytes(frames: &[Arc<Particles>], fps: f64, name: &str) -> anyhow::Result<Vec<u8>> {
    let stage = usd::Stage::builder().in_memory("pyrograph.usda")?;
    stage.define_prim("/World")?.set_type_name("Xform")?;
    stage.set_default_prim("World")?;
    let prim = format!("/World/{name}");
    stage.define_prim(prim.as_str())?.set_type_name("Points")?;
    stage.set_start_time_code(0.0)?;
    stage.set_end_time_code(frames.len().saturating_sub(1) as f64)?;
    let rate = if fps.is_finite() && fps > 0.0 { fps } else { 24.0 };
    stage.set_time_codes_per_second(rate)?;
    stage.set_frames_per_second(rate)?;
    let attribute = |prop: &str, ty: &str, primvar: bool| -> anyhow::Result<usd::Attribute> {
        let a = stage.create_attribute(format!("{prim}.{prop}").as_str(), ty)?.set_custom(false)?;
        Ok(if primvar { a.set_metadata(INTERPOLATION, sdf::Value::Token(VERTEX.into()))? } else { a })
    };
    let attrs = [
        ("points", "point3f[]", false),
        ("widths", "float[]", false),
        ("extent", "float3[]", false),
        ("primvars:displayColor", "color3f[]", true),
        ("primvars:displayOpacity", "float[]", true),
        ("primvars:age", "float[]", true),
        ("primvars:flame", "int[]", true),
    ];
    let handles: Vec<usd::Attribute> = attrs.iter().map(|(p, t, v)| attribute(p, t, *v)).collect::<anyhow::Result<_>>()?;
    // Widths are per point too (UsdGeomPoints: "vertex" when there is one per point).
    let widths = handles[1].clone().set_metadata(INTERPOLATION, sdf::Value::Token(VERTEX.into()))?;
    for (t, frame) in frames.iter().enumerate() {
        let time = usd::TimeCode::from(t as f64);
        let ps = &frame.particles;
        let points: Vec<openusd::gf::Vec3f> = ps.iter().map(|q| q.position.into()).collect();
        handles[0].clone().set_at(sdf::Value::Vec3fVec(points), time)?;
        let width = |q: &pyrograph_render::particles::Particle| 2.0 * q.size[0].abs().max(q.size[1].abs());
        widths.clone().set_at(sdf::Value::FloatVec(ps.iter().map(width).collect()), time)?;
        handles[2].clone().set_at(sdf::Value::Vec3fVec(extent(frame)), time)?;
        let colors = ps.iter().map(|q| [q.center[0], q.center[1], q.center[2]].into()).collect();
        handles[3].clone().set_at(sdf::Value::Vec3fVec(colors), time)?;
        handles[4].clone().set_at(sdf::Value::FloatVec(ps.iter().map(|q| q.center[3]).collect()), time)?;
        handles[5].clone().set_at(sdf::Value::FloatVec(ps.iter().map(|q| q.weight).collect()), time)?;
        let groups = ps.iter().map(|q| i32::try_from(q.group).unwrap_or(i32::MAX)).collect();
        handles[6].clone().set_at(sdf::Value::IntVec(groups), time)?;
    }
    {
        let root_id = stage.root_layer().identifier().to_string();
        let mut layer = stage.layer_mut(&root_id).ok_or_else(|| anyhow::anyhow!("the stage has no root layer"))?;
        let root = sdf::Path::abs_root();
        layer.edit(|edit| {
            edit.data_mut().set_field(&root, "upAxis", sdf::Value::Token("Y".into()));
            edit.data_mut().set_field(&root, "metersPerUnit", sdf::Value::Double(1.0));
            Ok(())
        })?;
    }
    let text = stage.root_layer().export_to_string()?;
    Ok(text.into_bytes())
}

/// The bounds of the particles' discs: the points widened by half their width.
fn extent(frame: &Particles) -> Vec<openusd::gf::Vec3f> {
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    for q in &frame.particles {
        let r = q.size[0].abs().max(q.size[1].abs());
        for k in 0..3 {
            lo[k] = lo[k].min(q.position[k] - r);
            hi[k] = hi[k].max(q.position[k] + r);
        }
    }
    if frame.particles.is_empty() {
        (lo, hi) = ([0.0; 3], [0.0; 3]);
    }
    vec![lo.into(), hi.into()]
}

#[cfg(test)]
mod tests {
    use super::*;
    use pyrograph_render::particles::Particle;

    fn frame(n: usize, t: f32) -> Arc<Particles> {
        let particles = (0..n)
            .map(|k| Particle {
                position: [k as f32, t, -1.0],
                size: [0.25, 0.5],
                center: [1.0, 0.5, 0.25, 0.75],
                weight: k as f32,
                group: (k % 2) as u32,
                ..Default::default()
            })
            .collect();
        Arc::new(Particles { particles, sides: 6, time: t, trails: true })
    }

    #[test]
    fn the_text_stage_has_a_points_prim_sampled_per_frame() {
        let frames = vec![frame(3, 0.0), frame(2, 1.0), frame(0, 2.0)];
        let text = String::from_utf8(stage_bytes(&frames, 24.0, "flames").unwrap()).unwrap();
        for needle in [
            "def Points \"flames\"",
            "point3f[] points.timeSamples",
            "color3f[] primvars:displayColor",
            "interpolation = \"vertex\"",
            "upAxis = \"Y\"",
            "defaultPrim = \"World\"",
            "timeCodesPerSecond = 24.0",
            "endTimeCode = 2.0",
        ] {
            assert!(text.contains(needle), "{needle} missing in\n{text}");
        }
        // The two points of frame 1, at y = 1.
        assert!(text.contains("1.0: [(0.0, 1.0, -1.0), (1.0, 1.0, -1.0)]"), "{text}");
    }

    #[test]
    fn names_and_numbers_usd_cannot_hold_are_refused() {
        assert!(valid_prim_name("flames_2") && valid_prim_name("_x"));
        assert!(!valid_prim_name("2flames") && !valid_prim_name("a b") && !valid_prim_name("") && !valid_prim_name("flame/s"));
        let mut bad = (*frame(2, 0.0)).clone();
        bad.particles[1].position[0] = f32::NAN;
        let e = check_finite(&bad, 4).unwrap_err().to_string();
        assert!(e.contains("frame 4: particle 1"), "{e}");
    }
}
