//! `imaging.levels`: black point, white point and gamma, the exposure fix a plate needs before
//! its HSV mask (Eigenfires thesis §3.2 assumes frames whose flame spans the value range).

use std::sync::Arc;

use pyrograph_core::declare::Cook;
use pyrograph_core::{Channels, CookCtx, Image, NodeError, port};
use rayon::prelude::*;

pyrograph_core::node! {
    /// Remaps an image's levels: input black and white points, gamma, output black and white points (pre-processing before the HSV masks of Eigenfires thesis §3.2).
    ///
    /// Each colour sample x becomes out_black + (out_white − out_black) · t^(1/gamma), where
    /// t = (x − black) / (white − black), clamped to 0..1 when `clamp` is on (Photoshop's Levels,
    /// Nuke's Grade without multiply). Alpha is left as it is. Raising `black` above a plate's
    /// noise floor and lowering `white` to its hottest flame lets the default HSV ranges select
    /// dim footage without retuning them.
    #[node("imaging.levels", "Imaging", PerFrame)]
    pub struct Levels {
        /// The image to adjust (gray or RGBA).
        image: Arc<Image>,
        /// Input black point: this sample and below become `out_black`.
        #[range(0.0, 1.0)]
        black: f32 = 0.0,
        /// Input white point: this sample and above become `out_white`; must be above `black`.
        #[range(0.0, 64.0)]
        white: f32 = 1.0,
        /// Gamma of the mid-tones: above 1 brightens them, below 1 darkens them.
        #[range(0.05, 10.0)]
        gamma: f32 = 1.0,
        /// Output black point.
        #[range(0.0, 64.0)]
        out_black: f32 = 0.0,
        /// Output white point.
        #[range(0.0, 64.0)]
        out_white: f32 = 1.0,
        /// Clamps t to 0..1, so nothing leaves the output range (off keeps HDR highlights above white).
        clamp: bool = true,
    }
    /// The adjusted image.
    -> image: Arc<Image>
}

impl Cook for Levels {
    fn cook(self, _: &CookCtx) -> Result<Arc<Image>, NodeError> {
        if self.white <= self.black {
            return Err(NodeError::port(port!(Levels, white), format!("{} must be above black {}", self.white, self.black)));
        }
        Ok(Arc::new(levels(&self.image, &self.settings())))
    }
}

/// The mapping of `imaging.levels` as plain numbers: input black and white points, gamma, output
/// range and whether to clamp.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LevelMap {
    /// Input value mapped to `out_black`.
    pub black: f32,
    /// Input value mapped to `out_white`; above `black`.
    pub white: f32,
    /// Gamma applied between the points (above 1 brightens the mid-tones).
    pub gamma: f32,
    /// Output value of `black`.
    pub out_black: f32,
    /// Output value of `white`.
    pub out_white: f32,
    /// Clamp to the points before the gamma.
    pub clamp: bool,
}

impl LevelMap {
    fn apply(&self, x: f32) -> f32 {
        let t = (x - self.black) / (self.white - self.black);
        let t = if self.clamp { t.clamp(0.0, 1.0) } else { t };
        // powf of a negative base is NaN: below black without clamping stays linear instead.
        let t = if t > 0.0 && self.gamma != 1.0 { t.powf(1.0 / self.gamma) } else { t };
        self.out_black + (self.out_white - self.out_black) * t
    }
}

impl Levels {
    /// The node's mapping.
    pub fn settings(&self) -> LevelMap {
        let Levels { black, white, gamma, out_black, out_white, clamp, .. } = *self;
        LevelMap { black, white, gamma, out_black, out_white, clamp }
    }
}

/// `img` with its colour samples remapped by `p` (alpha untouched); `p.white > p.black`.
pub fn levels(img: &Image, p: &LevelMap) -> Image {
    let mut out = img.clone();
    let colour = match img.channels() {
        Channels::Gray => 1,
        Channels::Rgba => 3,
    };
    let stride = img.channels().count();
    out.data_mut().par_chunks_mut(stride * 4096).for_each(|block| {
        for px in block.chunks_exact_mut(stride) {
            for v in &mut px[..colour] {
                *v = p.apply(*v);
            }
        }
    });
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use pyrograph_core::declare::Declared;

    fn params(black: f32, white: f32, gamma: f32) -> Levels {
        let image = Arc::new(Image::new(1, 1, Channels::Gray));
        Levels { image, black, white, gamma, out_black: 0.0, out_white: 1.0, clamp: true }
    }

    fn rgba(px: [f32; 4]) -> Image {
        Image::from_vec(1, 1, Channels::Rgba, px.to_vec()).unwrap()
    }

    fn assert_near(got: &[f32], want: &[f32], what: &str) {
        assert_eq!(got.len(), want.len());
        for (g, w) in got.iter().zip(want) {
            assert!((g - w).abs() < 1e-6, "{got:?} vs {want:?}: {what}");
        }
    }

    #[test]
    fn known_values() {
        let out = levels(&rgba([0.1, 0.4, 0.8, 0.3]), &params(0.2, 0.6, 1.0).settings());
        assert_near(out.data(), &[0.0, 0.5, 1.0, 0.3], "black clips, mid maps linearly, white clips, alpha kept");
        let out = levels(&rgba([0.25, 0.0, 1.0, 1.0]), &params(0.0, 1.0, 2.0).settings());
        assert_near(out.data(), &[0.5, 0.0, 1.0, 1.0], "gamma 2 is a square root");
        let mut p = params(0.0, 0.5, 1.0);
        p.clamp = false;
        p.out_black = 0.1;
        p.out_white = 0.2;
        let out = levels(&rgba([1.0, -0.5, 0.25, 1.0]), &p.settings());
        assert_near(out.data(), &[0.3, 0.0, 0.15, 1.0], "unclamped, output range 0.1..0.2");
        let gray = Image::from_vec(2, 1, Channels::Gray, vec![0.2, 0.6]).unwrap();
        assert_near(levels(&gray, &params(0.2, 0.6, 1.0).settings()).data(), &[0.0, 1.0], "a gray image's one channel");
    }

    #[test]
    fn defaults_leave_an_image_as_it_is() {
        let d = Levels::desc();
        let img = Arc::new(rgba([0.3, 0.7, 0.1, 0.5]));
        let values: Vec<_> =
            d.inputs.iter().map(|p| p.default.clone().unwrap_or_else(|| pyrograph_core::Value::Image(img.clone()))).collect();
        let p = Levels::read(&pyrograph_core::Inputs::new(&d, &values)).unwrap();
        let out = p.cook(&CookCtx::new()).unwrap();
        assert_eq!(out.data(), img.data());
    }

    #[test]
    fn white_at_or_below_black_names_the_port() {
        let e = params(0.5, 0.5, 1.0).cook(&CookCtx::new()).err().unwrap().to_string();
        assert!(e.contains("white") && e.contains("must be above black 0.5"), "{e}");
    }

    proptest! {
        #[test]
        fn levels_are_monotonic_and_stay_in_the_output_range(
            black in 0.0f32..0.5, span in 0.01f32..2.0, gamma in 0.1f32..5.0,
            a in -1.0f32..3.0, b in -1.0f32..3.0,
        ) {
            let p = params(black, black + span, gamma);
            let (lo, hi) = if a <= b { (a, b) } else { (b, a) };
            let (l, h) = (p.settings().apply(lo), p.settings().apply(hi));
            prop_assert!(l <= h, "{lo} -> {l}, {hi} -> {h}");
            prop_assert!((0.0..=1.0).contains(&l) && (0.0..=1.0).contains(&h));
        }
    }
}
