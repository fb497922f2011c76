//! Surface char (Perry 1994 §3.4.1) and glow (§4.6): a fuzzy, dark, translucent disc lying on the
//! surface wherever a flame died, optionally starting red-hot and fading to char; the
//! `particles.char` node.

use std::sync::Arc;

use glam::Vec3;
use pyrograph_core::declare::Cook;
use pyrograph_core::{CookCtx, NodeError};

use crate::flame::unit_random;
use crate::types::SpreadState;
use pyrograph_render::{Particle, Particles};

pyrograph_core::ports! {
    /// Look of the char marks: the ports of `particles.char` after its input.
    #[derive(PartialEq)]
    pub struct CharParams {
        /// Disc radius in world units.
        #[range(0.0, 1e6)]
        size: f32 = 0.05,
        /// Random per-mark radius variation.
        #[range(0.0, 1.0)]
        size_jitter: f32 = 0.4,
        /// Char colour and opacity.
        color: [f32; 4] = [0.03, 0.02, 0.015, 0.8],
        /// Start red-hot and fade to char (§4.6).
        glow: bool = true,
        /// Glow colour and opacity when the flame has just died.
        glow_color: [f32; 4] = [1.0, 0.28, 0.04, 0.9],
        /// Seconds for the glow to fade to char.
        #[range(0.0, 1e4)]
        glow_time: f32 = 1.5,
        /// Seconds over which a new mark fades in.
        #[range(0.0, 1e4)]
        fade_in: f32 = 0.3,
        /// Lift off the surface along the normal.
        #[range(0.0, 1e3)]
        offset: f32 = 0.002,
        /// Seed of the size variation.
        #[range(0, u32::MAX)]
        seed: u32 = 0,
    }
}

fn smoothstep(x: f32) -> f32 {
    let x = x.clamp(0.0, 1.0);
    x * x * (3.0 - 2.0 * x)
}

/// The colour (straight RGBA) of a mark of `age` seconds.
pub fn char_color(age: f32, p: &CharParams) -> [f32; 4] {
    let base = if p.glow && p.glow_time > 0.0 {
        let t = smoothstep(age / p.glow_time);
        // This form is exactly `color` once the glow is over (t = 1), not merely close to it.
        std::array::from_fn(|c| p.glow_color[c] * (1.0 - t) + p.color[c] * t)
    } else {
        p.color
    };
    let fade = if p.fade_in > 0.0 { (age / p.fade_in).clamp(0.0, 1.0) } else { 1.0 };
    [base[0], base[1], base[2], base[3] * fade]
}

/// Char discs for `state`'s marks: particles with the (lifted) position, the surface normal in
/// `velocity`, radius in `size`, colour at the centre and a transparent rim (fuzzy), age in `weight`.
pub fn char_particles(state: &SpreadState, p: &CharParams) -> Particles {
    let particles = state
        .char_marks
        .iter()
        .enumerate()
        .map(|(k, m)| {
            let n = Vec3::from_array(m.normal).normalize_or_zero();
            let r = p.size * (1.0 + p.size_jitter.clamp(0.0, 1.0) * (2.0 * unit_random(p.seed, k, 31) - 1.0));
            let center = char_color(m.age, p);
            Particle {
                position: (Vec3::from_array(m.position) + n * p.offset).to_array(),
                velocity: n.to_array(),
                size: [r, r],
                center,
                edge: [center[0], center[1], center[2], 0.0],
                weight: m.age,
                group: k as u32,
            }
        })
        .collect();
    Particles { particles, sides: 12, time: state.time, trails: false }
}

pyrograph_core::node! {
    /// Surface char (Perry 1994 §3.4.1) with optional glow (§4.6): a fuzzy, dark, translucent disc lies on the
    /// surface where each flame root died, blending with the shaded object beneath; with glow it starts red-hot
    /// and fades to char over glow_time. Output particles carry the surface normal in `velocity`;
    /// particles.render_fire draws them flat on the surface. Connect the Clip<SpreadState> of
    /// particles.fire_spread to get a clip.
    #[node("particles.char", "Particles", PerFrame)]
    pub struct Char {
        /// Spread state (particles.fire_spread).
        spread: Arc<SpreadState>,
        /// The look of the marks.
        look: CharParams,
    }
    /// Char discs.
    -> char: Arc<Particles>
}

impl Cook for Char {
    fn cook(self, _: &CookCtx) -> Result<Arc<Particles>, NodeError> {
        Ok(Arc::new(char_particles(&self.spread, &self.look)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::types::CharMark;

    #[test]
    fn glow_starts_red_and_fades_to_translucent_char() {
        let p = CharParams::default();
        let young = char_color(0.31, &p);
        let old = char_color(10.0, &p);
        assert!(young[0] > 0.8 && young[1] < 0.4, "{young:?}");
        assert_eq!(old, p.color);
        assert!(old[3] < 1.0, "char is translucent");
        assert_eq!(char_color(0.0, &p)[3], 0.0, "a new mark fades in");
        let cold = CharParams { glow: false, ..p };
        assert_eq!(char_color(5.0, &cold), cold.color);
    }

    #[test]
    fn one_fuzzy_disc_per_mark_lifted_along_the_normal() {
        let state = SpreadState {
            char_marks: vec![CharMark { position: [0.0, 0.5, 0.0], normal: [0.0, 1.0, 0.0], age: 3.0 }; 3],
            ..SpreadState::default()
        };
        let out = char_particles(&state, &CharParams::default());
        assert_eq!(out.particles.len(), 3);
        for q in &out.particles {
            assert!((q.position[1] - 0.502).abs() < 1e-6);
            assert_eq!(q.edge[3], 0.0);
            assert!(q.size[0] > 0.0);
        }
    }
}
