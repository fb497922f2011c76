//! Fuzzy particles on the scanline path against their definition, a fan of Gouraud triangles.

use glam::{Vec2, Vec3};

use super::support::{screen_view, sv};
use crate::raster::{Blend, DrawList, Vertex, render};

#[test]
fn fan_triangles_share_edges_without_double_blending() {
    let view = screen_view(64, 64);
    let mut list = DrawList::new(&view);
    let c = [0.1, 0.1, 0.1, 1.0];
    list.particle(Vec3::ZERO, Vec2::splat(1.0), 20, c, c, Blend::Additive);
    let fb = render(&view, &[list], [0.0; 4]);
    let mut covered = 0;
    for y in 0..64 {
        for x in 0..64 {
            let p = fb.premultiplied(x, y);
            assert!(p[0] == 0.0 || (p[0] - 0.1).abs() < 1e-6, "pixel ({x}, {y}) = {p:?}");
            covered += (p[0] > 0.0) as usize;
        }
    }
    // A 20-gon of radius 1 at distance 5 with a 60° field of view: about π·11.1² pixels.
    assert!((300..420).contains(&covered), "{covered}");
}

/// The same particle drawn through the scanline fast path and as 20 screen-space Gouraud
/// triangles (the definition): same pixels, same colours.
#[test]
fn scanline_particles_match_their_fan_of_triangles() {
    let view = screen_view(120, 90);
    let cases = [
        (Vec3::new(0.0, 0.0, 0.0), Vec2::new(1.0, 0.4), Blend::Additive),
        (Vec3::new(-2.9, 1.0, 0.5), Vec2::new(0.8, 1.3), Blend::Over),
        (Vec3::new(3.4, -1.2, -1.0), Vec2::new(1.07, 0.032), Blend::Additive),
        (Vec3::new(1.0, 1.5, 2.0), Vec2::new(0.05, 0.05), Blend::Additive),
    ];
    let (cc, ec) = ([1.0, 0.8, 0.3, 0.9], [0.6, 0.1, 0.0, 0.0]);
    for (center, half, blend) in cases {
        let mut fast = DrawList::new(&view);
        fast.particle(center, half, 20, cc, ec, blend);
        assert_eq!(fast.fans.len(), 1, "{center} takes the scanline path");
        let mut slow = DrawList::new(&view);
        let (r, u) = view.camera().billboard_axes(center);
        let s = |p: Vec3, c: [f32; 4]| {
            let q = view.project(p).unwrap();
            sv(q.x, q.y, q.z, c)
        };
        for k in 0..20 {
            let at = |k: usize| {
                let a = std::f32::consts::TAU * (k % 20) as f32 / 20.0;
                center + r * (half.x * a.cos()) + u * (half.y * a.sin())
            };
            slow.screen_triangle([s(center, cc), s(at(k), ec), s(at(k + 1), ec)], blend);
        }
        let (a, b) = (render(&view, &[fast], [0.0; 4]), render(&view, &[slow], [0.0; 4]));
        let (mut differ, mut lit) = (0, 0);
        for y in 0..90 {
            for x in 0..120 {
                let (p, q) = (a.premultiplied(x, y), b.premultiplied(x, y));
                lit += usize::from(q[3] > 0.0);
                if (p[3] > 0.0) != (q[3] > 0.0) {
                    differ += 1;
                } else {
                    for ch in 0..4 {
                        assert!((p[ch] - q[ch]).abs() < 2e-3, "{center}: ({x}, {y}) {p:?} vs {q:?}");
                    }
                }
            }
        }
        // Pixel centres exactly on an edge may fall either way.
        assert!(differ <= 2, "{center}: {differ} of {lit} pixels covered by one and not the other");
        assert!(lit > 0 || half.y < 0.1, "{center}: draws something");
    }
}

#[test]
fn particles_clipped_by_the_viewport_and_hidden_by_opaque_geometry() {
    let view = screen_view(64, 64);
    let c = [1.0, 1.0, 1.0, 1.0];
    // Half off the left side of the view: still a disc, brightest at the centre.
    let mut list = DrawList::new(&view);
    let centre = Vec3::new(-2.9, 0.0, 0.0);
    list.particle(centre, Vec2::splat(1.0), 20, c, [0.0, 0.0, 0.0, 0.0], Blend::Additive);
    let fb = render(&view, &[list], [0.0; 4]);
    let p = view.project(centre).unwrap();
    let (row, x_in) = (p.y as u32, (p.x.max(0.0) as u32).min(63));
    assert!(fb.premultiplied(0, row)[0] > 0.3, "{:?}", fb.premultiplied(0, row));
    assert!(fb.premultiplied(0, row)[0] <= fb.premultiplied(x_in, row)[0] + 1e-6);
    // Behind an opaque wall nothing shows; in front of it, everything does.
    for (z, seen) in [(-1.0, false), (1.0, true)] {
        let mut wall = DrawList::new(&view);
        let red = [1.0, 0.0, 0.0, 1.0];
        wall.triangle(
            [
                Vertex::new(Vec3::new(-9.0, -9.0, 0.0), red),
                Vertex::new(Vec3::new(9.0, -9.0, 0.0), red),
                Vertex::new(Vec3::new(0.0, 9.0, 0.0), red),
            ],
            Blend::Opaque,
        );
        wall.particle(Vec3::new(0.0, 0.0, z), Vec2::splat(0.5), 20, [0.0, 1.0, 0.0, 1.0], [0.0, 1.0, 0.0, 1.0], Blend::Additive);
        let fb = render(&view, &[wall], [0.0; 4]);
        assert_eq!(fb.premultiplied(32, 32)[1] > 0.5, seen, "particle at z = {z}");
    }
}
