//! Grid strips draw exactly what the same triangles draw as a mesh.

use glam::Vec3;
use proptest::prelude::*;

use crate::camera::Camera;
use crate::raster::{Blend, DrawList, Framebuffer, Vertex, View, render};

/// A 96 × 64 view from `distance` units up the z axis, looking at the origin.
fn view(distance: f32) -> View {
    let cam = Camera::new(Vec3::new(0.0, 0.0, distance), Vec3::ZERO, Vec3::Y, 60.0, 0.1, 100.0).unwrap();
    View::new(cam, 96, 64).unwrap()
}

/// The triangles [`DrawList::strip`] documents for rows of `across`.
fn strip_triangles(rows: u32, across: u32) -> Vec<[u32; 3]> {
    let mut tris = Vec::new();
    for k in 0..rows - 1 {
        let (a, b) = (k * across, (k + 1) * across);
        for j in 0..across - 1 {
            tris.extend([[a + j, a + j + 1, b + j + 1], [a + j, b + j + 1, b + j]]);
        }
    }
    tris
}

/// `verts` drawn as a strip and as a mesh of its triangles, each after an opaque backdrop
/// triangle (so that depth is tested) and over a grey background.
fn both(view: &View, verts: &[Vertex], across: u32, blend: Blend) -> (Framebuffer, Framebuffer) {
    let draw = |as_strip: bool| {
        let mut list = backdrop_only(view);
        if as_strip {
            list.strip(verts, across, blend);
        } else {
            let rows = verts.len() as u32 / across;
            list.mesh(&verts[..(rows * across) as usize], &strip_triangles(rows, across), None, blend);
        }
        render(view, &[list], [0.1, 0.1, 0.1, 1.0])
    };
    (draw(true), draw(false))
}

fn assert_same(strip: &Framebuffer, mesh: &Framebuffer) {
    for (i, (s, m)) in strip.color.iter().zip(&mesh.color).enumerate() {
        assert_eq!(s.map(f32::to_bits), m.map(f32::to_bits), "pixel {i}: strip {s:?}, mesh {m:?}");
    }
    let (sd, md): (Vec<u32>, Vec<u32>) =
        (strip.depth.iter().map(|d| d.to_bits()).collect(), mesh.depth.iter().map(|d| d.to_bits()).collect());
    assert_eq!(sd, md, "depth");
}

/// A wiggling strip along y whose width, colour and depth vary along it; `fold` sends it back
/// over itself (overlapping segments), `z` moves it towards the camera.
fn wiggle(rows: usize, across: usize, seed: &[f32], fold: bool, z: f32) -> Vec<Vertex> {
    let mut verts = Vec::new();
    for k in 0..rows {
        let t = k as f32 / (rows - 1) as f32;
        let s = seed[k % seed.len()];
        let y = if fold { 2.0 * (t * 5.0).sin() } else { -2.2 + 4.4 * t };
        let (cx, w) = (0.6 * (t * 7.0 + s).sin(), 0.05 + 0.5 * s.abs());
        for j in 0..across {
            let u = j as f32 / (across - 1) as f32 - 0.5;
            let c = [s.abs(), 1.0 - u.abs(), t, (0.3 + 0.7 * (1.0 - 2.0 * u.abs())) * (0.5 + 0.5 * s.abs())];
            verts.push(Vertex::new(Vec3::new(cx + 2.0 * u * w, y + 0.1 * u * s, z + 0.3 * s * u), c));
        }
    }
    verts
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    #[test]
    fn a_strip_draws_what_its_triangles_draw_as_a_mesh(
        seed in prop::collection::vec(-1.0f32..1.0, 1..12),
        rows in 2usize..40,
        across in prop::sample::select(vec![2usize, 3, 5]),
        fold: bool,
        blend in prop::sample::select(vec![Blend::Additive, Blend::Over, Blend::Opaque]),
    ) {
        let view = view(5.0);
        let verts = wiggle(rows, across, &seed, fold, 0.0);
        let (strip, mesh) = both(&view, &verts, across as u32, blend);
        assert_same(&strip, &mesh);
    }
}

#[test]
fn a_strip_through_the_near_plane_is_clipped_as_its_mesh_is() {
    // The camera sits at z = 1: the strip's near end reaches past it and is clipped.
    let view = view(1.0);
    let verts: Vec<Vertex> = (0..20)
        .flat_map(|k| {
            let z = -3.0 + 0.25 * k as f32;
            [-0.4f32, 0.0, 0.4].map(|x| Vertex::new(Vec3::new(x, -0.3, z), [1.0, 0.6, 0.2, 0.7]))
        })
        .collect();
    let (strip, mesh) = both(&view, &verts, 3, Blend::Additive);
    assert!(strip.color.iter().any(|c| c[0] > 0.5), "the strip is drawn");
    assert_same(&strip, &mesh);
}

#[test]
fn short_or_ragged_strips_draw_only_whole_rows() {
    let view = view(5.0);
    let verts = wiggle(6, 3, &[0.5, -0.2], false, 0.0);
    // One row and a part of the next: nothing; rows and a stray vertex: the rows.
    let (strip, mesh) = both(&view, &verts[..4], 3, Blend::Over);
    assert_same(&strip, &mesh);
    assert!(strip.color == render(&view, &[backdrop_only(&view)], [0.1, 0.1, 0.1, 1.0]).color, "one row draws nothing");
    let (strip, mesh) = both(&view, &verts[..17], 3, Blend::Over);
    assert_same(&strip, &mesh);
    // Fewer than two vertices across: nothing, without a panic.
    let mut list = DrawList::new(&view);
    list.strip(&verts, 1, Blend::Over);
    list.strip(&verts, 0, Blend::Over);
    assert_eq!(list.primitive_count(), 0);
}

/// A list holding only the opaque backdrop triangle of [`both`].
fn backdrop_only(view: &View) -> DrawList {
    let mut list = DrawList::new(view);
    let back = [[-3.0, -3.0, -0.2], [3.0, -3.0, 0.3], [0.0, 3.0, -0.1]];
    list.triangle(back.map(|p| Vertex::new(Vec3::from_array(p), [0.2, 0.3, 0.4, 1.0])), Blend::Opaque);
    list
}
