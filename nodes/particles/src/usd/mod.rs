//! `particles.write_usd`: particles over time as a USD stage, so Houdini, Blender, Unreal or any
//! USD reader can render Perry's flames and embers with its own lights and camera, or place them in
//! a scene: one `UsdGeomPoints` prim with a time sample per frame.

use std::sync::Arc;

use pyrograph_core::{Clip, ClipOf, Cook, CookCtx, NodeError, OutputPath, PortType, port};
use pyrograph_render::particles::Particles;

use crate::types::{Mesh, SpreadState};
use pyrograph_usd::TargetError;

mod scene;

/// An empty spread clip: the default of the optional `spread` input.
fn no_spread() -> ClipOf<Arc<SpreadState>> {
    ClipOf::new(Clip::from_frames(PortType::of::<SpreadState>(), 0.0, Vec::new()))
}

pyrograph_core::node! {
    /// Writes particles over time as a USD stage: one UsdGeomPoints prim sampled at every frame (Perry 1994 §3.2.1 particles, for DCCs).
    ///
    /// `/World/<name>` holds `points`, `widths` (twice the particles' half width), `extent`, and the primvars
    /// `displayColor` and `displayOpacity` (the centre colour), `age` (the particle's weight: its age in
    /// steps for flame particles) and `flame` (which flame or group it belongs to), all per point ("vertex")
    /// and sampled at time codes 0, 1, … (one per frame; `timeCodesPerSecond` is the clip's rate). A connected
    /// `mesh` becomes the Mesh `/World/mesh` (triangles, no subdivision); a connected `spread` (Perry §3.3–3.4)
    /// the BasisCurves `/World/front` (the burning boundary, linear, closed loops repeated to their start) and
    /// the Points `/World/roots` (live flame roots with their `age` in seconds), sampled per frame. The stage
    /// says `upAxis = "Y"`, `metersPerUnit = 1`. `.usda` and `.usd` are written as text (binary `.usdc`
    /// is refused: convert with usdcat); the file is written atomically and never replaces one unless
    /// `overwrite` is on.
    #[node("particles.write_usd", "Particles", Sink)]
    pub struct WriteUsd {
        /// The particles over time (particles.particle_flame, particles.embers).
        particles: ClipOf<Arc<Particles>>,
        /// A mesh to place with them (the burning object, the logs; particles.mesh_load); default none.
        mesh: Arc<Mesh> = Arc::new(Mesh::default()),
        /// A fire spreading over that mesh (particles.fire_spread): its front and flame roots per frame; default none.
        spread: ClipOf<Arc<SpreadState>> = no_spread(),
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

impl Cook for WriteUsd {
    fn cook(self, ctx: &CookCtx) -> Result<WriteUsdOut, NodeError> {
        let path_port = port!(WriteUsd, path);
        let overwrite = self.overwrite || ctx.settings().overwrite;
        pyrograph_usd::check_target(&self.path, &self.name, overwrite).map_err(|e| match e {
            TargetError::Path(m) => NodeError::port(path_port, m),
            TargetError::Name(m) => NodeError::port(port!(WriteUsd, name), m),
            TargetError::Exists(m) => NodeError::port(port!(WriteUsd, overwrite), m),
        })?;
        let taken = [
            (scene::MESH, !self.mesh.triangles.is_empty()),
            (scene::FRONT, !self.spread.is_empty()),
            (scene::ROOTS, !self.spread.is_empty()),
        ];
        if let Some((part, _)) = taken.iter().find(|(part, used)| *used && *part == self.name) {
            return Err(NodeError::port(
                port!(WriteUsd, name),
                format!("'{part}' is the name of the {part} prim this stage also holds; give the particles another name"),
            ));
        }
        let clip = &self.particles;
        if !self.spread.is_empty() && (self.spread.fps() - clip.fps()).abs() > 1e-6 * clip.fps().abs().max(1.0) {
            return Err(NodeError::port(
                port!(WriteUsd, spread),
                format!(
                    "the fire spread runs at {} fps and the particles at {} fps; the stage has one time code per frame, \
                     so both must run at one rate",
                    self.spread.fps(),
                    clip.fps()
                ),
            ));
        }
        let mut samples = self.mesh.positions.len();
        let mut frames = Vec::with_capacity(clip.len());
        for i in 0..clip.len() {
            ctx.check_cancel()?;
            let value = clip.get(i, ctx)?;
            let particles = value
                .downcast::<Particles>()
                .ok_or_else(|| NodeError::port(port!(WriteUsd, particles), format!("frame {i} holds no particles")))?;
            WriteUsd::check_finite(&particles, i)?;
            pyrograph_usd::count_samples(&mut samples, particles.particles.len(), i)
                .map_err(|m| NodeError::port(port!(WriteUsd, particles), m))?;
            frames.push(particles);
            ctx.frame_progress(i + 1, clip.len());
        }
        // The spread's frames past the particles' last would hold the flames still at their last
        // sample: the stage ends with the particles.
        let spread_frames = self.spread.len().min(clip.len());
        let mut fronts = Vec::with_capacity(spread_frames);
        for i in 0..spread_frames {
            ctx.check_cancel()?;
            let value = self.spread.get(i, ctx)?;
            let state = value
                .downcast::<SpreadState>()
                .ok_or_else(|| NodeError::port(port!(WriteUsd, spread), format!("frame {i} holds no fire spread")))?;
            let points = state.boundaries.iter().map(|b| b.len() + 1).sum::<usize>() + state.roots.len();
            pyrograph_usd::count_samples(&mut samples, points, i).map_err(|m| NodeError::port(port!(WriteUsd, spread), m))?;
            fronts.push(state);
        }
        let scene = scene::Scene { flames: &frames, name: &self.name, mesh: &self.mesh, spread: &fronts, fps: clip.fps() };
        let bytes = scene.text().map_err(|e| NodeError::port(path_port, format!("building the USD stage: {e:#}")))?;
        pyrograph_usd::write(&self.path, &bytes, overwrite).map_err(|m| NodeError::port(path_port, m))?;
        ctx.record_written(&self.path);
        Ok(WriteUsdOut { path: self.path, frames: clip.len() })
    }
}

impl WriteUsd {
    /// Refuses a frame USD cannot hold, naming the particle.
    fn check_finite(p: &Particles, frame: usize) -> Result<(), NodeError> {
        match p.particles.iter().position(|q| q.position.iter().chain(&q.size).any(|v| !v.is_finite())) {
            Some(k) => Err(NodeError::port(
                port!(WriteUsd, particles),
                format!("frame {frame}: particle {k} has a non-finite position or size; USD cannot hold it"),
            )),
            None => Ok(()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use pyrograph_core::Value;
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
        let text = String::from_utf8(
            scene::Scene { flames: &frames, name: "flames", mesh: &Mesh::default(), spread: &[], fps: 24.0 }.text().unwrap(),
        )
        .unwrap();
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
    fn a_mesh_and_a_spread_front_go_beside_the_flames() {
        use crate::types::FlameRoot;
        let mesh = Mesh {
            positions: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]],
            triangles: vec![[0, 1, 2], [1, 3, 2]],
            ..Default::default()
        };
        let state = |t: f32| {
            let root = FlameRoot { position: [0.5, 0.5, 0.0], age: t, ..Default::default() };
            let ring = vec![[0.4, 0.4, 0.0], [0.6, 0.4, 0.0], [0.5, 0.6, 0.0]];
            Arc::new(SpreadState {
                time: t,
                boundaries: vec![ring, vec![[0.0, 0.0, 0.0]]],
                roots: vec![root],
                ..Default::default()
            })
        };
        let spread = [state(0.0), state(0.5)];
        let frames = vec![frame(1, 0.0), frame(1, 1.0)];
        let scene = scene::Scene { flames: &frames, name: "flames", mesh: &mesh, spread: &spread, fps: 24.0 };
        let text = String::from_utf8(scene.text().unwrap()).unwrap();
        for needle in [
            "def Mesh \"mesh\"",
            "int[] faceVertexIndices = [0, 1, 2, 1, 3, 2]",
            "uniform token subdivisionScheme = \"none\"",
            "def BasisCurves \"front\"",
            "uniform token type = \"linear\"",
            // The closed ring comes back to its start; the one-point boundary is left out.
            "1.0: [4]",
            "def Points \"roots\"",
        ] {
            assert!(text.contains(needle), "{needle} missing in\n{text}");
        }
    }

    /// A spread state whose one ring has `points` points, at time `t`.
    fn spread_state(t: f32, points: usize) -> Arc<SpreadState> {
        let ring = (0..points).map(|k| [k as f32, 0.0, 0.0]).collect();
        Arc::new(SpreadState { time: t, boundaries: vec![ring], ..Default::default() })
    }

    /// The writer of `particles` (two frames at 24 fps) and `spread`, to a fresh path in the temp folder.
    fn writer(spread: ClipOf<Arc<SpreadState>>, tag: &str) -> WriteUsd {
        let frames = [frame(1, 0.0), frame(1, 1.0)].into_iter().map(Value::custom).collect();
        let path = std::env::temp_dir().join(format!("pyrograph-usd-{tag}-{}.usda", std::process::id()));
        let _ = std::fs::remove_file(&path);
        WriteUsd {
            particles: ClipOf::new(Clip::from_frames(PortType::of::<Particles>(), 24.0, frames)),
            mesh: Arc::new(Mesh::default()),
            spread,
            path: OutputPath(path),
            name: "flames".into(),
            overwrite: false,
        }
    }

    fn spread_clip(fps: f64, frames: usize) -> ClipOf<Arc<SpreadState>> {
        let states = (0..frames).map(|i| Value::custom(spread_state(i as f32 / 24.0, 3))).collect();
        ClipOf::new(Clip::from_frames(PortType::of::<SpreadState>(), fps, states))
    }

    #[test]
    fn a_spread_at_another_rate_is_refused_and_a_longer_one_ends_with_the_particles() {
        let e = writer(spread_clip(30.0, 2), "rate").cook(&CookCtx::default()).err().expect("refused").to_string();
        assert!(e.contains("30 fps") && e.contains("24 fps") && e.contains("spread"), "{e}");
        let w = writer(spread_clip(24.0, 5), "longer");
        let path = w.path.0.clone();
        let out = w.cook(&CookCtx::default()).expect("writes");
        let text = std::fs::read_to_string(&path).unwrap();
        std::fs::remove_file(&path).unwrap();
        assert_eq!(out.frames, 2);
        assert!(text.contains("endTimeCode = 1"), "the stage ends at the particles' last frame:\n{text}");
        assert!(!text.contains("2: ["), "no spread sample past the particles' last frame:\n{text}");
    }

    #[test]
    fn stages_past_the_point_sample_budget_are_refused_naming_the_frame() {
        let mut total = 0;
        assert!(pyrograph_usd::count_samples(&mut total, pyrograph_usd::MAX_POINT_SAMPLES, 0).is_ok());
        let e = pyrograph_usd::count_samples(&mut total, 1, 7).unwrap_err();
        assert!(e.contains("by frame 7") && e.contains("--frames"), "{e}");
        // Through the writer: a spread front of more points than the budget, refused on its port.
        let huge = ClipOf::new(Clip::from_frames(
            PortType::of::<SpreadState>(),
            24.0,
            vec![Value::custom(spread_state(0.0, pyrograph_usd::MAX_POINT_SAMPLES))],
        ));
        match writer(huge, "huge").cook(&CookCtx::default()) {
            Err(NodeError::Port { port, message, .. }) => {
                assert_eq!(port, "spread");
                assert!(message.contains("point samples"), "{message}");
            }
            other => panic!("{:?}", other.err()),
        }
    }

    #[test]
    fn numbers_usd_cannot_hold_are_refused() {
        let mut bad = (*frame(2, 0.0)).clone();
        bad.particles[1].position[0] = f32::NAN;
        let e = WriteUsd::check_finite(&bad, 4).unwrap_err().to_string();
        assert!(e.contains("frame 4: particle 1"), "{e}");
    }
}
