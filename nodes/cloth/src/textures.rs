//! The eight built-in flame textures of the mass-spring flame project 2019 (§Textures, Figure 3:
//! "the 8 textures used"), generated procedurally rather than loaded from files: teardrop flames
//! whose edges are torn by fractal gradient noise, coloured by a black-body ramp, with alpha
//! falling to zero outside the flame so the rectangular cloth reads as a flame.

use std::sync::{Arc, OnceLock};

use noise::{Fbm, MultiFractal, NoiseFn, Perlin};
use pyrograph_core::{Channels, Image};

/// Number of built-in textures.
pub const BUILTIN_COUNT: usize = 8;
/// Width of a built-in texture in pixels.
pub const TEXTURE_WIDTH: u32 = 64;
/// Height of a built-in texture in pixels.
pub const TEXTURE_HEIGHT: u32 = 128;

fn ramp(i: f32) -> [f32; 3] {
    // Dark red → orange → yellow → near white, by intensity.
    let i = i.clamp(0.0, 1.0);
    [(i * 2.2).min(1.0), (i * 1.6 - 0.25).clamp(0.0, 1.0), (i * 2.0 - 1.2).clamp(0.0, 0.9)]
}

/// Built-in texture `index` (0..8): the same every call; varied width, tongues and turbulence.
pub fn flame_texture(index: usize) -> Image {
    let k = index % BUILTIN_COUNT;
    let fbm: Fbm<Perlin> = Fbm::new(101 + k as u32 * 7919).set_octaves(4).set_frequency(1.0);
    let width = 0.5 + 0.06 * (k % 3) as f64;
    let turbulence = 0.18 + 0.04 * (k % 4) as f64;
    let tongues = 2.0 + (k % 2) as f64;
    let (w, h) = (TEXTURE_WIDTH as usize, TEXTURE_HEIGHT as usize);
    let mut data = vec![0.0f32; w * h * 4];
    for y in 0..h {
        // v: 0 at the bottom of the texture (the pinned row), 1 at the top.
        let v = 1.0 - (y as f64 + 0.5) / h as f64;
        for x in 0..w {
            let u = (x as f64 + 0.5) / w as f64 - 0.5;
            let n = fbm.get([u * tongues, v * 3.0, k as f64 * 1.7]);
            // Teardrop half width: round base, widest low down, pointed tip.
            let s = (v * 1.08 + 0.04).clamp(0.0, 1.0);
            let half = width * (std::f64::consts::PI * s).sin().max(0.0).powf(0.55) * (1.0 - 0.55 * s);
            let du = u + turbulence * v * n;
            let d = if half > 1e-4 { du.abs() / half } else { 10.0 };
            let body = (1.0 - d * d) + 0.6 * turbulence * n - 0.35 * v;
            let i = (body * 1.5).clamp(0.0, 1.0) as f32;
            let core = ((1.0 - d * 1.6) * (1.0 - v)).clamp(0.0, 1.0) as f32;
            let c = ramp(0.55 * i + 0.6 * core);
            let px = &mut data[(y * w + x) * 4..(y * w + x) * 4 + 4];
            px.copy_from_slice(&[c[0], c[1], c[2], i.min(1.0)]);
        }
    }
    Image::from_vec(TEXTURE_WIDTH, TEXTURE_HEIGHT, Channels::Rgba, data)
        .unwrap_or_else(|| Image::new(TEXTURE_WIDTH, TEXTURE_HEIGHT, Channels::Rgba))
}

/// The eight built-in textures, generated once per process.
pub fn builtin_textures() -> &'static [Arc<Image>] {
    static TEXTURES: OnceLock<Vec<Arc<Image>>> = OnceLock::new();
    TEXTURES.get_or_init(|| (0..BUILTIN_COUNT).map(|k| Arc::new(flame_texture(k))).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn eight_distinct_flames_opaque_inside_and_clear_at_the_corners() {
        let t = builtin_textures();
        assert_eq!(t.len(), 8);
        for (k, img) in t.iter().enumerate() {
            assert_eq!(img.size(), (TEXTURE_WIDTH, TEXTURE_HEIGHT));
            assert_eq!(img.pixel(0, 0)[3], 0.0, "texture {k} top-left is transparent");
            let inside = img.pixel(TEXTURE_WIDTH / 2, TEXTURE_HEIGHT * 3 / 4);
            assert!(inside[3] > 0.8 && inside[0] > 0.5, "texture {k} is a flame near its base: {inside:?}");
            assert!(img.data().iter().all(|x| x.is_finite()));
        }
        assert_ne!(t[0].data(), t[1].data());
    }
}
