//! Synthetic smoke from the original video (Eigenfires thesis §6.3): the difference of
//! consecutive frames, thresholded, slightly blurred and multiplied by a colour; the smoke layer
//! of original colouring (Algorithm 2).

use std::hash::{Hash, Hasher};
use std::sync::Arc;

use pyrograph_core::fingerprint::Fingerprinter;
use pyrograph_core::{Channels, Clip, ClipOf, Cook, CookCtx, FrameSource, Image, NodeError, PortType, Value, port};

use crate::color::{check_size, check_threshold};
use crate::gray::{GrayMode, to_gray};
use crate::preprocess::morphology::gaussian_blur;

pyrograph_core::choice! {
    /// Which difference of consecutive frames the smoke is made of.
    pub enum Difference {
        /// The saturated signed difference current − next (clamped at 0).
        Signed = "signed",
        /// |current − next|.
        Absolute = "absolute",
    }
}

pyrograph_core::ports! {
    /// Smoke settings (§6.3): the ports of `imaging.smoke` after its clip.
    #[derive(Copy, PartialEq)]
    pub struct SmokeParams {
        /// current − next clamped at 0, or |current − next|
        difference: Difference = Difference::Signed,
        /// Differences below this (0–255) are removed
        #[range(0.0, 255.0)]
        threshold: f64 = 8.0,
        /// Sigma of the small Gaussian blur, in pixels
        #[range(0.0, 20.0)]
        blur: f32 = 1.5,
        /// Multiply colour (dark gray)
        color: [f32; 4] = [0.45, 0.45, 0.45, 1.0],
    }
}

/// The index of the frame compared with frame `index`: the next one, or the previous one for the
/// last frame (itself for a one-frame clip).
pub fn partner_frame(index: usize, len: usize) -> usize {
    if index + 1 < len { index + 1 } else { index.saturating_sub(1) }
}

/// Why smoke cannot be made, by the setting it concerns (`Smoke`'s cook names the port).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SmokeError {
    /// Two frames of the clip differ in size.
    #[error("a frame {0}")]
    Clip(String),
    /// The threshold is outside 0–255.
    #[error("{0}")]
    Threshold(String),
    /// The blur is not a finite number.
    #[error("{0}")]
    Blur(String),
    /// Anything no setting is to blame for.
    #[error("{0}")]
    Message(String),
}

/// A smoke error on the port of `imaging.smoke` it concerns.
impl From<SmokeError> for NodeError {
    fn from(e: SmokeError) -> NodeError {
        match e {
            SmokeError::Clip(m) => NodeError::port(port!(Smoke, clip), format!("'{}' {m}", port!(Smoke, clip))),
            SmokeError::Threshold(m) => NodeError::port(port!(SmokeParams, threshold), m),
            SmokeError::Blur(m) => NodeError::port(port!(SmokeParams, blur), m),
            SmokeError::Message(m) => NodeError::msg(m),
        }
    }
}

/// Smoke of one frame from the `current` and `next` original frames (§6.3 steps 1–5):
/// gray difference (signed, clamped to 0..1, or absolute), threshold, blur, colour multiply.
/// The result is opaque RGBA.
pub fn smoke_frame(current: &Image, next: &Image, params: &SmokeParams) -> Result<Image, SmokeError> {
    check_size(current, next).map_err(SmokeError::Clip)?;
    let t = check_threshold(params.threshold).map_err(SmokeError::Threshold)? / 255.0;
    let (a, b) = (to_gray(current, GrayMode::Rec601), to_gray(next, GrayMode::Rec601));
    let diff: Vec<f32> = a
        .data()
        .iter()
        .zip(b.data())
        .map(|(&x, &y)| {
            let d = if params.difference == Difference::Absolute { (x - y).abs() } else { (x - y).max(0.0) };
            let d = d.min(1.0);
            if d < t { 0.0 } else { d }
        })
        .collect();
    let (w, h) = current.size();
    let mismatch = || SmokeError::Message("image data does not match its size".into());
    let diff = Image::from_vec(w, h, Channels::Gray, diff).ok_or_else(mismatch)?;
    let blurred = gaussian_blur(&diff, params.blur);
    let c = params.color;
    let data = blurred.data().iter().flat_map(|&v| [v * c[0], v * c[1], v * c[2], 1.0]).collect();
    Image::from_vec(w, h, Channels::Rgba, data).ok_or_else(mismatch)
}

/// The frames of the smoke clip, computed on demand from the original clip.
struct SmokeSource {
    clip: Clip,
    params: SmokeParams,
}

impl FrameSource for SmokeSource {
    fn len(&self) -> usize {
        self.clip.len()
    }
    fn frame(&self, index: usize, ctx: &CookCtx) -> Result<Value, NodeError> {
        let current = self.clip.image(index, ctx)?;
        let next = self.clip.image(partner_frame(index, self.clip.len()), ctx)?;
        Ok(Value::Image(Arc::new(smoke_frame(&current, &next, &self.params)?)))
    }
}

/// The smoke clip of an original clip, lazily per frame.
pub fn smoke_clip(clip: &Clip, params: SmokeParams) -> Result<Clip, SmokeError> {
    check_threshold(params.threshold).map_err(SmokeError::Threshold)?;
    if !params.blur.is_finite() {
        return Err(SmokeError::Blur("must be a finite number".into()));
    }
    let mut h = Fingerprinter::new();
    let absolute = params.difference == Difference::Absolute;
    ("imaging.smoke", clip.fingerprint(), absolute, params.threshold.to_bits(), params.blur.to_bits()).hash(&mut h);
    // The colour's alpha is not used, so it is not hashed.
    params.color[..3].iter().for_each(|c| c.to_bits().hash(&mut h));
    Ok(Clip::new(PortType::Image, clip.fps(), h.finish(), Arc::new(SmokeSource { clip: clip.clone(), params })))
}

pyrograph_core::node! {
    /// Synthetic smoke from the original video (Eigenfires thesis §6.3): the difference of consecutive frames, thresholded, blurred and colour-multiplied.
    ///
    /// Each frame is current − next in gray (signed and clamped at 0, or absolute), differences below the
    /// threshold (0–255) are removed, a small Gaussian blur softens the rest and the colour multiplies it. The
    /// last frame is compared with the previous one. Frames are computed lazily; feed the result to the smoke
    /// input of imaging.original_coloring_layered.
    #[node("imaging.smoke", "Color & Post", WholeClip)]
    pub struct Smoke {
        /// Original colour frames, the same pose as the coloured flame
        clip: ClipOf<Arc<Image>>,
        /// The smoke settings.
        params: SmokeParams,
    }
    /// Smoke frames (RGBA)
    -> clip: ClipOf<Arc<Image>>
}

impl Cook for Smoke {
    fn cook(self, _: &CookCtx) -> Result<ClipOf<Arc<Image>>, NodeError> {
        Ok(ClipOf::new(smoke_clip(&self.clip, self.params)?))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn gray(data: &[f32]) -> Image {
        Image::from_vec(data.len() as u32, 1, Channels::Gray, data.to_vec()).unwrap()
    }

    fn clip(frames: Vec<Image>) -> Clip {
        Clip::from_frames(PortType::Image, 24.0, frames.into_iter().map(|f| Value::Image(Arc::new(f))).collect())
    }

    fn no_blur(absolute: bool) -> SmokeParams {
        let difference = if absolute { Difference::Absolute } else { Difference::Signed };
        SmokeParams { difference, threshold: 25.5, blur: 0.0, color: [0.5, 0.5, 1.0, 1.0] }
    }

    #[test]
    fn signed_and_absolute_differences_threshold_and_colour() {
        let cur = gray(&[0.5, 0.2, 0.5, 0.55]);
        let next = gray(&[0.1, 0.6, 0.45, 0.5]);
        let s = smoke_frame(&cur, &next, &no_blur(false)).unwrap();
        let r: Vec<f32> = s.data().chunks(4).map(|p| p[0]).collect();
        let b: Vec<f32> = s.data().chunks(4).map(|p| p[2]).collect();
        // 0.4 kept (×0.5 colour); negative clamped to 0; 0.05 < threshold 0.1 removed.
        assert!((r[0] - 0.2).abs() < 1e-6 && (b[0] - 0.4).abs() < 1e-6);
        assert_eq!(&r[1..], &[0.0, 0.0, 0.0]);
        let a = smoke_frame(&cur, &next, &no_blur(true)).unwrap();
        let r: Vec<f32> = a.data().chunks(4).map(|p| p[0]).collect();
        assert!((r[1] - 0.2).abs() < 1e-6, "absolute keeps the negative difference: {r:?}");
    }

    #[test]
    fn the_last_frame_uses_the_previous_one_and_frames_are_lazy() {
        assert_eq!(partner_frame(0, 3), 1);
        assert_eq!(partner_frame(2, 3), 1);
        assert_eq!(partner_frame(0, 1), 0);
        let frames = vec![gray(&[0.0]), gray(&[0.5]), gray(&[1.0])];
        let smoke = smoke_clip(&clip(frames), no_blur(false)).unwrap();
        let ctx = CookCtx::new();
        assert_eq!(smoke.len(), 3);
        // Frame 2 (1.0) minus frame 1 (0.5) = 0.5, ×0.5.
        assert!((smoke.image(2, &ctx).unwrap().data()[0] - 0.25).abs() < 1e-6);
        // Frame 0 (0.0) minus frame 1: negative, clamped to 0.
        assert_eq!(smoke.image(0, &ctx).unwrap().data()[0], 0.0);
    }

    #[test]
    fn bad_threshold_and_sizes_are_errors() {
        let frames = vec![gray(&[0.0]), gray(&[0.5, 0.1])];
        let smoke = smoke_clip(&clip(frames.clone()), no_blur(false)).unwrap();
        assert!(smoke.get(0, &CookCtx::new()).unwrap_err().to_string().contains("same size"));
        let bad = SmokeParams { threshold: 300.0, ..no_blur(false) };
        assert!(smoke_clip(&clip(frames), bad).unwrap_err().to_string().contains("outside 0–255"));
    }
}
