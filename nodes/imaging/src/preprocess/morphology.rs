//! `imaging.morphology` and `imaging.gaussian_blur`: the clean-up filters of thesis §3.2.1,
//! a binary (0/255) span-based morphology written for masks, and imageproc's Gaussian blur.

use std::sync::Arc;

use image::{GrayImage, Luma};
use imageproc::morphology::Mask as ImageprocElement;
use pyrograph_core::{Channels, Cook, CookCtx, Image, Mask, NodeError, port};
use rayon::prelude::*;

use crate::convert::{from_gray32f, from_rgba32f, to_gray32f, to_rgba32f};

pyrograph_core::choice! {
    /// A morphological operation.
    pub enum MorphOp {
        /// Grows the mask.
        Dilate = "dilate",
        /// Shrinks the mask.
        Erode = "erode",
        /// Erode then dilate: removes specks smaller than the element.
        Open = "open",
        /// Dilate then erode: fills gaps smaller than the element.
        Close = "close",
    }
}

pyrograph_core::choice! {
    /// Shape of the structuring element.
    pub enum KernelShape {
        /// A full `size × size` square.
        Rect = "rect",
        /// The ellipse inscribed in the square, as OpenCV's `MORPH_ELLIPSE`.
        Ellipse = "ellipse",
        /// The centre row and column.
        Cross = "cross",
    }
}

impl KernelShape {
    /// Whether cell `(x, y)` of a `size × size` element (size odd) is set.
    ///
    /// The ellipse follows OpenCV's `getStructuringElement` rounding so a 5×5 ellipse is the
    /// same 17-cell element the OpenCV peer uses.
    pub fn contains(self, size: u32, x: u32, y: u32) -> bool {
        let r = (size / 2) as f64;
        let (dx, dy) = (x as f64 - r, y as f64 - r);
        match self {
            KernelShape::Rect => true,
            KernelShape::Cross => dx == 0.0 || dy == 0.0,
            KernelShape::Ellipse if r == 0.0 => true,
            KernelShape::Ellipse => dx.abs() <= (r * ((r * r - dy * dy) / (r * r)).sqrt()).round(),
        }
    }
}

/// A structuring element of odd size whose rows are spans centred on the element's column
/// (true of every [`KernelShape`]), kept as one half-width per row so binary morphology can run
/// as a horizontal pass per distinct half-width and a vertical combination of rows.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Element {
    shape: KernelShape,
    size: u32,
    /// Half-width of the span of each row, top row first.
    half_widths: Vec<usize>,
}

impl Element {
    /// The shape the element was built from.
    pub fn shape(&self) -> KernelShape {
        self.shape
    }

    /// Width and height in pixels.
    pub fn size(&self) -> u32 {
        self.size
    }

    /// Half-width of each row's span, top row first; row `i` covers offsets `-hw..=hw` at `dy = i - size / 2`.
    pub fn half_widths(&self) -> &[usize] {
        &self.half_widths
    }

    /// The same element as an imageproc mask (for its grayscale morphology).
    pub fn to_imageproc(&self) -> ImageprocElement {
        let size = self.size;
        let img = GrayImage::from_fn(size, size, |x, y| Luma([if self.shape.contains(size, x, y) { 255 } else { 0 }]));
        let centre = (size / 2) as u8;
        ImageprocElement::from_image(&img, centre, centre)
    }
}

/// A structuring element size that is even or outside 1..=99 (`Morphology`'s cook names its
/// `size` port).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{0}")]
pub struct ElementSizeError(pub String);

/// A size error on the `size` port of `imaging.morphology`.
impl From<ElementSizeError> for NodeError {
    fn from(e: ElementSizeError) -> NodeError {
        NodeError::port(port!(Morphology, size), e.0)
    }
}

/// The structuring element of `shape` and odd `size` (1..=99).
pub fn structuring_element(shape: KernelShape, size: u32) -> Result<Element, ElementSizeError> {
    if size.is_multiple_of(2) || !(1..=99).contains(&size) {
        return Err(ElementSizeError(format!("must be odd and in 1..=99, got {size}")));
    }
    let r = size / 2;
    // Every shape is symmetric about the centre column and each row is one contiguous span
    // (a test checks this against `contains` for every shape and size), so a row is its half-width.
    let half_widths = (0..size).map(|y| (0..=r).rev().find(|&d| shape.contains(size, r + d, y)).unwrap_or(0) as usize).collect();
    Ok(Element { shape, size, half_widths })
}

/// Binary min or max: on 0/255 masks erosion is AND (min) and dilation is OR (max); on
/// bit-packed rows they are AND / OR of words.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Reduce {
    Min,
    Max,
}

impl Reduce {
    #[inline(always)]
    fn apply(self, a: u64, b: u64) -> u64 {
        match self {
            Reduce::Min => a & b,
            Reduce::Max => a | b,
        }
    }

    /// The word that never changes the result (what pixels outside the image count as).
    fn neutral(self) -> u64 {
        match self {
            Reduce::Min => u64::MAX,
            Reduce::Max => 0,
        }
    }
}

/// `dst[j] = op(dst[j], src[j])`, a plain zip so it vectorizes.
#[inline(always)]
fn fold_into(dst: &mut [u64], src: &[u64], op: Reduce) {
    match op {
        Reduce::Min => dst.iter_mut().zip(src).for_each(|(d, &s)| *d &= s),
        Reduce::Max => dst.iter_mut().zip(src).for_each(|(d, &s)| *d |= s),
    }
}

/// A mask packed 64 pixels per word, row by row: bit `i` of word `j` of a row is pixel
/// `64 j + i`. Bits past the row's end are set to the operation's neutral value before use.
struct Bits {
    words: Vec<u64>,
    /// Words per row.
    stride: usize,
    width: usize,
}

/// `GATHER` gathers the low bits of eight bytes into the top byte: byte `i`'s bit sits at
/// `8 i`, times `2^(56 − 7 i)` lands it at `56 + i`, and no two products share a bit, so no carries.
const GATHER: u64 = 0x0102_0408_1020_4080;

/// `SPREAD[b]` has byte `i` = 255 where bit `i` of `b` is set (unpacking eight pixels at once).
const SPREAD: [u64; 256] = {
    let mut t = [0u64; 256];
    let mut b = 0;
    while b < 256 {
        let mut i = 0;
        while i < 8 {
            if b & (1 << i) != 0 {
                t[b] |= 0xFF << (8 * i);
            }
            i += 1;
        }
        b += 1;
    }
    t
};

impl Bits {
    /// Packs a 0/255 mask (`data` of `width`-byte rows), row-parallel.
    fn pack(data: &[u8], width: usize) -> Bits {
        let stride = width.div_ceil(64);
        let mut words = vec![0u64; stride * (data.len() / width.max(1))];
        if stride > 0 {
            words.par_chunks_mut(stride).zip(data.par_chunks(width)).with_min_len(ROWS_PER_TASK).for_each(|(dst, src)| {
                for (word, bytes) in dst.iter_mut().zip(src.chunks(64)) {
                    // Whole groups of eight as one load each (a variable-length copy would call memmove).
                    let mut groups = bytes.chunks_exact(8);
                    let mut w = 0u64;
                    for (k, eight) in (&mut groups).enumerate() {
                        let le: [u8; 8] = eight.try_into().unwrap_or_default();
                        let low_bits = u64::from_le_bytes(le) & 0x0101_0101_0101_0101;
                        w |= (low_bits.wrapping_mul(GATHER) >> 56) << (8 * k);
                    }
                    let done = bytes.len() - groups.remainder().len();
                    for (i, &b) in groups.remainder().iter().enumerate() {
                        w |= u64::from(b & 1) << (done + i);
                    }
                    *word = w;
                }
            });
        }
        Bits { words, stride, width }
    }

    /// Sets the bits past each row's end to `value`'s bits (the neutral word of an operation).
    fn pad_rows(&mut self, value: u64) {
        let used = self.width % 64;
        if used == 0 || self.stride == 0 {
            return;
        }
        let tail = !0u64 << used;
        for row in self.words.chunks_exact_mut(self.stride) {
            if let Some(last) = row.last_mut() {
                *last = (*last & !tail) | (value & tail);
            }
        }
    }

    /// Unpacks into a 0/255 byte image, row-parallel.
    fn unpack(&self) -> Vec<u8> {
        let rows = self.words.len().checked_div(self.stride).unwrap_or(0);
        let mut out = vec![0u8; rows * self.width];
        if self.width > 0 {
            out.par_chunks_mut(self.width).zip(self.words.par_chunks(self.stride)).with_min_len(ROWS_PER_TASK).for_each(
                |(dst, src)| {
                    for (bytes, &word) in dst.chunks_mut(64).zip(src) {
                        let done = bytes.len() / 8 * 8;
                        let mut groups = bytes.chunks_exact_mut(8);
                        for (k, eight) in (&mut groups).enumerate() {
                            eight.copy_from_slice(&SPREAD[((word >> (8 * k)) & 0xFF) as usize].to_le_bytes());
                        }
                        for (i, b) in groups.into_remainder().iter_mut().enumerate() {
                            *b = if (word >> (done + i)) & 1 != 0 { 255 } else { 0 };
                        }
                    }
                },
            );
        }
        out
    }
}

/// `dst[j]` = `op` over pixels `64 j + i - k ..= 64 j + i + k` of the packed row `src`, pixels
/// outside the row neutral. `padded` is scratch for the row with `pad` neutral words each side.
fn reduce_row(src: &[u64], dst: &mut [u64], k: usize, op: Reduce, padded: &mut Vec<u64>) {
    dst.copy_from_slice(src);
    if k == 0 {
        return;
    }
    let n = src.len();
    let pad = k.div_ceil(64);
    padded.clear();
    padded.resize(n + 2 * pad + 1, op.neutral());
    padded[pad..pad + n].copy_from_slice(src);
    for s in 1..=k {
        let (q, t) = (s / 64, (s % 64) as u32);
        // Bit i of `ahead(j)` is pixel 64 j + i + s; of `behind(j)` pixel 64 j + i − s.
        let ahead = |j: usize| {
            let lo = padded[pad + j + q];
            if t == 0 { lo } else { (lo >> t) | (padded[pad + j + q + 1] << (64 - t)) }
        };
        let behind = |j: usize| {
            let hi = padded[pad + j - q];
            if t == 0 { hi } else { (hi << t) | (padded[pad + j - q - 1] >> (64 - t)) }
        };
        for (j, d) in dst.iter_mut().enumerate() {
            *d = op.apply(*d, op.apply(ahead(j), behind(j)));
        }
    }
}

/// Binary erosion (`Min`) or dilation (`Max`) of a packed mask with `element`, pixels outside
/// the image ignored (as imageproc's `grayscale_erode` / `grayscale_dilate` on the 0/255 mask).
///
/// Written by hand because imageproc's grayscale morphology makes one single-threaded pass over
/// the whole byte image per element cell (17 for the 5×5 ellipse, 9801 for a 99×99 rect). Here
/// rows are bit-packed (64 pixels per word, so AND / OR handle 64 pixels at once) and the image
/// is cut into bands of rows, one rayon task each; a task reduces the rows its band reads
/// horizontally once per distinct half-width into scratch it keeps between bands (small enough
/// to stay in cache), then combines one reduced row per element row into each output row.
fn reduce(src: &mut Bits, element: &Element, op: Reduce) -> Bits {
    src.pad_rows(op.neutral());
    let (w, stride) = (src.width, src.stride);
    let mut out = Bits { words: vec![0u64; src.words.len()], stride, width: w };
    if stride == 0 || src.words.is_empty() {
        return out;
    }
    let src = &src.words;
    let h = src.len() / stride;
    let r = element.half_widths.len() / 2;
    let mut distinct: Vec<usize> = element.half_widths.iter().copied().filter(|&k| k > 0).collect();
    distinct.sort_unstable();
    distinct.dedup();
    let band = h.div_ceil(BANDS).max(MIN_BAND_ROWS);
    out.words.par_chunks_mut(band * stride).enumerate().for_each_init(
        || (Vec::<Vec<u64>>::new(), Vec::new()),
        |(planes, padded), (b, out_band)| {
            let y0 = b * band;
            let y1 = y0 + out_band.len() / stride;
            // Input rows lo..hi are read by this band; `planes[j]` holds them reduced by `distinct[j]`.
            let (lo, hi) = (y0.saturating_sub(r), (y1 + r).min(h));
            planes.resize_with(distinct.len(), Vec::new);
            for (plane, &k) in planes.iter_mut().zip(&distinct) {
                plane.resize((hi - lo) * stride, 0);
                for (d, s) in plane.chunks_exact_mut(stride).zip(src[lo * stride..hi * stride].chunks_exact(stride)) {
                    reduce_row(s, d, k, op, padded);
                }
            }
            for (y, row) in (y0..y1).zip(out_band.chunks_exact_mut(stride)) {
                let mut first = true;
                for (i, &k) in element.half_widths.iter().enumerate() {
                    // Element row i reads input row y + i - r; rows outside the image are ignored.
                    let Some(sy) = (y + i).checked_sub(r).filter(|&sy| sy < h) else { continue };
                    let input = match distinct.binary_search(&k) {
                        Ok(j) => planes.get(j).and_then(|p| p.get((sy - lo) * stride..(sy - lo + 1) * stride)),
                        Err(_) => src.get(sy * stride..(sy + 1) * stride),
                    };
                    let Some(input) = input else { continue };
                    if first {
                        row.copy_from_slice(input);
                        first = false;
                    } else {
                        fold_into(row, input, op);
                    }
                }
                if first {
                    row.fill(op.neutral());
                }
            }
        },
    );
    out
}

/// Bands per image in [`reduce`]: a few per core so a descheduled thread does not stall the op.
const BANDS: usize = 8;
/// Fewest rows per band, so the halo rows reduced twice stay a small share.
const MIN_BAND_ROWS: usize = 16;
/// Rows per rayon task when packing and unpacking.
const ROWS_PER_TASK: usize = 32;

/// Applies `op` with `element` to a binary mask. Pixels outside the image never grow the mask
/// and never erode it (OpenCV's default border for morphology). Equal to imageproc's
/// `grayscale_dilate` / `grayscale_erode` on the mask (tests compare them on random masks).
pub fn morphology(mask: &Mask, op: MorphOp, element: &Element) -> Mask {
    let (w, h) = (mask.width(), mask.height());
    let mut bits = Bits::pack(mask.data(), w as usize);
    let out = match op {
        MorphOp::Dilate => reduce(&mut bits, element, Reduce::Max),
        MorphOp::Erode => reduce(&mut bits, element, Reduce::Min),
        MorphOp::Open => reduce(&mut reduce(&mut bits, element, Reduce::Min), element, Reduce::Max),
        MorphOp::Close => reduce(&mut reduce(&mut bits, element, Reduce::Max), element, Reduce::Min),
    };
    Mask::from_vec(w, h, out.unpack()).unwrap_or_else(|| Mask::new(w, h))
}

pyrograph_core::node! {
    /// Dilates, erodes, opens or closes a mask to filter noise (Eigenfires thesis §3.2.1).
    ///
    /// The structuring element is a rect, ellipse (OpenCV MORPH_ELLIPSE) or cross of odd size.
    #[node("imaging.morphology", "Pre-processing", PerFrame)]
    pub struct Morphology {
        /// Mask to filter
        mask: Arc<Mask>,
        /// Operation: open removes specks, close fills gaps
        op: MorphOp = MorphOp::Open,
        /// Structuring element shape
        shape: KernelShape = KernelShape::Ellipse,
        /// Element width and height in pixels; must be odd
        #[range(1, 99)]
        size: u32 = 5,
    }
    /// Filtered mask
    -> mask: Arc<Mask>
}

impl Cook for Morphology {
    fn cook(self, _: &CookCtx) -> Result<Arc<Mask>, NodeError> {
        let element = structuring_element(self.shape, self.size)?;
        Ok(Arc::new(morphology(&self.mask, self.op, &element)))
    }
}

/// Gaussian blur of a gray or RGBA image; `sigma <= 0` returns the image unchanged.
pub fn gaussian_blur(image: &Image, sigma: f32) -> Image {
    if sigma.is_nan() || sigma <= 0.0 {
        return image.clone();
    }
    match image.channels() {
        Channels::Gray => from_gray32f(imageproc::filter::gaussian_blur_f32(&to_gray32f(image), sigma)),
        Channels::Rgba => from_rgba32f(imageproc::filter::gaussian_blur_f32(&to_rgba32f(image), sigma)),
    }
}

pyrograph_core::node! {
    /// Gaussian smoothing of a gray or RGBA image (Eigenfires thesis §3.2.1); sigma 0 passes the image through.
    #[node("imaging.gaussian_blur", "Pre-processing", PerFrame)]
    pub struct GaussianBlur {
        /// Image to blur
        image: Arc<Image>,
        /// Standard deviation in pixels; 0 is the identity
        #[range(0.0, 100.0)]
        sigma: f32 = 0.0,
    }
    /// Blurred image
    -> image: Arc<Image>
}

impl Cook for GaussianBlur {
    fn cook(self, _: &CookCtx) -> Result<Arc<Image>, NodeError> {
        // Sigma 0 is the common case in presets (a fan-out point), so keep the same Arc and skip the copy.
        let image = if self.sigma > 0.0 { Arc::new(gaussian_blur(&self.image, self.sigma)) } else { self.image };
        Ok(image)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mask(w: u32, rows: &[&str]) -> Mask {
        let data = rows.iter().flat_map(|r| r.bytes().map(|b| if b == b'#' { 255 } else { 0 })).collect();
        Mask::from_vec(w, rows.len() as u32, data).unwrap()
    }

    fn rows(m: &Mask) -> Vec<String> {
        m.data().chunks(m.width() as usize).map(|r| r.iter().map(|&v| if v != 0 { '#' } else { '.' }).collect()).collect()
    }

    #[test]
    fn ellipse_5x5_is_opencvs_element() {
        let cells: Vec<String> =
            (0..5).map(|y| (0..5).map(|x| if KernelShape::Ellipse.contains(5, x, y) { '#' } else { '.' }).collect()).collect();
        assert_eq!(cells, ["..#..", "#####", "#####", "#####", "..#.."]);
        assert!((0..3).all(|y| (0..3).all(|x| KernelShape::Cross.contains(3, x, y) == (x == 1 || y == 1))));
    }

    #[test]
    fn dilate_and_erode_with_a_cross() {
        let m = mask(5, &[".....", ".....", "..#..", ".....", "....."]);
        let e = structuring_element(KernelShape::Cross, 3).unwrap();
        let d = morphology(&m, MorphOp::Dilate, &e);
        assert_eq!(rows(&d), [".....", "..#..", ".###.", "..#..", "....."]);
        assert_eq!(morphology(&d, MorphOp::Erode, &e), m);
    }

    #[test]
    fn open_removes_specks_and_close_fills_gaps() {
        let e = structuring_element(KernelShape::Rect, 3).unwrap();
        let speck = mask(7, &["#......", ".......", "..###..", "..###..", "..###..", ".......", "......."]);
        assert_eq!(rows(&morphology(&speck, MorphOp::Open, &e))[0], ".......");
        let gap = mask(5, &["#####", "#####", "##.##", "#####", "#####"]);
        assert!(morphology(&gap, MorphOp::Close, &e).data().iter().all(|&v| v == 255));
    }

    #[test]
    fn even_or_out_of_range_sizes_are_errors() {
        for size in [0, 4, 101] {
            let err = NodeError::from(structuring_element(KernelShape::Rect, size).unwrap_err());
            assert!(matches!(&err, NodeError::Port { port, .. } if port == "size"), "{err}");
        }
    }

    #[test]
    fn blur_with_sigma_zero_is_identity_and_keeps_channels() {
        let img = Image::gray_from_fn(5, 5, |x, y| if x == 2 && y == 2 { 1.0 } else { 0.0 });
        assert_eq!(gaussian_blur(&img, 0.0), img);
        let b = gaussian_blur(&img, 1.0);
        assert_eq!(b.channels(), Channels::Gray);
        assert!(b.pixel(2, 2)[0] < 1.0 && b.pixel(1, 2)[0] > 0.0);
        let rgba = gaussian_blur(&img.to_rgba(), 1.0);
        assert_eq!(rgba.channels(), Channels::Rgba);
        assert!((rgba.pixel(1, 2)[0] - b.pixel(1, 2)[0]).abs() < 1e-6);
    }
}

#[cfg(test)]
mod proptests {
    use super::*;
    use crate::convert::{gray8_to_mask, mask_to_gray8};
    use imageproc::morphology::{grayscale_dilate, grayscale_erode};
    use proptest::prelude::*;

    /// The reference: imageproc's grayscale morphology on the mask as a gray image.
    fn reference(mask: &Mask, op: MorphOp, element: &Element) -> Mask {
        let e = element.to_imageproc();
        let img = mask_to_gray8(mask);
        gray8_to_mask(match op {
            MorphOp::Dilate => grayscale_dilate(&img, &e),
            MorphOp::Erode => grayscale_erode(&img, &e),
            MorphOp::Open => grayscale_dilate(&grayscale_erode(&img, &e), &e),
            MorphOp::Close => grayscale_erode(&grayscale_dilate(&img, &e), &e),
        })
    }

    fn arb_mask(max_side: u32) -> impl Strategy<Value = Mask> {
        (1u32..max_side, 1u32..max_side, 0.05f64..0.95).prop_flat_map(|(w, h, p)| {
            proptest::collection::vec(proptest::bool::weighted(p), (w * h) as usize)
                .prop_map(move |bits| Mask::from_vec(w, h, bits.into_iter().map(|b| if b { 255 } else { 0 }).collect()).unwrap())
        })
    }

    const OPS: [MorphOp; 4] = [MorphOp::Dilate, MorphOp::Erode, MorphOp::Open, MorphOp::Close];
    const SHAPES: [KernelShape; 3] = [KernelShape::Rect, KernelShape::Ellipse, KernelShape::Cross];

    #[test]
    fn half_widths_describe_every_element_exactly() {
        for shape in SHAPES {
            for size in (1..=99).step_by(2) {
                let e = structuring_element(shape, size).unwrap();
                let r = size / 2;
                for (y, &hw) in (0..size).zip(e.half_widths()) {
                    for x in 0..size {
                        assert_eq!(shape.contains(size, x, y), x.abs_diff(r) as usize <= hw, "{shape:?} {size} ({x}, {y})");
                    }
                }
            }
        }
    }

    #[test]
    fn matches_imageproc_on_a_large_element_and_thin_images() {
        let m = Mask::from_vec(23, 3, (0..69).map(|i| if i % 7 < 4 { 255 } else { 0 }).collect()).unwrap();
        for shape in SHAPES {
            for size in [1, 3, 5, 31, 99] {
                let e = structuring_element(shape, size).unwrap();
                for op in OPS {
                    assert_eq!(morphology(&m, op, &e), reference(&m, op, &e), "{shape:?} {size} {op:?}");
                }
            }
        }
        let empty = Mask::new(0, 0);
        assert_eq!(morphology(&empty, MorphOp::Open, &structuring_element(KernelShape::Ellipse, 5).unwrap()), empty);
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(256))]
        /// Every op, shape and the sizes of both horizontal paths (shifted passes up to
        /// half-width 6, doubling windows above) equal imageproc's grayscale morphology.
        #[test]
        fn binary_morphology_equals_imageprocs(
            m in arb_mask(40),
            op in proptest::sample::select(OPS.to_vec()),
            shape in proptest::sample::select(SHAPES.to_vec()),
            size in proptest::sample::select(vec![1u32, 3, 5, 7, 9, 11, 13, 15, 17, 21, 25, 33]),
        ) {
            let e = structuring_element(shape, size).unwrap();
            prop_assert_eq!(morphology(&m, op, &e), reference(&m, op, &e));
        }

        /// Wide rows: several packed words per row, shifts carrying across word boundaries, and
        /// rows whose width is and is not a multiple of 64.
        #[test]
        fn wide_rows_equal_imageprocs(
            w in prop_oneof![Just(64u32), Just(128), Just(129), 60u32..300],
            rows in proptest::collection::vec(proptest::collection::vec(proptest::bool::weighted(0.6), 300), 1..10),
            op in proptest::sample::select(OPS.to_vec()),
            shape in proptest::sample::select(SHAPES.to_vec()),
            size in proptest::sample::select(vec![3u32, 5, 9, 21, 41, 99]),
        ) {
            let data = rows.iter().flat_map(|r| r[..w as usize].iter().map(|&b| if b { 255 } else { 0 })).collect();
            let m = Mask::from_vec(w, rows.len() as u32, data).unwrap();
            let e = structuring_element(shape, size).unwrap();
            prop_assert_eq!(morphology(&m, op, &e), reference(&m, op, &e));
        }

        /// The bench's case, 5×5 ellipse, on masks taller than a band of rows.
        #[test]
        fn ellipse_5_open_close_equals_imageprocs(m in arb_mask(90)) {
            let e = structuring_element(KernelShape::Ellipse, 5).unwrap();
            for op in OPS {
                prop_assert_eq!(morphology(&m, op, &e), reference(&m, op, &e));
            }
        }
    }
}
