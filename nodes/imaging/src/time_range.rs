//! `imaging.time_range`: the frames first..=last of a clip, pulled from it only when asked for.

use std::hash::{Hash, Hasher};
use std::sync::Arc;

use pyrograph_core::fingerprint::Fingerprinter;
use pyrograph_core::{Clip, ClipOf, Cook, CookCtx, FrameSource, Image, NodeError, Value, port};

pyrograph_core::node! {
    /// Keeps the frames first..=last of a clip.
    ///
    /// Frames are pulled from the source clip only when asked for.
    #[node("imaging.time_range", "Imaging", WholeClip)]
    pub struct TimeRange {
        /// The clip to trim.
        clip: ClipOf<Arc<Image>>,
        /// First frame kept (0-based).
        #[range(0, 1i64 << 40)]
        first: i64 = 0,
        /// Last frame kept, inclusive; negative counts from the end (-1 = last frame).
        #[range(-(1i64 << 40), 1i64 << 40)]
        last: i64 = -1,
    }
    /// The trimmed clip.
    -> clip: ClipOf<Arc<Image>>
}

/// Frames `first..first + len` of another clip.
struct RangeSource {
    clip: Clip,
    first: usize,
    len: usize,
}

impl FrameSource for RangeSource {
    fn len(&self) -> usize {
        self.len
    }
    fn frame(&self, index: usize, ctx: &CookCtx) -> Result<Value, NodeError> {
        self.clip.get(self.first + index, ctx)
    }
}

/// Why a range does not fit a clip, by the end it concerns (`TimeRange`'s cook names the port).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum RangeError {
    /// The first frame lies outside the clip.
    #[error("{0}")]
    First(String),
    /// The last frame lies outside the clip, or before the first.
    #[error("{0}")]
    Last(String),
}

/// A range's error on the port of `imaging.time_range` it concerns.
impl From<RangeError> for NodeError {
    fn from(e: RangeError) -> NodeError {
        match e {
            RangeError::First(m) => NodeError::port(port!(TimeRange, first), m),
            RangeError::Last(m) => NodeError::port(port!(TimeRange, last), m),
        }
    }
}

/// Resolves `first..=last` (negative `last` counts from the end) against a clip of `len` frames.
pub fn resolve_range(len: usize, first: i64, last: i64) -> Result<(usize, usize), RangeError> {
    let frames = |len: usize| {
        if len == 0 { "it has no frames".to_string() } else { format!("frames 0-{}", len - 1) }
    };
    let len_i = i64::try_from(len).unwrap_or(i64::MAX);
    if first < 0 || first >= len_i {
        return Err(RangeError::First(format!("frame {first} is outside the {len}-frame clip ({})", frames(len))));
    }
    let last_abs = if last < 0 { len_i + last } else { last };
    if last_abs < 0 || last_abs >= len_i {
        return Err(RangeError::Last(format!("frame {last} is outside the {len}-frame clip ({})", frames(len))));
    }
    if last_abs < first {
        return Err(RangeError::Last(format!(
            "the range {first}-{last_abs} is empty: last must not be before first (the clip has {len} frames)"
        )));
    }
    // Both are within 0..len, so they fit usize.
    Ok((first as usize, last_abs as usize))
}

/// The frames `first..=last` of `clip`, computed lazily from it.
pub fn time_range(clip: &Clip, first: i64, last: i64) -> Result<Clip, RangeError> {
    let (first, last) = resolve_range(clip.len(), first, last)?;
    let mut h = Fingerprinter::new();
    ("imaging.time_range", clip.fingerprint(), first, last).hash(&mut h);
    let source = RangeSource { clip: clip.clone(), first, len: last - first + 1 };
    Ok(Clip::new(clip.element().clone(), clip.fps(), h.finish(), Arc::new(source)))
}

impl Cook for TimeRange {
    fn cook(self, _: &CookCtx) -> Result<ClipOf<Arc<Image>>, NodeError> {
        Ok(ClipOf::new(time_range(&self.clip, self.first, self.last)?))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use pyrograph_core::PortType;

    fn int_clip(n: i64) -> Clip {
        Clip::from_frames(PortType::Int, 12.0, (0..n).map(Value::Int).collect())
    }

    fn ints(clip: &Clip) -> Vec<i64> {
        let ctx = CookCtx::new();
        (0..clip.len()).map(|i| if let Ok(Value::Int(v)) = clip.get(i, &ctx) { v } else { -1 }).collect()
    }

    #[test]
    fn time_range_maps_frames_lazily() {
        let clip = int_clip(5);
        assert_eq!(ints(&time_range(&clip, 1, 3).unwrap()), [1, 2, 3]);
        assert_eq!(ints(&time_range(&clip, 2, -1).unwrap()), [2, 3, 4]);
        assert_eq!(ints(&time_range(&clip, 0, -2).unwrap()), [0, 1, 2, 3]);
        let trimmed = time_range(&clip, 4, 4).unwrap();
        assert_eq!((ints(&trimmed), trimmed.fps()), (vec![4], 12.0));
        assert_ne!(time_range(&clip, 0, 1).unwrap().fingerprint(), time_range(&clip, 1, 2).unwrap().fingerprint());
    }

    #[test]
    fn time_range_errors_name_port_and_length() {
        let clip = int_clip(5);
        let err = NodeError::from(time_range(&clip, 5, -1).unwrap_err());
        assert!(matches!(&err, NodeError::Port { port, message } if port == "first" && message.contains("5-frame")), "{err}");
        let err = NodeError::from(time_range(&clip, 0, 5).unwrap_err());
        assert!(matches!(&err, NodeError::Port { port, message } if port == "last" && message.contains("0-4")), "{err}");
        let err = NodeError::from(time_range(&clip, 3, 2).unwrap_err());
        assert!(matches!(&err, NodeError::Port { port, message } if port == "last" && message.contains("empty")), "{err}");
        assert!(time_range(&int_clip(0), 0, -1).is_err());
    }
}
