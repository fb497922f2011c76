//! `imaging.morphology` and `imaging.gaussian_blur`: the clean-up filters of thesis §3.2.1,
//! built on imageproc's mask-based grayscale morphology and Gaussian blur.

use std::sync::Arc;

use image::{GrayImage, Luma};
use imageproc::morphology::{Mask as Element, grayscale_dilate, grayscale_erode};
use pyrograph_core::{
    Channels, CookCtx, FnNode, Image, Inputs, Mask, Node, NodeDesc, NodeError, PortDesc, PortType, TimeDep, Value,
};

use crate::convert::{from_gray32f, from_rgba32f, gray8_to_mask, mask_to_gray8, to_gray32f, to_rgba32f};

/// A morphological operation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MorphOp {
    /// Grows the mask.
    Dilate,
    /// Shrinks the mask.
    Erode,
    /// Erode then dilate: removes specks smaller than the element.
    Open,
    /// Dilate then erode: fills gaps smaller than the element.
    Close,
}

impl MorphOp {
    /// Parameter names.
    pub const NAMES: [&'static str; 4] = ["dilate", "erode", "open", "close"];

    /// Parses a parameter value.
    pub fn parse(name: &str) -> Option<MorphOp> {
        match name {
            "dilate" => Some(MorphOp::Dilate),
            "erode" => Some(MorphOp::Erode),
            "open" => Some(MorphOp::Open),
            "close" => Some(MorphOp::Close),
            _ => None,
        }
    }
}

/// Shape of the structuring element.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum KernelShape {
    /// A full `size × size` square.
    Rect,
    /// The ellipse inscribed in the square, as OpenCV's `MORPH_ELLIPSE`.
    Ellipse,
    /// The centre row and column.
    Cross,
}

impl KernelShape {
    /// Parameter names.
    pub const NAMES: [&'static str; 3] = ["rect", "ellipse", "cross"];

    /// Parses a parameter value.
    pub fn parse(name: &str) -> Option<KernelShape> {
        match name {
            "rect" => Some(KernelShape::Rect),
            "ellipse" => Some(KernelShape::Ellipse),
            "cross" => Some(KernelShape::Cross),
            _ => None,
        }
    }

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

/// The imageproc structuring element of `shape` and odd `size` (1..=99).
pub fn structuring_element(shape: KernelShape, size: u32) -> Result<Element, NodeError> {
    if size % 2 == 0 || !(1..=99).contains(&size) {
        return Err(NodeError::port("size", format!("must be odd and in 1..=99, got {size}")));
    }
    let img = GrayImage::from_fn(size, size, |x, y| Luma([if shape.contains(size, x, y) { 255 } else { 0 }]));
    let centre = (size / 2) as u8;
    Ok(Element::from_image(&img, centre, centre))
}

/// Applies `op` with `element` to a binary mask. Pixels outside the image never grow the mask
/// and never erode it (OpenCV's default border for morphology).
pub fn morphology(mask: &Mask, op: MorphOp, element: &Element) -> Mask {
    let img = mask_to_gray8(mask);
    let out = match op {
        MorphOp::Dilate => grayscale_dilate(&img, element),
        MorphOp::Erode => grayscale_erode(&img, element),
        MorphOp::Open => grayscale_dilate(&grayscale_erode(&img, element), element),
        MorphOp::Close => grayscale_erode(&grayscale_dilate(&img, element), element),
    };
    gray8_to_mask(out)
}

/// Description of `imaging.morphology`.
pub fn desc() -> NodeDesc {
    NodeDesc::new(
        "imaging.morphology",
        "Pre-processing",
        TimeDep::PerFrame,
        "Dilates, erodes, opens or closes a mask to filter noise (Eigenfires thesis §3.2.1).\n\
         The structuring element is a rect, ellipse (OpenCV MORPH_ELLIPSE) or cross of odd size.",
    )
    .input(PortDesc::new("mask", PortType::Mask, "Mask to filter"))
    .input(PortDesc::choice("op", &MorphOp::NAMES, "open", "Operation: open removes specks, close fills gaps"))
    .input(PortDesc::choice("shape", &KernelShape::NAMES, "ellipse", "Structuring element shape"))
    .input(PortDesc::int("size", 5, (1, 99), "Element width and height in pixels; must be odd"))
    .output("mask", PortType::Mask, "Filtered mask")
}

fn cook(inputs: &Inputs<'_>, _ctx: &CookCtx) -> Result<Vec<Value>, NodeError> {
    let mask = inputs.mask("mask")?;
    let op_name = inputs.choice("op")?;
    let op = MorphOp::parse(op_name).ok_or_else(|| NodeError::port("op", format!("unknown operation '{op_name}'")))?;
    let shape_name = inputs.choice("shape")?;
    let shape =
        KernelShape::parse(shape_name).ok_or_else(|| NodeError::port("shape", format!("unknown shape '{shape_name}'")))?;
    let size = inputs.int("size")?;
    let size = u32::try_from(size).map_err(|_| NodeError::port("size", format!("must be odd and in 1..=99, got {size}")))?;
    let element = structuring_element(shape, size)?;
    Ok(vec![Value::Mask(Arc::new(morphology(mask, op, &element)))])
}

/// The `imaging.morphology` node.
pub fn node() -> Arc<dyn Node> {
    FnNode::new(desc(), cook)
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

/// Description of `imaging.gaussian_blur`.
pub fn blur_desc() -> NodeDesc {
    NodeDesc::new(
        "imaging.gaussian_blur",
        "Pre-processing",
        TimeDep::PerFrame,
        "Gaussian smoothing of a gray or RGBA image (Eigenfires thesis §3.2.1); sigma 0 passes the image through.",
    )
    .input(PortDesc::new("image", PortType::Image, "Image to blur"))
    .input(PortDesc::float("sigma", 0.0, (0.0, 100.0), "Standard deviation in pixels; 0 is the identity"))
    .output("image", PortType::Image, "Blurred image")
}

fn blur_cook(inputs: &Inputs<'_>, _ctx: &CookCtx) -> Result<Vec<Value>, NodeError> {
    let image = inputs.image("image")?;
    let sigma = inputs.float("sigma")? as f32;
    // Sigma 0 is the common case in presets (a fan-out point), so keep the same Arc and skip the copy.
    let out = if sigma > 0.0 { Arc::new(gaussian_blur(image, sigma)) } else { Arc::clone(image) };
    Ok(vec![Value::Image(out)])
}

/// The `imaging.gaussian_blur` node.
pub fn blur_node() -> Arc<dyn Node> {
    FnNode::new(blur_desc(), blur_cook)
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
            let err = structuring_element(KernelShape::Rect, size).unwrap_err();
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
