//! Triangles, meshes, quads and clipping through draw lists.

use std::sync::Arc;

use glam::{Vec2, Vec3};
use pyrograph_core::{Channels, Image};

use super::support::{WHITE, screen_view, sv};
use crate::camera::Camera;
use crate::raster::{Blend, DrawList, Vertex, View, blend_pixel, render};

#[test]
fn one_triangle_covers_exactly_the_pixels_whose_centres_it_contains() {
    let view = screen_view(8, 8);
    let mut list = DrawList::new(&view);
    list.screen_triangle([sv(0.0, 0.0, 0.5, WHITE), sv(4.5, 0.0, 0.5, WHITE), sv(0.0, 4.5, 0.5, WHITE)], Blend::Over);
    let fb = render(&view, &[list], [0.0; 4]);
    let mut covered = 0;
    for y in 0..8 {
        for x in 0..8 {
            let a = fb.premultiplied(x, y)[3];
            assert_eq!(a, if x + y <= 3 { 1.0 } else { 0.0 }, "pixel ({x}, {y})");
            covered += (a > 0.0) as usize;
        }
    }
    assert_eq!(covered, 10);
}

#[test]
fn colour_at_the_centroid_is_the_mean_of_the_vertex_colours() {
    let view = screen_view(12, 12);
    let mut list = DrawList::new(&view);
    let (r, g, b) = ([1.0, 0.0, 0.0, 1.0], [0.0, 1.0, 0.0, 1.0], [0.0, 0.0, 1.0, 1.0]);
    list.screen_triangle([sv(1.5, 1.5, 0.5, r), sv(10.5, 1.5, 0.5, g), sv(1.5, 10.5, 0.5, b)], Blend::Over);
    let px = render(&view, &[list], [0.0; 4]).premultiplied(4, 4);
    for (ch, want) in [1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0, 1.0].iter().enumerate() {
        assert!((px[ch] - want).abs() < 1e-5, "channel {ch}: {px:?}");
    }
}

#[test]
fn world_triangle_facing_the_camera_interpolates_barycentrically() {
    let view = screen_view(101, 101);
    let mut list = DrawList::new(&view);
    let (p0, p1, p2) = (Vec3::new(-1.0, -1.0, 0.0), Vec3::new(1.0, -1.0, 0.0), Vec3::new(0.0, 1.0, 0.0));
    list.triangle(
        [Vertex::new(p0, [1.0, 0.0, 0.0, 1.0]), Vertex::new(p1, [0.0, 1.0, 0.0, 1.0]), Vertex::new(p2, [0.0, 0.0, 1.0, 1.0])],
        Blend::Over,
    );
    let s = view.project((p0 + p1 + p2) / 3.0).unwrap();
    let px = render(&view, &[list], [0.0; 4]).premultiplied(s.x as u32, s.y as u32);
    for ch in 0..3 {
        assert!((px[ch] - 1.0 / 3.0).abs() < 0.03, "{px:?}");
    }
}

#[test]
fn additive_blending_saturates_at_one_and_not_beyond() {
    let view = screen_view(4, 4);
    let mut list = DrawList::new(&view);
    let c = [0.7, 0.3, 0.1, 0.6];
    for _ in 0..2 {
        list.screen_triangle([sv(0.0, 0.0, 0.5, c), sv(4.0, 0.0, 0.5, c), sv(0.0, 4.0, 0.5, c)], Blend::Additive);
    }
    let once = {
        let mut l = DrawList::new(&view);
        l.screen_triangle([sv(0.0, 0.0, 0.5, c), sv(4.0, 0.0, 0.5, c), sv(0.0, 4.0, 0.5, c)], Blend::Additive);
        render(&view, &[l], [0.0; 4]).premultiplied(0, 0)
    };
    let twice = render(&view, &[list], [0.0; 4]).premultiplied(0, 0);
    let expect_once = [0.42, 0.18, 0.06, 0.6];
    let expect_twice = [0.84, 0.36, 0.12, 1.0];
    for ch in 0..4 {
        assert!((once[ch] - expect_once[ch]).abs() < 1e-6, "{once:?}");
        assert!((twice[ch] - expect_twice[ch]).abs() < 1e-6, "{twice:?}");
    }
    // Many more layers: every component stops at exactly 1.
    let mut many = DrawList::new(&view);
    for _ in 0..20 {
        many.screen_triangle([sv(0.0, 0.0, 0.5, c), sv(4.0, 0.0, 0.5, c), sv(0.0, 4.0, 0.5, c)], Blend::Additive);
    }
    assert_eq!(render(&view, &[many], [0.0; 4]).premultiplied(0, 0), [1.0, 1.0, 1.0, 1.0]);
    let mut d = [0.9, 0.2, 0.0, 0.5];
    blend_pixel(&mut d, [1.0, 1.0, 1.0, 1.0], Blend::Additive);
    assert_eq!(d, [1.0, 1.0, 1.0, 1.0]);
}

#[test]
fn depth_test_keeps_the_nearest_opaque_surface_in_either_order() {
    let view = screen_view(4, 4);
    let red = [1.0, 0.0, 0.0, 1.0];
    let green = [0.0, 1.0, 0.0, 1.0];
    let tri = |d: f32, c| [sv(-1.0, -1.0, d, c), sv(9.0, -1.0, d, c), sv(-1.0, 9.0, d, c)];
    for near_first in [true, false] {
        let mut list = DrawList::new(&view);
        if near_first {
            list.screen_triangle(tri(0.2, red), Blend::Opaque);
            list.screen_triangle(tri(0.5, green), Blend::Opaque);
        } else {
            list.screen_triangle(tri(0.5, green), Blend::Opaque);
            list.screen_triangle(tri(0.2, red), Blend::Opaque);
        }
        // Blended geometry behind the opaque surface is hidden, in front of it is seen,
        // even when submitted before the opaque surfaces.
        let mut glow = DrawList::new(&view);
        glow.screen_triangle(tri(0.8, [0.0, 0.0, 1.0, 1.0]), Blend::Additive);
        glow.screen_triangle(tri(0.1, [0.0, 0.5, 0.0, 1.0]), Blend::Additive);
        let fb = render(&view, &[glow, list], [0.0; 4]);
        assert_eq!(fb.premultiplied(1, 1), [1.0, 0.5, 0.0, 1.0], "near_first = {near_first}");
        assert_eq!(fb.depth(1, 1), 0.2);
    }
}

#[test]
fn a_mesh_draws_like_its_triangles() {
    let view = screen_view(40, 40);
    let (r, g, b) = ([1.0, 0.0, 0.0, 1.0], [0.0, 1.0, 0.0, 1.0], [0.0, 0.0, 1.0, 1.0]);
    let v = [
        Vertex::new(Vec3::new(-2.0, -2.0, 0.0), r),
        Vertex::new(Vec3::new(2.0, -2.0, 0.0), g),
        Vertex::new(Vec3::new(2.0, 2.0, 0.0), b),
        Vertex::new(Vec3::new(-2.0, 2.0, 0.0), g),
    ];
    let mut mesh = DrawList::new(&view);
    mesh.mesh(&v, &[[0, 1, 2], [0, 2, 3]], None, Blend::Over);
    let mut tris = DrawList::new(&view);
    tris.triangle([v[0], v[1], v[2]], Blend::Over);
    tris.triangle([v[0], v[2], v[3]], Blend::Over);
    assert_eq!(render(&view, &[mesh], [0.0; 4]), render(&view, &[tris], [0.0; 4]));
}

#[test]
fn billboards_face_the_camera_from_any_side() {
    let white = Arc::new(Image::from_vec(1, 1, Channels::Rgba, vec![1.0; 4]).unwrap());
    // Seen from +x, a 2 × 2 billboard at distance 10 through a 90° lens on 100 px is 10 × 10 px.
    let cam = Camera::new(Vec3::new(10.0, 0.0, 0.0), Vec3::ZERO, Vec3::Y, 90.0, 0.1, 100.0).unwrap();
    let view = View::new(cam, 100, 100).unwrap();
    let mut list = DrawList::new(&view);
    let t = list.add_texture(&white);
    list.billboard(Vec3::ZERO, Vec2::ONE, t, WHITE, Blend::Over);
    let fb = render(&view, &[list], [0.0; 4]);
    let covered: Vec<(u32, u32)> =
        (0..100).flat_map(|y| (0..100).map(move |x| (x, y))).filter(|&(x, y)| fb.premultiplied(x, y)[3] > 0.0).collect();
    assert_eq!(covered.len(), 100);
    assert!(covered.iter().all(|&(x, y)| (45..55).contains(&x) && (45..55).contains(&y)));
    // The same quad fixed in the xy plane is seen edge-on and covers nothing.
    let mut flat = DrawList::new(&view);
    let t = flat.add_texture(&white);
    let q = [Vec3::new(-1.0, 1.0, 0.0), Vec3::new(1.0, 1.0, 0.0), Vec3::new(1.0, -1.0, 0.0), Vec3::new(-1.0, -1.0, 0.0)];
    flat.textured_quad(q, t, WHITE, Blend::Over);
    let fb = render(&view, &[flat], [0.0; 4]);
    assert!((0..100).all(|y| (0..100).all(|x| fb.premultiplied(x, y)[3] == 0.0)));
}

#[test]
fn textured_quad_maps_the_texture_left_to_right() {
    let tex = Arc::new(Image::from_vec(2, 1, Channels::Rgba, vec![1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 1.0]).unwrap());
    let cam = Camera::new(Vec3::new(0.0, 0.0, 1.0), Vec3::ZERO, Vec3::Y, 90.0, 0.1, 10.0).unwrap();
    let view = View::new(cam, 20, 20).unwrap();
    let mut list = DrawList::new(&view);
    let t = list.add_texture(&tex);
    let q = [Vec3::new(-1.0, 1.0, 0.0), Vec3::new(1.0, 1.0, 0.0), Vec3::new(1.0, -1.0, 0.0), Vec3::new(-1.0, -1.0, 0.0)];
    list.textured_quad(q, t, WHITE, Blend::Over);
    let img = render(&view, &[list], [0.0; 4]).to_image();
    assert_eq!(img.pixel(1, 10), &[1.0, 0.0, 0.0, 1.0]);
    assert_eq!(img.pixel(18, 10), &[0.0, 0.0, 1.0, 1.0]);
}

#[test]
fn geometry_through_the_near_plane_is_clipped_not_dropped() {
    let view = screen_view(32, 32);
    let mut list = DrawList::new(&view);
    // From behind the camera to far in front of it.
    let c = [1.0, 1.0, 1.0, 1.0];
    list.triangle(
        [
            Vertex::new(Vec3::new(-1.0, -0.5, 10.0), c),
            Vertex::new(Vec3::new(1.0, -0.5, 10.0), c),
            Vertex::new(Vec3::new(0.0, -0.5, -20.0), c),
        ],
        Blend::Over,
    );
    let fb = render(&view, &[list], [0.0; 4]);
    let covered = (0..32).flat_map(|y| (0..32).map(move |x| (x, y))).filter(|&(x, y)| fb.premultiplied(x, y)[3] > 0.0).count();
    assert!(covered > 0 && covered < 32 * 32, "{covered}");
    assert!(view.project(Vec3::new(0.0, 0.0, 6.0)).is_none());
}
