//! View and clipping: the camera and viewport that turn world geometry into pixels, and the
//! clipping of polygons against the near plane and the guard band in homogeneous space.

use glam::{Mat4, Vec2, Vec3, Vec4};

use super::{BAND_ROWS, MAX_SIZE};
use crate::camera::{Camera, CameraError, CameraField};

/// Guard band: geometry is clipped to `|x|, |y| <= GUARD * w` in clip space, which keeps every
/// screen coordinate small enough for exact 64-bit edge functions.
const GUARD: f32 = 8.0;

/// A camera and a viewport: everything needed to turn world geometry into pixels.
#[derive(Clone, Debug)]
pub struct View {
    pub(super) camera: Camera,
    pub(super) width: u32,
    pub(super) height: u32,
    pub(super) view_proj: Mat4,
}

impl View {
    /// A view of `width × height` pixels (each 1..=[`MAX_SIZE`]).
    pub fn new(camera: Camera, width: u32, height: u32) -> Result<Self, CameraError> {
        for (field, v) in [(CameraField::Width, width), (CameraField::Height, height)] {
            if v == 0 || v > MAX_SIZE {
                return Err(CameraError { field, message: format!("must be 1..={MAX_SIZE} pixels, got {v}") });
            }
        }
        let view_proj = camera.projection_matrix(width as f32 / height as f32) * camera.view_matrix();
        Ok(View { camera, width, height, view_proj })
    }

    /// The camera.
    pub fn camera(&self) -> &Camera {
        &self.camera
    }

    /// Width in pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in pixels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// Projection × view.
    pub fn view_proj(&self) -> Mat4 {
        self.view_proj
    }

    /// Number of bands of [`BAND_ROWS`] rows (the last may be shorter).
    pub(super) fn bands(&self) -> usize {
        (self.height as usize).div_ceil(BAND_ROWS)
    }

    /// Pixel coordinates and depth of a world point, `None` when it is not in front of the near plane.
    pub fn project(&self, p: Vec3) -> Option<Vec3> {
        let c = self.view_proj * p.extend(1.0);
        if c.z < 0.0 || c.w <= 0.0 {
            return None;
        }
        let s = self.to_screen(c);
        Some(Vec3::new(s.x, s.y, c.z / c.w))
    }

    /// Pixel coordinates of a clip-space point in front of the camera.
    pub(super) fn to_screen(&self, c: Vec4) -> Vec2 {
        let iw = 1.0 / c.w;
        Vec2::new((c.x * iw * 0.5 + 0.5) * self.width as f32, (0.5 - c.y * iw * 0.5) * self.height as f32)
    }
}

/// A vertex in clip space, before the perspective divide.
#[derive(Clone, Copy, Debug)]
pub(super) struct ClipVert {
    pub(super) pos: Vec4,
    pub(super) color: Vec4,
    pub(super) uv: Vec2,
}

impl ClipVert {
    /// The point a fraction `t` of the way from `self` to `o`, attributes included.
    fn lerp(&self, o: &ClipVert, t: f32) -> ClipVert {
        ClipVert { pos: self.pos.lerp(o.pos, t), color: self.color.lerp(o.color, t), uv: self.uv.lerp(o.uv, t) }
    }
}

/// The planes geometry is clipped against: near (`z >= 0`) and the guard band.
fn plane_distances(p: Vec4) -> [f32; 5] {
    [p.z, GUARD * p.w - p.x, GUARD * p.w + p.x, GUARD * p.w - p.y, GUARD * p.w + p.y]
}

/// Whether a clip-space point is inside every clipping plane (and in front of the camera).
pub(super) fn inside_all(p: Vec4) -> bool {
    plane_distances(p).iter().all(|d| *d >= 0.0) && p.w > 0.0
}

/// Sutherland–Hodgman clipping of a convex polygon against the near and guard-band planes.
pub(super) fn clip_polygon(mut poly: Vec<ClipVert>) -> Vec<ClipVert> {
    for plane in 0..5 {
        if poly.is_empty() {
            break;
        }
        let mut out = Vec::with_capacity(poly.len() + 2);
        for i in 0..poly.len() {
            let a = &poly[i];
            let b = &poly[(i + 1) % poly.len()];
            let da = plane_distances(a.pos)[plane];
            let db = plane_distances(b.pos)[plane];
            if da >= 0.0 {
                out.push(*a);
            }
            if (da >= 0.0) != (db >= 0.0) {
                out.push(a.lerp(b, da / (da - db)));
            }
        }
        poly = out;
    }
    poly
}
