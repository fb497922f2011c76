//! The USD stage `particles.write_usd` writes, authored through openusd's stage API: the flames as
//! Points, an optional mesh, and an optional fire spread's front (BasisCurves) and roots (Points).

use std::sync::Arc;

use openusd::gf::Vec3f;
use openusd::{sdf, usd};
use pyrograph_render::particles::{Particle, Particles};

use crate::types::{Mesh, SpreadState};

/// USD's primvar interpolation for one value per point.
const VERTEX: &str = "vertex";
/// The metadata field that holds a primvar's interpolation.
const INTERPOLATION: &str = "interpolation";
/// Prim names the optional parts take under /World.
pub const MESH: &str = "mesh";
/// The fire front's prim name.
pub const FRONT: &str = "front";
/// The spread's flame roots' prim name.
pub const ROOTS: &str = "roots";

/// What goes into one stage.
pub struct Scene<'a> {
    /// The particles, one entry a frame.
    pub flames: &'a [Arc<Particles>],
    /// Their Points prim's name under /World.
    pub name: &'a str,
    /// A static mesh (empty: none).
    pub mesh: &'a Mesh,
    /// A fire spread, one entry a frame (empty: none).
    pub spread: &'a [Arc<SpreadState>],
    /// Frames per second of the clips.
    pub fps: f64,
}

impl Scene<'_> {
    /// The stage as `.usda` text (time code i = frame i).
    pub fn text(&self) -> anyhow::Result<Vec<u8>> {
        let stage = usd::Stage::builder().in_memory("pyrograph.usda")?;
        stage.define_prim("/World")?.set_type_name("Xform")?;
        stage.set_default_prim("World")?;
        let frames = self.flames.len().max(self.spread.len());
        stage.set_start_time_code(0.0)?;
        stage.set_end_time_code(frames.saturating_sub(1) as f64)?;
        let rate = if self.fps.is_finite() && self.fps > 0.0 { self.fps } else { 24.0 };
        stage.set_time_codes_per_second(rate)?;
        stage.set_frames_per_second(rate)?;
        write_points(&stage, &format!("/World/{}", self.name), self.flames)?;
        if !self.mesh.triangles.is_empty() {
            write_mesh(&stage, &format!("/World/{MESH}"), self.mesh)?;
        }
        if !self.spread.is_empty() {
            write_front(&stage, &format!("/World/{FRONT}"), self.spread)?;
            write_roots(&stage, &format!("/World/{ROOTS}"), self.spread)?;
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
        Ok(stage.root_layer().export_to_string()?.into_bytes())
    }
}

/// A schema attribute (`custom = false`) of `prim`; a primvar gets per-point interpolation.
fn attribute(stage: &usd::Stage, prim: &str, name: &str, ty: &str, per_point: bool) -> anyhow::Result<usd::Attribute> {
    let a = stage.create_attribute(format!("{prim}.{name}").as_str(), ty)?.set_custom(false)?;
    Ok(if per_point { a.set_metadata(INTERPOLATION, sdf::Value::Token(VERTEX.into()))? } else { a })
}

fn at(t: usize) -> usd::TimeCode {
    usd::TimeCode::from(t as f64)
}

/// The flames: a Points prim with a sample per frame.
fn write_points(stage: &usd::Stage, prim: &str, frames: &[Arc<Particles>]) -> anyhow::Result<()> {
    stage.define_prim(prim)?.set_type_name("Points")?;
    let points = attribute(stage, prim, "points", "point3f[]", false)?;
    let widths = attribute(stage, prim, "widths", "float[]", true)?;
    let extent = attribute(stage, prim, "extent", "float3[]", false)?;
    let color = attribute(stage, prim, "primvars:displayColor", "color3f[]", true)?;
    let opacity = attribute(stage, prim, "primvars:displayOpacity", "float[]", true)?;
    let age = attribute(stage, prim, "primvars:age", "float[]", true)?;
    let flame = attribute(stage, prim, "primvars:flame", "int[]", true)?;
    let radius = |q: &Particle| q.size[0].abs().max(q.size[1].abs());
    for (t, frame) in frames.iter().enumerate() {
        let ps = &frame.particles;
        points.clone().set_at(sdf::Value::Vec3fVec(ps.iter().map(|q| q.position.into()).collect()), at(t))?;
        widths.clone().set_at(sdf::Value::FloatVec(ps.iter().map(|q| 2.0 * radius(q)).collect()), at(t))?;
        let bounds = extent_of(ps.iter().map(|q| (q.position, radius(q))));
        extent.clone().set_at(sdf::Value::Vec3fVec(bounds), at(t))?;
        let colors = ps.iter().map(|q| [q.center[0], q.center[1], q.center[2]].into()).collect();
        color.clone().set_at(sdf::Value::Vec3fVec(colors), at(t))?;
        opacity.clone().set_at(sdf::Value::FloatVec(ps.iter().map(|q| q.center[3]).collect()), at(t))?;
        age.clone().set_at(sdf::Value::FloatVec(ps.iter().map(|q| q.weight).collect()), at(t))?;
        let groups = ps.iter().map(|q| i32::try_from(q.group).unwrap_or(i32::MAX)).collect();
        flame.clone().set_at(sdf::Value::IntVec(groups), at(t))?;
    }
    Ok(())
}

/// A static triangle mesh (no subdivision: the triangles are the surface).
fn write_mesh(stage: &usd::Stage, prim: &str, mesh: &Mesh) -> anyhow::Result<()> {
    stage.define_prim(prim)?.set_type_name("Mesh")?;
    let points: Vec<Vec3f> = mesh.positions.iter().map(|&p| p.into()).collect();
    attribute(stage, prim, "points", "point3f[]", false)?.set(sdf::Value::Vec3fVec(points))?;
    let counts = vec![3; mesh.triangles.len()];
    attribute(stage, prim, "faceVertexCounts", "int[]", false)?.set(sdf::Value::IntVec(counts))?;
    let indices: Vec<i32> = mesh.triangles.iter().flatten().map(|&i| i32::try_from(i).unwrap_or(i32::MAX)).collect();
    attribute(stage, prim, "faceVertexIndices", "int[]", false)?.set(sdf::Value::IntVec(indices))?;
    let bounds = extent_of(mesh.positions.iter().map(|&p| (p, 0.0)));
    attribute(stage, prim, "extent", "float3[]", false)?.set(sdf::Value::Vec3fVec(bounds))?;
    attribute(stage, prim, "subdivisionScheme", "token", false)?
        .set_variability(sdf::Variability::Uniform)?
        .set(sdf::Value::Token("none".into()))?;
    Ok(())
}

/// The burning boundary: linear curves, a closed loop repeated to its first point.
fn write_front(stage: &usd::Stage, prim: &str, frames: &[Arc<SpreadState>]) -> anyhow::Result<()> {
    stage.define_prim(prim)?.set_type_name("BasisCurves")?;
    attribute(stage, prim, "type", "token", false)?
        .set_variability(sdf::Variability::Uniform)?
        .set(sdf::Value::Token("linear".into()))?;
    let points = attribute(stage, prim, "points", "point3f[]", false)?;
    let counts = attribute(stage, prim, "curveVertexCounts", "int[]", false)?;
    let extent = attribute(stage, prim, "extent", "float3[]", false)?;
    for (t, state) in frames.iter().enumerate() {
        let mut all: Vec<Vec3f> = Vec::new();
        let mut n: Vec<i32> = Vec::new();
        // A boundary of one point is no curve (USD wants two vertices at least).
        for line in state.boundaries.iter().filter(|l| l.len() >= 2) {
            let closed = line.len() > 2;
            all.extend(line.iter().map(|&p| Vec3f::from(p)));
            if closed {
                all.push(line[0].into());
            }
            n.push(i32::try_from(line.len() + usize::from(closed)).unwrap_or(i32::MAX));
        }
        let bounds = extent_of(state.boundaries.iter().flatten().map(|&p| (p, 0.0)));
        points.clone().set_at(sdf::Value::Vec3fVec(all), at(t))?;
        counts.clone().set_at(sdf::Value::IntVec(n), at(t))?;
        extent.clone().set_at(sdf::Value::Vec3fVec(bounds), at(t))?;
    }
    Ok(())
}

/// The live flame roots the front dropped, with their age in seconds.
fn write_roots(stage: &usd::Stage, prim: &str, frames: &[Arc<SpreadState>]) -> anyhow::Result<()> {
    stage.define_prim(prim)?.set_type_name("Points")?;
    let points = attribute(stage, prim, "points", "point3f[]", false)?;
    let extent = attribute(stage, prim, "extent", "float3[]", false)?;
    let age = attribute(stage, prim, "primvars:age", "float[]", true)?;
    for (t, state) in frames.iter().enumerate() {
        points.clone().set_at(sdf::Value::Vec3fVec(state.roots.iter().map(|r| r.position.into()).collect()), at(t))?;
        extent.clone().set_at(sdf::Value::Vec3fVec(extent_of(state.roots.iter().map(|r| (r.position, 0.0)))), at(t))?;
        age.clone().set_at(sdf::Value::FloatVec(state.roots.iter().map(|r| r.age).collect()), at(t))?;
    }
    Ok(())
}

/// The bounds of spheres (centre, radius); a zero box when there are none.
fn extent_of(items: impl Iterator<Item = ([f32; 3], f32)>) -> Vec<Vec3f> {
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
    vec![lo.into(), hi.into()]
}
