//! Perry's fire spread over polygon meshes (Perry 1994 §3.3–3.4) and the `particles.fire_spread`
//! node: the spread's parameters ([`spread_params`]), the surface a front moves over
//! ([`surface`]), the front itself ([`front`]), the stepping cache behind the node's clip
//! ([`cache`]) and the node ([`node`]).
//!
//! The inception boundary is a counter-clockwise ring of spread control points per ignition
//! (burnt region on the left, seen from outside). Each point moves along its heading, in the
//! plane of its face, at the speed of eq. 3.4:
//!
//! `v_s = (1 + κ) · (A_o q_o + A_c q_c) / K`, with `A_o = 1`, `A_c = max(0, ĥ · û∞,face)`,
//!
//! where `û∞,face` is the normalized projection of the wind `u∞ = −k_g g + w_L` on the face and
//! `κ = (1 − d/d_t)·Θ/π` within `d_t` of an edge whose faces meet at the signed angle `Θ`
//! (positive on convex edges, negative on concave ones), else 0. Eq. 3.4 as printed multiplies by
//! the curvature coefficient, which would stop the spread on flat faces (Θ = 0); we apply it as a
//! relative change, which keeps the linear ramp to the edge and the preference for convex edges.
//! Speeds are in distance units per second. A point that would leave its face is split at the
//! edge and its heading rotated into the neighbour by the edge's pre-stored rotation (§3.3.2,
//! Figure 3-8); on a boundary edge it stops. Neighbours more than `d_s` apart get a new point
//! between them, placed by walking the surface and heading between its live neighbours' headings;
//! none is inserted that would head into the burnt side. With double-burn prevention on, a point
//! whose move (position at t−1 → t) meets another segment of the boundary at t−1 (or as proposed
//! at t) is not allowed to move and goes out (Figure 3-9), and so are two neighbours whose
//! segment turns over (they met) and a point that runs along its own segment. Segments and moves
//! bend where they cross an edge (Perry §4: geodesics, not chords). The test uses a uniform grid
//! of boundary segments, so a step is O(n) for n points. Runs of extinguished points are thinned
//! where that hardly changes the boundary, so stopped fronts do not pile up. Every point drops a
//! flame root each `d_d` it travels (§3.4): the face normal is the flame's initial direction, and
//! the root lives `l_f`; when it dies it leaves a char mark (§3.4.1).

pub mod cache;
pub mod front;
pub mod node;
pub mod spread_params;
pub mod surface;

pub use cache::SpreadSource;
pub use front::{ControlPoint, Ignition, Spread, SpreadError, spread_wind};
pub use node::{FireSpread, parse_ignitions};
pub use spread_params::SpreadParams;
pub use surface::Surface;

#[cfg(test)]
mod tests;
