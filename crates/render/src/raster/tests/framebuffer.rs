//! The frame and its conversion to straight alpha.

use std::mem::MaybeUninit;

use glam::{Vec2, Vec3};
use pyrograph_testing::lcg;

use super::support::{screen_view, sv};
use crate::raster::framebuffer::{straight, write_straight, write_straight_uninit};
use crate::raster::{Blend, DrawList, Vertex, render, render_image};

#[test]
fn render_image_equals_the_framebuffer_converted() {
    let view = screen_view(50, 37);
    let mut list = DrawList::new(&view);
    list.particle(Vec3::ZERO, Vec2::new(1.5, 1.0), 20, [1.0, 0.7, 0.2, 0.8], [0.8, 0.2, 0.0, 0.0], Blend::Additive);
    let g = [0.2, 0.3, 0.1, 1.0];
    let verts = [
        Vertex::new(Vec3::new(-3.0, -1.0, -2.0), g),
        Vertex::new(Vec3::new(3.0, -1.0, -2.0), g),
        Vertex::new(Vec3::new(3.0, -1.0, 2.0), g),
        Vertex::new(Vec3::new(-3.0, -1.0, 2.0), g),
    ];
    list.mesh(&verts, &[[0, 1, 2], [0, 2, 3], [0, 9, 2]], None, Blend::Opaque);
    let lists = [list];
    let bg = [0.0, 0.0, 0.1, 0.5];
    assert_eq!(render_image(&view, &lists, bg), render(&view, &lists, bg).to_image());
}

#[test]
fn the_vectorized_straight_alpha_conversion_is_bit_identical_to_the_scalar_one() {
    // Ordinary, saturated, over-bright, transparent, negative, tiny and NaN samples, in every
    // channel, and an odd count so the scalar remainder runs too.
    let special = [0.0, -0.0, 1.0, 0.5, 1.5, 1e-30, -0.25, 0.999_999_9, f32::NAN, f32::INFINITY];
    let mut seed = 3u64;
    let pick = |s: &mut u64| {
        let r = lcg(s);
        if r < 0.4 { special[(lcg(s) * special.len() as f32) as usize % special.len()] } else { 1.2 * lcg(s) }
    };
    let color: Vec<[f32; 4]> = (0..4001).map(|_| [pick(&mut seed), pick(&mut seed), pick(&mut seed), pick(&mut seed)]).collect();
    let mut out = vec![0.0f32; 4 * color.len()];
    write_straight(&color, &mut out);
    let mut uninit = vec![MaybeUninit::new(7.0f32); 4 * color.len()];
    write_straight_uninit(&color, &mut uninit);
    for (i, p) in color.iter().enumerate() {
        let want = straight(*p).map(f32::to_bits);
        assert_eq!(out[4 * i..4 * i + 4].iter().map(|v| v.to_bits()).collect::<Vec<_>>(), want, "pixel {i}: {p:?}");
        // SAFETY: `write_straight_uninit` wrote every sample (and they started initialised).
        let got: Vec<u32> = uninit[4 * i..4 * i + 4].iter().map(|v| unsafe { v.assume_init() }.to_bits()).collect();
        assert_eq!(got, want, "pixel {i}: {p:?}");
    }
}

#[test]
fn additive_light_over_black_round_trips_through_straight_alpha() {
    let view = screen_view(2, 2);
    let mut list = DrawList::new(&view);
    let c = [1.0, 0.5, 0.25, 0.5];
    list.screen_triangle([sv(-1.0, -1.0, 0.5, c), sv(5.0, -1.0, 0.5, c), sv(-1.0, 5.0, 0.5, c)], Blend::Additive);
    list.screen_triangle([sv(-1.0, -1.0, 0.5, c), sv(5.0, -1.0, 0.5, c), sv(-1.0, 5.0, 0.5, c)], Blend::Additive);
    let fb = render(&view, &[list], [0.0; 4]);
    assert_eq!(fb.premultiplied(0, 0), [1.0, 0.5, 0.25, 1.0]);
    assert_eq!(fb.to_image().pixel(0, 0), &[1.0, 0.5, 0.25, 1.0]);
}
