//! `cloth.write_usd`: mass-spring flames as an animated USD mesh, so a DCC can texture, light and
//! render the silk-torch cloths itself.

use std::sync::Arc;

use pyrograph_core::declare::Cook;
use pyrograph_core::{ClipOf, CookCtx, NodeError, OutputPath, port};
use pyrograph_usd::{Attribute, TargetError, Value, attribute, define, extent_of, sample, uniform_token, vec3s};

use crate::state::ClothState;

pyrograph_core::node! {
    /// Writes mass-spring flames over time as a USD stage: one Mesh of every flame's cloth, its points sampled at every frame (mass-spring flame project 2019 §Textures: the cloth a texture is drawn on).
    ///
    /// `/World/<name>` is a Mesh of quads, one per cell of each flame's `width × height` grid of masses, at
    /// its root: local x right, y up, z towards +Z (the renderer turns each cloth to its camera; in a DCC,
    /// aim them with a look-at constraint or leave them facing +Z). It carries `primvars:st` (texture
    /// coordinates per mass: s across the cloth, t up from its pinned bottom row) and `primvars:flame`
    /// (which flame), per point, with `subdivisionScheme = "none"`. Time code i is frame i; the stage says
    /// `upAxis = "Y"`, `metersPerUnit = 1`. Written as `.usda` or `.usd` text, atomically, never replacing a
    /// file unless `overwrite` is on.
    #[node("cloth.write_usd", "Cloth", Sink)]
    pub struct WriteClothUsd {
        /// The cloths over time (cloth.mass_spring_flame).
        cloth: ClipOf<Arc<ClothState>>,
        /// The stage file (.usda or .usd, text).
        path: OutputPath = "cloth.usda".into(),
        /// The Mesh prim's name under /World.
        name: String = "cloth".to_string(),
        /// Replace the file if it exists.
        overwrite: bool = false,
    }
    pub struct WriteClothUsdOut {
        /// The stage written.
        path: OutputPath,
        /// Frames (time samples) in it.
        frames: usize,
    }
}

impl Cook for WriteClothUsd {
    fn cook(self, ctx: &CookCtx) -> Result<WriteClothUsdOut, NodeError> {
        let path_port = port!(WriteClothUsd, path);
        let overwrite = self.overwrite || ctx.settings().overwrite;
        pyrograph_usd::check_target(&self.path, &self.name, overwrite).map_err(|e| match e {
            TargetError::Path(m) => NodeError::port(path_port, m),
            TargetError::Name(m) => NodeError::port(port!(WriteClothUsd, name), m),
            TargetError::Exists(m) => NodeError::port(port!(WriteClothUsd, overwrite), m),
        })?;
        let clip = &self.cloth;
        let mut samples = 0;
        let mut frames = Vec::with_capacity(clip.len());
        for i in 0..clip.len() {
            ctx.check_cancel()?;
            let state = clip
                .get(i, ctx)?
                .downcast::<ClothState>()
                .ok_or_else(|| NodeError::port(port!(WriteClothUsd, cloth), format!("frame {i} holds no cloth")))?;
            let bad = |points: &[[f32; 3]]| points.iter().position(|p| p.iter().any(|v| !v.is_finite()));
            let what = match (bad(&state.positions), bad(&state.roots)) {
                (Some(k), _) => Some(format!("mass {k}")),
                (None, Some(k)) => Some(format!("flame root {k}")),
                (None, None) => None,
            };
            if let Some(what) = what {
                return Err(NodeError::port(
                    port!(WriteClothUsd, cloth),
                    format!("frame {i}: {what} has a non-finite position; USD cannot hold it"),
                ));
            }
            pyrograph_usd::count_samples(&mut samples, state.positions.len(), i)
                .map_err(|m| NodeError::port(port!(WriteClothUsd, cloth), m))?;
            frames.push(state);
            ctx.frame_progress(i + 1, clip.len());
        }
        let bytes = stage_text(&frames, clip.fps(), &self.name)
            .map_err(|e| NodeError::port(path_port, format!("building the USD stage: {e:#}")))?;
        pyrograph_usd::write(&self.path, &bytes, overwrite).map_err(|m| NodeError::port(path_port, m))?;
        ctx.record_written(&self.path);
        Ok(WriteClothUsdOut { path: self.path, frames: clip.len() })
    }
}

/// The stage of `frames` as `.usda` text: one Mesh of all the flames' cloths.
pub fn stage_text(frames: &[Arc<ClothState>], fps: f64, name: &str) -> anyhow::Result<Vec<u8>> {
    let stage = pyrograph_usd::new_stage(frames.len(), fps)?;
    let prim = format!("/World/{name}");
    define(&stage, &prim, "Mesh")?;
    uniform_token(&stage, &prim, "subdivisionScheme", "none")?;
    let points = attribute(&stage, &prim, "points", "point3f[]", false)?;
    let extent = attribute(&stage, &prim, "extent", "float3[]", false)?;
    let counts = attribute(&stage, &prim, "faceVertexCounts", "int[]", false)?;
    let indices = attribute(&stage, &prim, "faceVertexIndices", "int[]", false)?;
    let st = attribute(&stage, &prim, "primvars:st", "texCoord2f[]", true)?;
    let flame = attribute(&stage, &prim, "primvars:flame", "int[]", true)?;
    // Topology is written once when every frame shares it, else with each frame's points.
    let shape = |s: &ClothState| (s.width, s.height, s.flames());
    let constant = frames.windows(2).all(|w| shape(&w[0]) == shape(&w[1]));
    for (t, state) in frames.iter().enumerate() {
        let world = world_points(state);
        sample(&points, t, vec3s(&world))?;
        sample(&extent, t, extent_of(world.iter().map(|&p| (p, 0.0))))?;
        if !constant || t == 0 {
            // The default value when it holds for every frame, else a sample at this one.
            let put = |attr: &Attribute, value: Value| -> anyhow::Result<()> {
                if constant {
                    attr.clone().set(value)?;
                    Ok(())
                } else {
                    sample(attr, t, value)
                }
            };
            let grid = Grid::of(state);
            put(&counts, grid.counts)?;
            put(&indices, grid.indices)?;
            put(&flame, grid.flame)?;
            put(&st, grid.st)?;
        }
    }
    pyrograph_usd::finish(&stage)
}

/// Every mass in world space: its flame's root plus its local position (x right, y up, z +Z).
fn world_points(state: &ClothState) -> Vec<[f32; 3]> {
    let n = (state.width as usize * state.height as usize).max(1);
    state
        .positions
        .iter()
        .enumerate()
        .map(|(k, p)| {
            let r = state.roots.get(k / n).copied().unwrap_or_default();
            [r[0] + p[0], r[1] + p[1], r[2] + p[2]]
        })
        .collect()
}

/// The cloths' shared topology and per-mass primvars.
struct Grid {
    counts: Value,
    indices: Value,
    st: Value,
    flame: Value,
}

impl Grid {
    fn of(state: &ClothState) -> Grid {
        let (w, h) = (state.width as usize, state.height as usize);
        let (mut indices, mut st, mut flame) = (Vec::new(), Vec::new(), Vec::new());
        let cells = w.saturating_sub(1) * h.saturating_sub(1);
        for f in 0..state.flames() {
            let base = f * w * h;
            for y in 0..h {
                for x in 0..w {
                    let s = if w > 1 { x as f32 / (w - 1) as f32 } else { 0.5 };
                    let t = if h > 1 { y as f32 / (h - 1) as f32 } else { 0.0 };
                    st.push([s, t]);
                    flame.push(i32::try_from(f).unwrap_or(i32::MAX));
                }
            }
            for y in 0..h.saturating_sub(1) {
                for x in 0..w.saturating_sub(1) {
                    // Counter-clockwise seen from +Z (USD's default right-handed orientation).
                    let at = |x: usize, y: usize| i32::try_from(base + y * w + x).unwrap_or(i32::MAX);
                    indices.extend([at(x, y), at(x + 1, y), at(x + 1, y + 1), at(x, y + 1)]);
                }
            }
        }
        Grid {
            counts: Value::IntVec(vec![4; cells * state.flames()]),
            indices: Value::IntVec(indices),
            st: Value::Vec2fVec(st.into_iter().map(Into::into).collect()),
            flame: Value::IntVec(flame),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn state(t: f32) -> Arc<ClothState> {
        // Two flames of 3 × 2 masses.
        let grid: Vec<[f32; 3]> = (0..6).map(|k| [(k % 3) as f32 * 0.5, (k / 3) as f32 + t, 0.0]).collect();
        Arc::new(ClothState {
            width: 3,
            height: 2,
            roots: vec![[0.0, 0.0, 0.0], [10.0, 0.0, 0.0]],
            seeds: vec![1, 2],
            positions: grid.iter().chain(&grid).copied().collect(),
            time: t,
        })
    }

    #[test]
    fn the_cloths_are_one_mesh_of_quads_with_moving_points() {
        let text = String::from_utf8(stage_text(&[state(0.0), state(0.25)], 24.0, "cloth").unwrap()).unwrap();
        for needle in [
            "def Mesh \"cloth\"",
            // 2 × 1 cells a flame, two flames, constant topology: written once.
            "int[] faceVertexCounts = [4, 4, 4, 4]",
            "int[] faceVertexIndices = [0, 1, 4, 3, 1, 2, 5, 4, 6, 7, 10, 9, 7, 8, 11, 10]",
            "texCoord2f[] primvars:st = [(0.0, 0.0), (0.5, 0.0), (1.0, 0.0), (0.0, 1.0)",
            // The second flame sits at its root, 10 along x; its top row moves up with time.
            "(10.0, 1.25, 0.0)",
            "uniform token subdivisionScheme = \"none\"",
        ] {
            assert!(text.contains(needle), "{needle} missing in\n{text}");
        }
    }
}
