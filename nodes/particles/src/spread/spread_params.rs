//! The parameters of Perry's fire spread ([`SpreadParams`], Perry 1994 §3.3–3.4, Table 3.1): the
//! ports of `particles.fire_spread` after its inputs, frames, fps and substeps.

// The port `K` is Perry's global time scale K; the field carries its name.
#![allow(non_snake_case)]

use pyrograph_core::declare::Anim;

pyrograph_core::ports! {
    /// Parameters of the spread (Perry 1994 §3.3–3.4, Table 3.1): the ports of
    /// `particles.fire_spread` after its inputs, frames, fps and substeps.
    #[derive(PartialEq)]
    pub struct SpreadParams {
        /// Opposed-flow heat flux q_o (footnote 10: 0.09).
        #[range(0.0, 10.0)]
        q_o: f32 = 0.09,
        /// Concurrent-flow heat flux q_c (footnote 10: 0.13).
        #[range(0.0, 10.0)]
        q_c: f32 = 0.13,
        /// Global time scale K of eq. 3.4 (Table 3.1): lower spreads faster; sampled at every step.
        #[range(0.004, 0.4)]
        K: Anim<f32> = Anim::constant(0.4),
        /// Curvature distance d_t (Table 3.1).
        #[range(0.01, 0.5)]
        d_t: f32 = 0.05,
        /// Use the curvature ramp of eq. 3.4 (off: flat speed everywhere).
        curvature: bool = true,
        /// Control point separation d_s (Table 3.1).
        #[range(0.01, 0.2)]
        d_s: f32 = 0.05,
        /// Flame drop distance d_d (Table 3.1).
        #[range(0.01, 1.0)]
        d_d: f32 = 0.05,
        /// Flame lifetime l_f in frames (Table 3.1).
        #[range(1, 1000)]
        lifetime: u32 = 48,
        /// Random per-flame lifetime variation.
        #[range(0.0, 1.0)]
        lifetime_jitter: f32 = 0.3,
        /// Control points of each ignition ring (footnote 13: eight or more).
        #[range(8, 4096)]
        points: usize = 16,
        /// No points are inserted beyond this many.
        #[range(8, 10_000_000)]
        max_points: usize = 200_000,
        /// Prevent double burning by the segment test of Figure 3-9 (off for planar cases).
        double_burn: bool = true,
        /// Seed of the per-flame lifetime variation.
        #[range(0, u32::MAX)]
        seed: u32 = 0,
    }
}
