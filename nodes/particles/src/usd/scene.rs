//! The USD stage `particles.write_usd` writes: the flames as Points, an optional mesh, and an
//! optional fire spread's front (BasisCurves) and roots (Points).

use std::sync::Arc;

use pyrograph_render::particles::{Particle, Particles};
use pyrograph_usd::{Stage, Value, attribute, define, extent_of, sample, uniform_token, vec3s};

use crate::types::{Mesh, SpreadState};

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
        let stage = pyrograph_usd::new_stage(self.flames.len().max(self.spread.len()), self.fps)?;
        write_points(&stage, &format!("/World/{}", self.name), self.flames)?;
        if !self.mesh.triangles.is_empty() {
            write_mesh(&stage, &format!("/World/{MESH}"), self.mesh)?;
        }
        if !self.spread.is_empty() {
            write_front(&stage, &format!("/World/{FRONT}"), self.spread)?;
            write_roots(&stage, &format!("/World/{ROOTS}"), self.spread)?;
        }
        pyrograph_usd::finish(&stage)
    }
}

/// The flames: a Points prim with a sample per frame.
fn write_points(stage: &Stage, prim: &str, frames: &[Arc<Particles>]) -> anyhow::Result<()> {
    define(stage, prim, "Points")?;
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
        sample(&points, t, vec3s(ps.iter().map(|q| &q.position)))?;
        sample(&widths, t, Value::FloatVec(ps.iter().map(|q| 2.0 * radius(q)).collect()))?;
        sample(&extent, t, extent_of(ps.iter().map(|q| (q.position, radius(q)))))?;
        let colors: Vec<[f32; 3]> = ps.iter().map(|q| [q.center[0], q.center[1], q.center[2]]).collect();
        sample(&color, t, vec3s(&colors))?;
        sample(&opacity, t, Value::FloatVec(ps.iter().map(|q| q.center[3]).collect()))?;
        sample(&age, t, Value::FloatVec(ps.iter().map(|q| q.weight).collect()))?;
        sample(&flame, t, Value::IntVec(ps.iter().map(|q| i32::try_from(q.group).unwrap_or(i32::MAX)).collect()))?;
    }
    Ok(())
}

/// A static triangle mesh (no subdivision: the triangles are the surface).
fn write_mesh(stage: &Stage, prim: &str, mesh: &Mesh) -> anyhow::Result<()> {
    define(stage, prim, "Mesh")?;
    attribute(stage, prim, "points", "point3f[]", false)?.set(vec3s(&mesh.positions))?;
    attribute(stage, prim, "faceVertexCounts", "int[]", false)?.set(Value::IntVec(vec![3; mesh.triangles.len()]))?;
    let indices: Vec<i32> = mesh.triangles.iter().flatten().map(|&i| i32::try_from(i).unwrap_or(i32::MAX)).collect();
    attribute(stage, prim, "faceVertexIndices", "int[]", false)?.set(Value::IntVec(indices))?;
    attribute(stage, prim, "extent", "float3[]", false)?.set(extent_of(mesh.positions.iter().map(|&p| (p, 0.0))))?;
    uniform_token(stage, prim, "subdivisionScheme", "none")
}

/// The burning boundary: linear curves, a closed loop repeated to its first point.
fn write_front(stage: &Stage, prim: &str, frames: &[Arc<SpreadState>]) -> anyhow::Result<()> {
    define(stage, prim, "BasisCurves")?;
    uniform_token(stage, prim, "type", "linear")?;
    let points = attribute(stage, prim, "points", "point3f[]", false)?;
    let counts = attribute(stage, prim, "curveVertexCounts", "int[]", false)?;
    let extent = attribute(stage, prim, "extent", "float3[]", false)?;
    for (t, state) in frames.iter().enumerate() {
        let mut all: Vec<[f32; 3]> = Vec::new();
        let mut n: Vec<i32> = Vec::new();
        // A boundary of one point is no curve (USD wants two vertices at least).
        for line in state.boundaries.iter().filter(|l| l.len() >= 2) {
            let closed = line.len() > 2;
            all.extend(line);
            if closed {
                all.push(line[0]);
            }
            n.push(i32::try_from(line.len() + usize::from(closed)).unwrap_or(i32::MAX));
        }
        sample(&points, t, vec3s(&all))?;
        sample(&counts, t, Value::IntVec(n))?;
        sample(&extent, t, extent_of(state.boundaries.iter().flatten().map(|&p| (p, 0.0))))?;
    }
    Ok(())
}

/// The live flame roots the front dropped, with their age in seconds.
fn write_roots(stage: &Stage, prim: &str, frames: &[Arc<SpreadState>]) -> anyhow::Result<()> {
    define(stage, prim, "Points")?;
    let points = attribute(stage, prim, "points", "point3f[]", false)?;
    let extent = attribute(stage, prim, "extent", "float3[]", false)?;
    let age = attribute(stage, prim, "primvars:age", "float[]", true)?;
    for (t, state) in frames.iter().enumerate() {
        sample(&points, t, vec3s(state.roots.iter().map(|r| &r.position)))?;
        sample(&extent, t, extent_of(state.roots.iter().map(|r| (r.position, 0.0))))?;
        sample(&age, t, Value::FloatVec(state.roots.iter().map(|r| r.age).collect()))?;
    }
    Ok(())
}
