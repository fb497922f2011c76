//! Compact storage of cached frames (DESIGN: frames stored no wider than their content).
//!
//! Nodes compute in f32, but most frames that enter a graph come from 8-bit files and videos,
//! whose samples are the 256 levels `k / 255` exactly as the decoders make them. Such a frame is
//! kept in the frame cache at one byte a sample, a quarter of its f32 size, and widened back when a
//! cook asks for it; the widening is the decoders' own `k as f32 / 255.0`, so it is bit-identical.
//! A frame with any other sample (a blur, a gray conversion, HDR, a negative zero) stays f32.

use crate::value::{Channels, Image};

/// An image whose every sample is an 8-bit level, one byte a sample.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Bytes8 {
    width: u32,
    height: u32,
    channels: Channels,
    data: Vec<u8>,
}

/// Samples checked per step: the checks of one step run without a branch (so they vectorize),
/// and a frame that is not 8-bit is given up after the first step that shows it.
const STEP: usize = 256;

impl Bytes8 {
    /// The image in bytes, or `None` when a sample is not exactly `k / 255` for a byte `k`.
    pub(crate) fn pack(img: &Image) -> Option<Bytes8> {
        let src = img.data();
        let mut data = vec![0_u8; src.len()];
        for (s, d) in src.chunks(STEP).zip(data.chunks_mut(STEP)) {
            let mut exact = true;
            for (&v, b) in s.iter().zip(d.iter_mut()) {
                // Saturating cast: negatives and NaN give 0, over-bright values 255; the
                // comparison below then refuses them (as it refuses -0.0, whose bits differ).
                let k = (v * 255.0 + 0.5) as u8;
                exact &= widen(k).to_bits() == v.to_bits();
                *b = k;
            }
            if !exact {
                return None;
            }
        }
        let (width, height) = img.size();
        Some(Bytes8 { width, height, channels: img.channels(), data })
    }

    /// The f32 image, bit-identical to the one packed.
    pub(crate) fn unpack(&self) -> Image {
        let data = self.data.iter().map(|&k| widen(k)).collect();
        // The length matches by construction (it was the image's).
        Image::from_vec(self.width, self.height, self.channels, data)
            .unwrap_or_else(|| Image::new(self.width, self.height, self.channels))
    }

    /// Bytes held.
    pub(crate) fn byte_size(&self) -> usize {
        self.data.len()
    }
}

/// A byte as the 8-bit decoders widen it (`image`'s `u8 -> f32` and the video reader's table).
fn widen(k: u8) -> f32 {
    f32::from(k) / 255.0
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;

    use super::*;

    fn image(data: Vec<f32>) -> Image {
        let w = data.len() as u32;
        Image::from_vec(w, 1, Channels::Gray, data).unwrap()
    }

    #[test]
    fn only_exact_8_bit_levels_pack() {
        let levels: Vec<f32> = (0..=255).map(|k| k as f32 / 255.0).collect();
        let packed = Bytes8::pack(&image(levels.clone())).expect("8-bit levels pack");
        assert_eq!(packed.byte_size(), 256);
        assert_eq!(packed.unpack().data(), &levels[..]);
        for odd in [0.5, -0.0, -1.0 / 255.0, 256.0 / 255.0, f32::NAN, f32::INFINITY, 0.299 * (7.0 / 255.0)] {
            // The odd sample sits after a full step of levels, so a late mismatch is caught too.
            let mut data = levels.clone();
            data.extend([0.0; 40]);
            data.push(odd);
            assert!(Bytes8::pack(&image(data)).is_none(), "{odd} is not an 8-bit level");
        }
        // One ulp away from a level is not that level.
        let near = f32::from_bits((100.0_f32 / 255.0).to_bits() + 1);
        assert!(Bytes8::pack(&image(vec![near])).is_none());
    }

    proptest! {
        #[test]
        fn rgba_bytes_round_trip_bit_identically(bytes in prop::collection::vec(any::<u8>(), 4..400)) {
            let n = bytes.len() / 4 * 4;
            let data: Vec<f32> = bytes[..n].iter().map(|&k| f32::from(k) / 255.0).collect();
            let img = Image::from_vec((n / 4) as u32, 1, Channels::Rgba, data).unwrap();
            let packed = Bytes8::pack(&img).expect("decoded bytes pack");
            prop_assert_eq!(packed.byte_size(), img.byte_size() / 4);
            let back = packed.unpack();
            prop_assert_eq!(back.channels(), Channels::Rgba);
            prop_assert!(back.data().iter().zip(img.data()).all(|(a, b)| a.to_bits() == b.to_bits()));
        }
    }
}
