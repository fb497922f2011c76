//! USD stages for DCCs, shared by the node crates' writers (`particles.write_usd`,
//! `cloth.write_usd`): a stage in memory through openusd's stage API with pyrograph's conventions
//! (`/World` as default prim, Y up, metres, a time code per frame), schema attributes and per-point
//! primvars, extents, and the checks and atomic write every writer makes.

use std::path::Path;

use openusd::gf::Vec3f;
use openusd::{sdf, usd};
use pyrograph_core::document::write_atomic;

pub use openusd::sdf::Value;
pub use openusd::usd::{Attribute, Stage};

/// USD's primvar interpolation for one value per point.
const VERTEX: &str = "vertex";
/// The metadata field that holds a primvar's interpolation.
const INTERPOLATION: &str = "interpolation";

/// A new stage with `/World` (an Xform, the default prim) and time codes 0 … frames − 1 at `fps`.
pub fn new_stage(frames: usize, fps: f64) -> anyhow::Result<Stage> {
    let stage = usd::Stage::builder().in_memory("pyrograph.usda")?;
    stage.define_prim("/World")?.set_type_name("Xform")?;
    stage.set_default_prim("World")?;
    stage.set_start_time_code(0.0)?;
    stage.set_end_time_code(frames.saturating_sub(1) as f64)?;
    let rate = if fps.is_finite() && fps > 0.0 { fps } else { 24.0 };
    stage.set_time_codes_per_second(rate)?;
    stage.set_frames_per_second(rate)?;
    Ok(stage)
}

/// Defines `path` as a prim of schema `type_name`.
pub fn define(stage: &Stage, path: &str, type_name: &str) -> anyhow::Result<()> {
    stage.define_prim(path)?.set_type_name(type_name)?;
    Ok(())
}

/// A schema attribute (`custom = false`) of `prim`; `per_point` gives it vertex interpolation (a primvar).
pub fn attribute(stage: &Stage, prim: &str, name: &str, ty: &str, per_point: bool) -> anyhow::Result<Attribute> {
    let a = stage.create_attribute(format!("{prim}.{name}").as_str(), ty)?.set_custom(false)?;
    Ok(if per_point { a.set_metadata(INTERPOLATION, sdf::Value::Token(VERTEX.into()))? } else { a })
}

/// A uniform token attribute (a schema setting such as `subdivisionScheme` or a curve `type`).
pub fn uniform_token(stage: &Stage, prim: &str, name: &str, value: &str) -> anyhow::Result<()> {
    attribute(stage, prim, name, "token", false)?
        .set_variability(sdf::Variability::Uniform)?
        .set(sdf::Value::Token(value.into()))?;
    Ok(())
}

/// Sets `attr` at frame `t`.
pub fn sample(attr: &Attribute, t: usize, value: Value) -> anyhow::Result<()> {
    attr.clone().set_at(value, usd::TimeCode::from(t as f64))?;
    Ok(())
}

/// An `asset` value: a file the stage refers to.
pub fn asset(path: &str) -> Value {
    Value::AssetPath(sdf::AssetPath::new(path))
}

/// A schema relationship `name` of `prim` targeting the prims at `targets`.
pub fn relationship(stage: &Stage, prim: &str, name: &str, targets: &[&str]) -> anyhow::Result<()> {
    let paths = targets.iter().map(|t| sdf::Path::new(t)).collect::<anyhow::Result<Vec<_>>>()?;
    stage.create_relationship(format!("{prim}.{name}").as_str())?.set_custom(false)?.set_targets(paths)?;
    Ok(())
}

/// Points as USD vectors.
pub fn vec3s<'a>(points: impl IntoIterator<Item = &'a [f32; 3]>) -> Value {
    Value::Vec3fVec(points.into_iter().map(|&p| Vec3f::from(p)).collect())
}

/// The bounds of spheres (centre, radius) as a USD `extent`; a zero box when there are none.
pub fn extent_of(items: impl Iterator<Item = ([f32; 3], f32)>) -> Value {
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    for (p, r) in items {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k] - r);
            hi[k] = hi[k].max(p[k] + r);
        }
    }
    if lo[0] > hi[0] {
        (lo, hi) = ([0.0; 3], [0.0; 3]);
    }
    Value::Vec3fVec(vec![lo.into(), hi.into()])
}

/// The stage as `.usda` text, with its up axis (Y) and unit (metres) said.
pub fn finish(stage: &Stage) -> anyhow::Result<Vec<u8>> {
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
    Ok(stage.root_layer().export_to_string()?.into_bytes())
}

/// Point samples (points × frames, every prim together) one stage may hold: the stage is built
/// whole in memory before it is written (openusd has no streaming writer), so a long clip of many
/// particles is refused with the way round instead of filling memory.
pub const MAX_POINT_SAMPLES: usize = 1 << 24;

/// Adds `points` (one frame's) to `total` and refuses the stage once it passes
/// [`MAX_POINT_SAMPLES`], naming the frame.
pub fn count_samples(total: &mut usize, points: usize, frame: usize) -> Result<(), String> {
    *total = total.saturating_add(points);
    if *total <= MAX_POINT_SAMPLES {
        return Ok(());
    }
    Err(format!(
        "by frame {frame} the stage holds {total} point samples, more than the {MAX_POINT_SAMPLES} a stage built in \
         memory may hold; write a shorter frame range (--frames) or fewer points per frame, as several stages"
    ))
}

/// A USD prim name: an identifier (letters, digits, underscores; not starting with a digit).
pub fn valid_prim_name(name: &str) -> bool {
    let mut chars = name.chars();
    chars.next().is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
        && chars.all(|c| c.is_ascii_alphanumeric() || c == '_')
        && name.len() <= 255
}

/// What is wrong with a writer's target, and which of its settings to change.
#[derive(Debug, PartialEq, Eq)]
pub enum TargetError {
    /// The file's name (its extension).
    Path(String),
    /// The prim name.
    Name(String),
    /// The file exists and `overwrite` is off.
    Exists(String),
}

/// Checks a stage writer's file and prim name before anything is cooked.
pub fn check_target(path: &Path, name: &str, overwrite: bool) -> Result<(), TargetError> {
    let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).unwrap_or_default();
    match ext.as_str() {
        "usda" | "usd" => {}
        // openusd 0.6 writes a prim's children list as a token array where Pixar's reader wants a
        // token vector, so a nested prim is lost on load (usd-core: "Invalid children found in
        // primChildren field"); openusd 0.7 fixes it but needs a newer Rust than this build's.
        "usdc" => {
            return Err(TargetError::Path(format!(
                "'{}': binary .usdc is not written yet (the USD library pyrograph uses writes crate files Pixar's \
                 USD cannot open); write .usda or .usd (text, which every USD reader opens) and convert with \
                 `usdcat fire.usda -o fire.usdc` if you need binary",
                path.display()
            )));
        }
        _ => return Err(TargetError::Path(format!("'{}' must end in .usda or .usd (a USD text stage)", path.display()))),
    }
    if !valid_prim_name(name) {
        return Err(TargetError::Name(format!(
            "'{}' is not a USD prim name: use letters, digits and underscores, not starting with a digit",
            name.escape_default()
        )));
    }
    if !overwrite && path.exists() {
        return Err(TargetError::Exists(format!(
            "{} already exists; nothing was written. Set overwrite to true or render with --overwrite",
            path.display()
        )));
    }
    Ok(())
}

/// Writes the stage's bytes to `path` atomically (its folder made if missing).
pub fn write(path: &Path, bytes: &[u8], overwrite: bool) -> Result<(), String> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    }
    write_atomic(path, bytes, overwrite).map_err(|e| format!("writing {}: {e}", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn targets_usd_cannot_take_are_refused_before_anything_is_cooked() {
        let dir = std::env::temp_dir();
        assert!(matches!(check_target(&dir.join("a.usdc"), "x", false), Err(TargetError::Path(m)) if m.contains("usdcat")));
        assert!(matches!(check_target(&dir.join("a.abc"), "x", false), Err(TargetError::Path(_))));
        assert!(matches!(check_target(&dir.join("a.usda"), "2x", false), Err(TargetError::Name(_))));
        assert!(valid_prim_name("flames_2") && valid_prim_name("_x"));
        assert!(!valid_prim_name("a b") && !valid_prim_name("") && !valid_prim_name("flame/s"));
        let file = tempfile_in(&dir);
        assert!(matches!(check_target(&file, "x", false), Err(TargetError::Exists(_))));
        assert_eq!(check_target(&file, "x", true), Ok(()));
        std::fs::remove_file(file).unwrap();
    }

    fn tempfile_in(dir: &Path) -> std::path::PathBuf {
        let p = dir.join(format!("pyrograph-usd-test-{}.usda", std::process::id()));
        std::fs::write(&p, "").unwrap();
        p
    }

    #[test]
    fn a_stage_says_its_axis_unit_and_time_codes() {
        let stage = new_stage(3, 30.0).unwrap();
        define(&stage, "/World/p", "Points").unwrap();
        let a = attribute(&stage, "/World/p", "points", "point3f[]", false).unwrap();
        sample(&a, 2, vec3s(&[[1.0, 2.0, 3.0]])).unwrap();
        let text = String::from_utf8(finish(&stage).unwrap()).unwrap();
        for needle in
            ["upAxis = \"Y\"", "metersPerUnit = 1.0", "endTimeCode = 2.0", "timeCodesPerSecond = 30.0", "2.0: [(1.0, 2.0, 3.0)]"]
        {
            assert!(text.contains(needle), "{needle} missing in\n{text}");
        }
        assert_eq!(extent_of(std::iter::empty()), Value::Vec3fVec(vec![[0.0; 3].into(), [0.0; 3].into()]));
    }
}
