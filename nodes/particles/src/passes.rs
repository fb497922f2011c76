//! Compositing passes of the flame renderers (`particles.render_flames`, `particles.render_fire`):
//! which pass to draw, and the depth pass from the rasterizer's depth buffer.

use pyrograph_core::Image;
use pyrograph_render::{DrawList, View};

pyrograph_core::choice! {
    /// What a flame renderer draws: a compositor's pass.
    pub enum RenderPass {
        /// The whole frame.
        Beauty = "beauty",
        /// The flames (and sparks) alone on transparent black, hidden behind opaque geometry.
        Emission = "emission",
        /// The opaque geometry's distance along the view axis (gray, world units).
        Depth = "depth",
    }
}

/// The depth pass of `lists`: per pixel, the distance along the camera's view axis of the nearest
/// opaque surface, the far plane where there is none (a gray image).
pub fn depth_image(view: &View, lists: &[DrawList]) -> Image {
    let frame = pyrograph_render::render(view, lists, [0.0; 4]);
    let camera = view.camera();
    let (near, far) = (camera.near(), camera.far());
    Image::gray_from_fn(frame.width(), frame.height(), |x, y| {
        // The projection maps view depth z (near..far) to d = far (z − near) / (z (far − near)).
        let d = frame.depth(x, y).clamp(0.0, 1.0);
        if d >= 1.0 { far } else { (near * far / (far - d * (far - near))).min(far) }
    })
}

/// The emission pass of `lists`, in which opaque geometry is drawn black as a holdout: the
/// rasterizer's opaque primitives make alpha 1, so where one was drawn the alpha is given back to
/// the light in front of it (`max(r, g, b)`, the rule the renderer already uses for additive light
/// brighter than its coverage) and the holdout alone is transparent black.
pub fn emission_image(view: &View, lists: &[DrawList]) -> Image {
    let frame = pyrograph_render::render(view, lists, [0.0; 4]);
    let mut image = frame.to_image();
    let w = frame.width();
    for (k, px) in image.data_mut().chunks_exact_mut(4).enumerate() {
        let (x, y) = (k as u32 % w, k as u32 / w);
        if frame.depth(x, y) < 1.0 {
            let [r, g, b, _] = frame.premultiplied(x, y);
            let a = r.max(g).max(b).min(1.0);
            px.copy_from_slice(&if a > 0.0 { [r / a, g / a, b / a, a] } else { [0.0; 4] });
        }
    }
    image
}
