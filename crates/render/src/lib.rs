//! pyrograph-render: a small software rasterizer shared by the particle, fire-spread and cloth
//! nodes. Perspective [`Camera`] (position, target, up, vertical field of view, near/far),
//! Gouraud-shaded triangles with per-vertex straight RGBA, [`Blend::Additive`] (saturating at
//! 1, as Perry 1994 §3.2.2 renders flames), [`Blend::Over`], a depth test for [`Blend::Opaque`]
//! meshes, textured quads, camera-facing billboards and fuzzy N-gon particles (Perry §3.2.1).
//! The output is a [`pyrograph_core::Image`] (RGBA, straight alpha); the crate knows nothing of
//! the node registry.
//!
//! Why hand-written rather than `euc`: the flame workload is hundreds of thousands of tiny
//! triangles per frame (1,000 flames × 25 particles × 20 triangles) whose cost is per-triangle
//! setup, plus blend modes (saturating additive in a premultiplied framebuffer) and an
//! order-preserving parallel split that `euc`'s generic pipeline does not offer. Here a fuzzy
//! particle is projected once (centre plus two axes, projection being linear in homogeneous
//! coordinates), stored as one triangle fan, binned into row bands, and rasterized with exact
//! 64-bit fixed-point edge functions, bands in parallel with rayon. Rasterization is
//! half-space (edge function) over each triangle's bounding box clipped to the band, with the
//! top-left fill rule so shared edges are drawn once; geometry is clipped against the near
//! plane and a guard band in homogeneous space.
//!
//! ```
//! use glam::Vec3;
//! use pyrograph_render::{render, Blend, Camera, DrawList, View};
//! let cam = Camera::new(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, Vec3::Y, 45.0, 0.1, 100.0).unwrap();
//! let view = View::new(cam, 64, 48).unwrap();
//! let mut list = DrawList::new(&view);
//! list.particle(Vec3::ZERO, glam::Vec2::splat(0.5), 20, [1.0, 0.8, 0.3, 1.0], [1.0, 0.2, 0.0, 0.0], Blend::Additive);
//! let image = render(&view, &[list], [0.0, 0.0, 0.0, 1.0]).to_image();
//! assert_eq!(image.size(), (64, 48));
//! ```
#![deny(missing_docs)]

pub mod camera;
pub mod particles;
pub mod ports;
pub mod raster;

pub use camera::{Camera, CameraError};
pub use particles::{Particle, Particles};
pub use raster::{
    BAND_ROWS, Blend, DrawList, Framebuffer, ScreenVertex, TextureId, Vertex, View, blend_pixel, render, render_image,
    sample_bilinear,
};
