//! Procedural flame images for when no footage is at hand: the embedded demo, tests, previews.
//!
//! This is the classic noise-turbulence flame (Perlin 1985, "An image synthesizer", §fire): a
//! teardrop intensity field whose edge is displaced by fractal noise scrolling upward, mapped
//! through a black-body-like ramp. It is not one of the four papers' models; Perry's particle
//! flames (nodes/particles) and the learned flame model replace it where they apply.

use std::sync::Arc;

use noise::{Fbm, MultiFractal, NoiseFn, Perlin};
use pyrograph_core::fingerprint::Fingerprinter;
use pyrograph_core::{Channels, Clip, ClipOf, Cook, CookCtx, FrameSource, Image, NodeError, PortType, Value};
use rayon::prelude::*;

pyrograph_core::node! {
    /// An animated procedural flame: a teardrop whose edge is displaced by upward-scrolling fractal noise (Perlin
    /// 1985), coloured by a black-body ramp with alpha = intensity. For demos and tests when no footage is at hand;
    /// not one of the four papers' models.
    #[node("imaging.turbulence_flame", "Procedural", Source)]
    pub struct TurbulenceFlame {
        /// Image width in pixels.
        #[range(8, 8192)]
        width: u32 = 256,
        /// Image height in pixels.
        #[range(8, 8192)]
        height: u32 = 384,
        /// Length and rate of the clip (`frames`, `fps`).
        timeline: pyrograph_core::Timeline,
        /// Noise seed.
        #[range(0, u32::MAX)]
        seed: u32 = 1,
        /// Flame width at the base, fraction of the image width.
        #[range(0.05, 1.0)]
        base_width: f64 = 0.5,
        /// Flame height, fraction of the image height.
        #[range(0.1, 1.0)]
        height_fraction: f64 = 0.75,
        /// How strongly noise tears the flame's edge.
        #[range(0.0, 4.0)]
        turbulence: f64 = 0.9,
        /// Upward scroll of the noise, flame heights per second.
        #[range(0.0, 10.0)]
        speed: f64 = 1.2,
        /// Noise octaves (detail).
        #[range(1, 8)]
        octaves: usize = 5,
    }
    /// RGBA frames, straight alpha.
    -> clip: ClipOf<Arc<Image>>
}

/// Black → deep red → orange → yellow → near white: the colours of a hydrocarbon flame by temperature.
const RAMP: [(f32, [f32; 3]); 5] = [
    (0.0, [0.0, 0.0, 0.0]),
    (0.25, [0.45, 0.04, 0.0]),
    (0.5, [0.95, 0.32, 0.02]),
    (0.75, [1.0, 0.72, 0.18]),
    (1.0, [1.0, 0.97, 0.85]),
];

/// The flame colour at intensity `t` (0..1), linearly interpolated along [`RAMP`].
pub fn flame_ramp(t: f32) -> [f32; 3] {
    let t = t.clamp(0.0, 1.0);
    let i = RAMP.iter().position(|(p, _)| *p >= t).unwrap_or(RAMP.len() - 1).max(1);
    let ((p0, c0), (p1, c1)) = (RAMP[i - 1], RAMP[i]);
    let f = if p1 > p0 { (t - p0) / (p1 - p0) } else { 0.0 };
    [c0[0] + (c1[0] - c0[0]) * f, c0[1] + (c1[1] - c0[1]) * f, c0[2] + (c1[2] - c0[2]) * f]
}

impl TurbulenceFlame {
    /// Frame `frame` of the flame as straight-alpha RGBA (alpha = intensity).
    pub fn frame_image(&self, frame: usize) -> Image {
        let p = self;
        let fbm: Fbm<Perlin> = Fbm::new(p.seed).set_octaves(p.octaves.clamp(1, 8)).set_frequency(1.0);
        let t = frame as f64 / p.timeline.fps.max(1e-6);
        let (w, h) = (p.width as usize, p.height as usize);
        let mut data = vec![0.0f32; w * h * 4];
        data.par_chunks_mut(w * 4).enumerate().for_each(|(y, row)| {
            // v: 0 at the flame's base (near the bottom), 1 at its nominal tip.
            let v = ((h - 1 - y) as f64 / h as f64 - 0.16) / p.height_fraction;
            for (x, px) in row.chunks_exact_mut(4).enumerate() {
                let u = (x as f64 / w as f64 - 0.5) / p.base_width;
                let i = p.intensity(&fbm, u, v, t) as f32;
                let c = flame_ramp(i);
                px.copy_from_slice(&[c[0], c[1], c[2], i.min(1.0)]);
            }
        });
        Image::from_vec(p.width, p.height, Channels::Rgba, data).unwrap_or_else(|| Image::new(p.width, p.height, Channels::Rgba))
    }

    /// The flame's intensity (0..1) at `(u, v)` (across the base, up the height) at time `t`.
    fn intensity(&self, fbm: &Fbm<Perlin>, u: f64, v: f64, t: f64) -> f64 {
        let p = self;
        if !(-0.3..=1.8).contains(&v) {
            return 0.0;
        }
        // Noise sampled in a frame that scrolls upward, so features rise through the flame; it grows
        // with height, as real flames are laminar at the base and torn at the tip.
        let n = fbm.get([u * 2.0, (v - t * p.speed) * 2.4, t * 0.35]);
        let sway = 0.22 * v * v * fbm.get([0.0, t * 0.45, 7.3]);
        // A teardrop: round base, widest a quarter of the way up, pointed tip.
        let s = ((v + 0.2) / 1.2).clamp(0.0, 1.0);
        let half_width = 0.5 * (std::f64::consts::PI * s).sin().max(0.0).powf(0.6) * (1.0 - 0.45 * s);
        if half_width < 1e-3 {
            return 0.0;
        }
        let d = (u - sway).abs() / half_width;
        let edge = 1.0 - d * d;
        let body = edge + p.turbulence * n * (0.25 + v) - 0.45 * v.max(0.0);
        (body * 1.3).clamp(0.0, 1.0)
    }
}

/// The flame's frames, made on request.
struct FlameSource(TurbulenceFlame);

impl FrameSource for FlameSource {
    fn len(&self) -> usize {
        self.0.timeline.frames
    }
    fn frame(&self, index: usize, _ctx: &CookCtx) -> Result<Value, NodeError> {
        Ok(Value::Image(Arc::new(self.0.frame_image(index))))
    }
}

impl Cook for TurbulenceFlame {
    fn cook(self, _: &CookCtx) -> Result<ClipOf<Arc<Image>>, NodeError> {
        // Every parameter, the frame count included, is in the Debug text.
        let mut h = Fingerprinter::new();
        std::hash::Hash::hash(&format!("{self:?}"), &mut h);
        let fp = std::hash::Hasher::finish(&h);
        let clip = Clip::new(PortType::Image, self.timeline.fps, fp, Arc::new(FlameSource(self)));
        Ok(ClipOf::new(clip))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn small() -> TurbulenceFlame {
        TurbulenceFlame {
            width: 32,
            height: 48,
            timeline: pyrograph_core::Timeline { frames: 8, fps: 24.0 },
            seed: 3,
            base_width: 0.55,
            height_fraction: 0.8,
            turbulence: 0.9,
            speed: 1.2,
            octaves: 3,
        }
    }

    #[test]
    fn ramp_runs_from_black_to_near_white() {
        assert_eq!(flame_ramp(0.0), [0.0, 0.0, 0.0]);
        assert_eq!(flame_ramp(1.0), [1.0, 0.97, 0.85]);
        let mid = flame_ramp(0.5);
        assert!(mid[0] > mid[1] && mid[1] > mid[2], "orange at the middle: {mid:?}");
    }

    #[test]
    fn flame_is_bright_at_the_base_centre_and_dark_in_the_corners() {
        let img = small().frame_image(0);
        let alpha = |x, y| img.pixel(x, y)[3];
        assert!(alpha(16, 40) > 0.5, "base centre alpha {}", alpha(16, 40));
        assert_eq!(alpha(0, 0), 0.0);
        assert_eq!(alpha(31, 0), 0.0);
    }

    #[test]
    fn frames_are_deterministic_and_animated() {
        let p = small();
        assert_eq!(p.frame_image(5), p.frame_image(5));
        assert_ne!(p.frame_image(5), p.frame_image(6));
    }
}
