//! The `particles.fire_spread` node: its ports (the [`SpreadParams`] group is the spread's
//! parameters), the `ignite` points, and the spread's errors mapped to the ports they are about.

use std::hash::{Hash, Hasher};
use std::sync::Arc;

use glam::Vec3;
use pyrograph_core::declare::Cook;
use pyrograph_core::fingerprint::Fingerprinter;
use pyrograph_core::value::{Place, Points};
use pyrograph_core::{AtPort, Clip, ClipOf, CookCtx, NodeError, PortType, Value, port};

use super::cache::SpreadSource;
use super::front::{Ignition, Spread, SpreadError};
use super::spread_params::SpreadParams;
use super::surface::Surface;
use crate::types::{Mesh, SpreadState, WindField};
use crate::wind::validate_wind;

pyrograph_core::node! {
    /// Perry's fire spread over a polygon mesh (Perry 1994 §3.3–3.4): each ignition starts a
    /// counter-clockwise ring of control points moving at v_s = (1 + κ)(A_o q_o + A_c q_c)/K (eq. 3.4;
    /// A_o = 1, A_c = max(0, heading · wind projected on the face), κ the curvature ramp (1 − d/d_t)Θ/π near
    /// edges, positive on convex edges) in the wind u∞ = −k_g g + w_L. Crossing an edge rotates the heading
    /// into the next face by the mesh's stored rotation (§3.3.2); a boundary edge stops the point. A new
    /// point is inserted where neighbours are more than d_s apart; with double_burn on, a point whose move
    /// crosses the boundary (Figure 3-9) goes out. Every point drops a flame root each d_d travelled, with
    /// the face normal as direction and lifetime l_f (§3.4); dead roots leave char marks (§3.4.1). Ranges
    /// of K, d_d, d_s, d_t and l_f are Table 3.1. Deterministic for a seed; the clip steps a cache.
    #[node("particles.fire_spread", "Particles", Simulation)]
    pub struct FireSpread {
        /// The mesh to burn (particles.mesh_load).
        mesh: Arc<Mesh>,
        /// External wind: convection −k_g g plus w_L (particles.wind_field).
        wind: Arc<WindField> = Arc::new(WindField::default()),
        /// Ignition points: `(x, y, z)` (the nearest surface point) or `face(F[, (b0, b1, b2)])`, each at time 0 or as `(seconds, point)`.
        ignite: Arc<Points> = Arc::new(Points::face(0)),
        /// Largest distance from an ignition position to the surface.
        #[range(0.0, 1e6)]
        snap: f32 = 0.05,
        /// Length and rate of the clip (`frames`, `fps`; speeds are per second).
        timeline: pyrograph_core::Timeline = pyrograph_core::Timeline { frames: 96, fps: 24.0 },
        /// Spread steps per frame.
        #[range(1, 64)]
        substeps: usize = 1,
        /// The spread.
        params: SpreadParams,
    }
    /// Per frame: boundary, live flame roots, extinguished points, char.
    -> spread: ClipOf<Arc<SpreadState>>
}

impl Cook for FireSpread {
    fn cook(self, _: &CookCtx) -> Result<ClipOf<Arc<SpreadState>>, NodeError> {
        let surface = Arc::new(Surface::new(&self.mesh).map_err(|m| NodeError::port(port!(FireSpread, mesh), m))?);
        validate_wind(&self.wind).at_port(port!(FireSpread, wind))?;
        self.params.validate(self.timeline.fps as f32).map_err(FireSpread::error)?;
        let ignitions = parse_ignitions(&self.ignite, &surface, self.snap).map_err(FireSpread::error)?;
        let (frames, fps, substeps) = (self.timeline.frames, self.timeline.fps, self.substeps);
        let mut h = Fingerprinter::new();
        "particles.fire_spread".hash(&mut h);
        Value::custom(self.mesh.clone()).hash_into(&mut h);
        Value::custom(self.wind.clone()).hash_into(&mut h);
        format!("{:?}{ignitions:?}", self.params).hash(&mut h);
        (frames, fps.to_bits(), substeps).hash(&mut h);
        let spread = Spread::new(surface, ignitions, self.params, fps as f32).map_err(FireSpread::error)?;
        let source = SpreadSource::new(spread, (*self.wind).clone(), frames, fps as f32, substeps);
        Ok(ClipOf::new(Clip::new(PortType::of::<SpreadState>(), fps, h.finish(), Arc::new(source))))
    }
}

impl FireSpread {
    /// The node error for a spread that cannot start: a parameter's error names its port, an
    /// ignition's names `ignite`.
    pub(crate) fn error(e: SpreadError) -> NodeError {
        match e {
            SpreadError::Param { param, message } => NodeError::port(param, message),
            SpreadError::Ignition(message) => NodeError::port(port!(FireSpread, ignite), message),
        }
    }
}

/// Resolves the `ignite` points on the surface: a position snaps to the nearest surface point
/// (an error farther than `snap`), a face must exist. Errors name the point, counted from 1.
pub fn parse_ignitions(points: &Points, surface: &Surface, snap: f32) -> Result<Vec<Ignition>, SpreadError> {
    let err = SpreadError::Ignition;
    let mut out = Vec::with_capacity(points.points().len());
    for (k, (time, place)) in points.points().iter().enumerate() {
        // The spread computes in f32; the document holds f64.
        let time = *time as f32;
        match place {
            Place::Face(face, bary) => {
                if *face as usize >= surface.len() {
                    return Err(err(format!("point {}: face {face} is past the mesh's {} faces", k + 1, surface.len())));
                }
                let bary = bary.map_or([1.0 / 3.0; 3], |b| b.map(|c| c as f32));
                out.push(Ignition { face: *face, bary, time });
            }
            Place::At(p) => {
                let p = Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32);
                let (face, bary, dist) = surface.nearest(p);
                if dist > snap {
                    return Err(err(format!(
                        "point {} at ({}, {}, {}) is off the mesh: the nearest surface point (face {face}) is {dist:.4} away, \
                         more than snap = {snap}; move it onto the surface or raise snap",
                        k + 1,
                        p.x,
                        p.y,
                        p.z
                    )));
                }
                out.push(Ignition { face, bary, time });
            }
        }
    }
    Ok(out)
}
