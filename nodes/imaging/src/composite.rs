//! `imaging.composite`: a foreground image combined onto a background by a blend mode and an
//! opacity.

use std::sync::Arc;

use pyrograph_core::{Channels, Cook, CookCtx, Image, NodeError, port};

use crate::size::image_size_text;

pyrograph_core::choice! {
    /// How the foreground's colour combines with the background's.
    pub enum BlendMode {
        /// Porter–Duff over with straight alpha.
        Over = "over",
        /// a + b (not clamped: HDR allowed).
        Add = "add",
        /// 1 − (1 − a)(1 − b).
        Screen = "screen",
        /// max(a, b).
        Max = "max",
        /// a × b.
        Multiply = "multiply",
    }
}

impl BlendMode {
    /// The blended colour of one channel (`over` is the foreground itself).
    fn blend(self, a: f32, b: f32) -> f32 {
        match self {
            BlendMode::Over => b,
            BlendMode::Add => a + b,
            BlendMode::Screen => 1.0 - (1.0 - a) * (1.0 - b),
            BlendMode::Max => a.max(b),
            BlendMode::Multiply => a * b,
        }
    }
}

pyrograph_core::node! {
    /// Combines a foreground image b onto a background a.
    ///
    /// The foreground's weight is opacity × its alpha. `over` is Porter–Duff over with straight alpha; the other
    /// modes mix the background's colour towards mode(a, b) by that weight and combine alphas as over does. A gray
    /// input is promoted to RGBA when the other is RGBA; two gray inputs give a gray result.
    #[node("imaging.composite", "Imaging", PerFrame)]
    pub struct Composite {
        /// Background.
        a: Arc<Image>,
        /// Foreground, same size as a.
        b: Arc<Image>,
        /// How b combines with a.
        mode: BlendMode = BlendMode::Over,
        /// Strength of the foreground.
        #[range(0.0, 1.0)]
        opacity: f32 = 1.0,
    }
    /// The composite.
    -> image: Arc<Image>
}

/// One straight-alpha RGBA pixel of `b` combined onto `a` with foreground weight `opacity`.
fn composite_rgba(a: &[f32], b: &[f32], mode: BlendMode, opacity: f32) -> [f32; 4] {
    let (aa, ba) = (a[3], b[3]);
    let w = opacity * ba;
    let alpha = w + aa * (1.0 - w);
    let mut out = [0.0, 0.0, 0.0, alpha];
    for c in 0..3 {
        out[c] = match mode {
            // Straight-alpha over: premultiply, combine, un-premultiply.
            BlendMode::Over if alpha > 0.0 => (b[c] * w + a[c] * aa * (1.0 - w)) / alpha,
            BlendMode::Over => 0.0,
            _ => a[c] + w * (mode.blend(a[c], b[c]) - a[c]),
        };
    }
    out
}

/// Why two images cannot be composited, by the input it concerns (`Composite`'s cook names the
/// port).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum CompositeError {
    /// The background's data does not match its size.
    #[error("{0}")]
    A(String),
    /// The foreground's size is not the background's.
    #[error("{0}")]
    B(String),
}

/// A composite's error on the port of `imaging.composite` it concerns.
impl From<CompositeError> for NodeError {
    fn from(e: CompositeError) -> NodeError {
        match e {
            CompositeError::A(m) => NodeError::port(port!(Composite, a), m),
            CompositeError::B(m) => NodeError::port(port!(Composite, b), m),
        }
    }
}

/// `b` combined onto `a`; both must have the same size.
pub fn composite(a: &Image, b: &Image, mode: BlendMode, opacity: f32) -> Result<Image, CompositeError> {
    if a.size() != b.size() {
        return Err(CompositeError::B(format!(
            "b is {} but a is {}; composite needs images of the same size",
            image_size_text(b),
            image_size_text(a)
        )));
    }
    let (w, h) = a.size();
    let both_gray = a.channels() == Channels::Gray && b.channels() == Channels::Gray;
    let data: Vec<f32> = if both_gray {
        a.data().iter().zip(b.data()).map(|(&x, &y)| x + opacity * (mode.blend(x, y) - x)).collect()
    } else {
        let (a, b) = (a.to_rgba(), b.to_rgba());
        a.data().chunks_exact(4).zip(b.data().chunks_exact(4)).flat_map(|(p, q)| composite_rgba(p, q, mode, opacity)).collect()
    };
    let channels = if both_gray { Channels::Gray } else { Channels::Rgba };
    Image::from_vec(w, h, channels, data).ok_or_else(|| CompositeError::A("image data does not match its size".into()))
}

impl Cook for Composite {
    fn cook(self, _: &CookCtx) -> Result<Arc<Image>, NodeError> {
        Ok(Arc::new(composite(&self.a, &self.b, self.mode, self.opacity)?))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::{assert_close, gray, rgba};

    #[test]
    fn composite_modes_on_one_pixel() {
        let a = rgba(1, 1, &[0.2, 0.4, 0.6, 1.0]);
        let b = rgba(1, 1, &[0.5, 0.5, 0.5, 1.0]);
        let run = |m| composite(&a, &b, m, 1.0).unwrap().into_vec();
        assert_close(&run(BlendMode::Over), &[0.5, 0.5, 0.5, 1.0]);
        assert_close(&run(BlendMode::Add), &[0.7, 0.9, 1.1, 1.0]);
        assert_close(&run(BlendMode::Screen), &[0.6, 0.7, 0.8, 1.0]);
        assert_close(&run(BlendMode::Max), &[0.5, 0.5, 0.6, 1.0]);
        assert_close(&run(BlendMode::Multiply), &[0.1, 0.2, 0.3, 1.0]);
        assert_close(&composite(&a, &b, BlendMode::Add, 0.5).unwrap().into_vec(), &[0.45, 0.65, 0.85, 1.0]);
    }

    #[test]
    fn over_uses_straight_alpha() {
        let a = rgba(1, 1, &[0.2, 0.4, 0.6, 1.0]);
        let half = rgba(1, 1, &[1.0, 0.0, 0.0, 0.5]);
        assert_close(&composite(&a, &half, BlendMode::Over, 1.0).unwrap().into_vec(), &[0.6, 0.2, 0.3, 1.0]);
        // Half-transparent red over half-transparent blue: alpha 0.75, colour weighted 2:1 to red.
        let blue = rgba(1, 1, &[0.0, 0.0, 1.0, 0.5]);
        assert_close(&composite(&blue, &half, BlendMode::Over, 1.0).unwrap().into_vec(), &[2.0 / 3.0, 0.0, 1.0 / 3.0, 0.75]);
        let clear = rgba(1, 1, &[0.0; 4]);
        assert_close(&composite(&clear, &clear, BlendMode::Over, 1.0).unwrap().into_vec(), &[0.0; 4]);
    }

    #[test]
    fn composite_promotes_gray_and_checks_sizes() {
        let g = gray(1, 1, &[0.5]);
        let both = composite(&g, &gray(1, 1, &[0.25]), BlendMode::Add, 1.0).unwrap();
        assert_eq!((both.channels(), both.data()), (Channels::Gray, &[0.75][..]));
        let mixed = composite(&g, &rgba(1, 1, &[0.1, 0.2, 0.3, 1.0]), BlendMode::Multiply, 1.0).unwrap();
        assert_eq!(mixed.channels(), Channels::Rgba);
        assert_close(mixed.data(), &[0.05, 0.1, 0.15, 1.0]);
        let err = composite(&g, &gray(2, 1, &[0.0, 0.0]), BlendMode::Over, 1.0).unwrap_err().to_string();
        assert!(err.contains("2x1") && err.contains("1x1"), "{err}");
    }
}
