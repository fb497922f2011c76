//! Helpers shared by the rasterizer's tests.

use glam::Vec3;

use crate::camera::Camera;
use crate::raster::{ScreenVertex, View};

/// A view of `w × h` pixels from 5 units up the z axis, looking at the origin.
pub(super) fn screen_view(w: u32, h: u32) -> View {
    let cam = Camera::new(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, Vec3::Y, 60.0, 0.1, 100.0).unwrap();
    View::new(cam, w, h).unwrap()
}

/// A screen vertex without texture coordinates.
pub(super) fn sv(x: f32, y: f32, depth: f32, color: [f32; 4]) -> ScreenVertex {
    ScreenVertex { x, y, depth, color, uv: [0.0, 0.0] }
}

/// Opaque white.
pub(super) const WHITE: [f32; 4] = [1.0, 1.0, 1.0, 1.0];
