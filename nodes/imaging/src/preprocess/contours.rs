//! Contour nodes of thesis §3.2.1–3.2.3: tracing (`imaging.contours`), hole removal
//! (`imaging.hole_removal`), Douglas–Peucker simplification (`imaging.simplify_contours`),
//! filled masks (`imaging.contour_mask`) and preview overlays (`imaging.contour_overlay`).

use std::sync::Arc;

use image::{GrayImage, Luma, Rgba};
use imageproc::drawing::{draw_hollow_polygon_mut, draw_polygon_mut};
use imageproc::geometry::contour_area;
use imageproc::point::Point;
use pyrograph_core::{Contour, Contours, Cook, CookCtx, Image, Mask, NodeError};

use crate::convert::{from_rgba32f, gray8_to_mask, to_rgba32f};

/// Shoelace area of a closed polygon (always positive), via imageproc.
pub fn polygon_area(points: &[[f32; 2]]) -> f64 {
    let pts: Vec<Point<f32>> = points.iter().map(|&[x, y]| Point::new(x, y)).collect();
    contour_area(&pts)
}

/// Neighbour steps in the order imageproc's `find_contours` searches them: W, NW, N, NE, E, SE, S, SW
/// (clockwise on screen); the opposite of direction `d` is `(d + 4) % 8`.
const STEPS: [(i32, i32); 8] = [(-1, 0), (-1, -1), (0, -1), (1, -1), (1, 0), (1, 1), (0, 1), (-1, 1)];
/// Index of east in [`STEPS`].
const EAST: usize = 4;

/// One traced border: its points, whether it is an outer border, and its parent's index.
struct Traced {
    points: Vec<[i32; 2]>,
    outer: bool,
    parent: Option<usize>,
}

/// Suzuki–Abe border following, step for step as imageproc 0.27's `find_contours` (same borders,
/// same order, same points, same parents; a proptest compares the two on random masks).
///
/// Written by hand because imageproc's version spends most of its time in bookkeeping rather
/// than in following borders: it reads the mask pixel by pixel through `get_pixel`, keeps the
/// search directions in a `VecDeque` rotated by a linear search at every contour step, and
/// bounds-checks every neighbour. Here the labels carry a one-pixel zero border (so neighbours
/// need no bounds checks), directions are indices mod 8, and runs of background are skipped
/// eight bytes at a time on the mask (background pixels are never relabelled).
fn suzuki_abe(mask: &Mask) -> Vec<Traced> {
    let (w, h) = (mask.width() as usize, mask.height() as usize);
    let mut traced: Vec<Traced> = Vec::new();
    if w == 0 || h == 0 {
        return traced;
    }
    let pw = w + 2;
    let mut labels = vec![0i32; pw * (h + 2)];
    for (dst, src) in labels.chunks_exact_mut(pw).skip(1).zip(mask.data().chunks_exact(w)) {
        for (d, &s) in dst[1..=w].iter_mut().zip(src) {
            *d = i32::from(s != 0);
        }
    }
    let offsets: [isize; 8] = STEPS.map(|(dx, dy)| dy as isize * pw as isize + dx as isize);
    let at = |labels: &[i32], i: usize, d: usize| -> (usize, i32) {
        let j = i.wrapping_add_signed(offsets[d]);
        (j, labels.get(j).copied().unwrap_or(0))
    };
    let mut curr_border_num: i32 = 1;
    for (y, row) in mask.data().chunks_exact(w).enumerate() {
        let mut parent_border_num: i32 = 1;
        let mut x = 0;
        while x < w {
            // Skip background (untouched by tracing) eight pixels at a time.
            if let Some(chunk) = row.get(x..x + 8)
                && chunk.iter().all(|&v| v == 0)
            {
                x += 8;
                continue;
            }
            let i = (y + 1) * pw + x + 1;
            let value = labels[i];
            if value == 0 {
                x += 1;
                continue;
            }
            let start = if value == 1 && x > 0 && labels[i - 1] == 0 {
                Some((0, true))
            } else if value > 0 && x + 1 < w && labels[i + 1] == 0 {
                if value > 1 {
                    parent_border_num = value;
                }
                Some((EAST, false))
            } else {
                None
            };
            if let Some((adj, outer)) = start {
                curr_border_num += 1;
                let parent = if parent_border_num > 1 {
                    let parent_index = (parent_border_num - 2) as usize;
                    traced.get(parent_index).and_then(|p| if outer ^ p.outer { Some(parent_index) } else { p.parent })
                } else {
                    None
                };
                let mut points = Vec::new();
                let first = (0..8).map(|k| (adj + k) % 8).find(|&d| at(&labels, i, d).1 != 0);
                if let Some(d1) = first {
                    let pos1 = at(&labels, i, d1).0;
                    // pos3 is the current border pixel, `back` the direction from it to the previous one.
                    let (mut pos3, mut x3, mut y3, mut back) = (i, x as i32, y as i32, d1);
                    loop {
                        points.push([x3, y3]);
                        // Counter-clockwise from just before `back`; `back` itself is non-zero, so this finds one.
                        let d4 = (1..=8).map(|k| (back + 8 - k) % 8).find(|&d| at(&labels, pos3, d).1 != 0).unwrap_or(back);
                        let is_right_edge = (1..=8).map(|k| (back + 8 - k) % 8).take_while(|&d| d != d4).any(|d| d == EAST);
                        if x3 as usize + 1 == w || is_right_edge {
                            labels[pos3] = -curr_border_num;
                        } else if labels[pos3] == 1 {
                            labels[pos3] = curr_border_num;
                        }
                        let pos4 = at(&labels, pos3, d4).0;
                        if pos4 == i && pos3 == pos1 {
                            break;
                        }
                        pos3 = pos4;
                        x3 += STEPS[d4].0;
                        y3 += STEPS[d4].1;
                        back = (d4 + 4) % 8;
                    }
                } else {
                    points.push([x as i32, y as i32]);
                    labels[i] = -curr_border_num;
                }
                traced.push(Traced { points, outer, parent });
            }
            if labels[i] != 1 {
                parent_border_num = labels[i].abs();
            }
            x += 1;
        }
    }
    traced
}

/// imageproc's `contour_area` (shoelace, same order of f64 operations) on integer points.
fn traced_area(points: &[[i32; 2]]) -> f64 {
    let Some(&last) = points.last() else { return 0.0 };
    if points.len() < 3 {
        return 0.0;
    }
    let mut prev = [f64::from(last[0]), f64::from(last[1])];
    let mut accum = 0.0;
    for p in points {
        let p = [f64::from(p[0]), f64::from(p[1])];
        accum += prev[0] * p[1] - prev[1] * p[0];
        prev = p;
    }
    (0.5 * accum).abs()
}

/// Traces every border of `mask` (Suzuki–Abe border following, as imageproc's `find_contours`).
///
/// Depth counts enclosing borders (0 = outermost, 1 = a hole in it, 2 = an island in the hole …);
/// parents precede their children. An empty mask gives an empty list, not an error.
pub fn trace_contours(mask: &Mask) -> Contours {
    let traced = suzuki_abe(mask);
    let mut depths: Vec<u32> = Vec::with_capacity(traced.len());
    let mut contours = Vec::with_capacity(traced.len());
    for c in traced {
        // Suzuki–Abe finds a parent before its children in raster order, so its depth is known.
        let depth = c.parent.and_then(|p| depths.get(p)).map_or(0, |d| d + 1);
        depths.push(depth);
        let area = traced_area(&c.points);
        let points: Vec<[f32; 2]> = c.points.iter().map(|p| [p[0] as f32, p[1] as f32]).collect();
        contours.push(Contour { area, points, depth, parent: c.parent });
    }
    Contours { width: mask.width(), height: mask.height(), contours }
}

/// Keeps contours with `depth <= max_depth` and `area >= min_area`; the children of a dropped
/// contour are dropped too, and parents are re-indexed into the shorter list (thesis §3.2.2).
pub fn remove_holes(contours: &Contours, max_depth: u32, min_area: f64) -> Contours {
    retain_contours(contours, |_, c| c.depth <= max_depth && c.area >= min_area)
}

/// Keeps the `n` largest outermost contours (by area) with everything nested in them; `n = 0`
/// keeps all. Reflections and glowing surroundings that survive the HSV mask as separate blobs
/// go, the flame stays.
pub fn keep_largest(contours: &Contours, n: usize) -> Contours {
    if n == 0 {
        return contours.clone();
    }
    let mut outer: Vec<(usize, f64)> =
        contours.contours.iter().enumerate().filter(|(_, c)| c.parent.is_none()).map(|(i, c)| (i, c.area)).collect();
    outer.sort_by(|a, b| b.1.total_cmp(&a.1));
    let chosen: Vec<usize> = outer.into_iter().take(n).map(|(i, _)| i).collect();
    retain_contours(contours, |i, c| c.parent.is_some() || chosen.contains(&i))
}

/// Drops the contours `keep` refuses, with all their descendants, re-indexing parents.
/// Relies on parents coming before their children in the list (as traced).
pub(crate) fn retain_contours(contours: &Contours, keep: impl Fn(usize, &Contour) -> bool) -> Contours {
    let mut new_index: Vec<Option<usize>> = Vec::with_capacity(contours.contours.len());
    let mut kept = Vec::new();
    for (i, c) in contours.contours.iter().enumerate() {
        let parent_kept = match c.parent {
            None => Some(None),
            Some(p) => new_index.get(p).copied().flatten().map(Some),
        };
        match parent_kept {
            Some(parent) if keep(i, c) => {
                new_index.push(Some(kept.len()));
                kept.push(Contour { parent, ..c.clone() });
            }
            _ => new_index.push(None),
        }
    }
    Contours { width: contours.width, height: contours.height, contours: kept }
}

/// Distance from `p` to the segment `a`–`b` (to `a` when the segment is a point).
fn segment_distance(p: [f32; 2], a: [f32; 2], b: [f32; 2]) -> f64 {
    let (px, py, ax, ay, bx, by) = (p[0] as f64, p[1] as f64, a[0] as f64, a[1] as f64, b[0] as f64, b[1] as f64);
    let (dx, dy) = (bx - ax, by - ay);
    let len2 = dx * dx + dy * dy;
    let t = if len2 > 0.0 { (((px - ax) * dx + (py - ay) * dy) / len2).clamp(0.0, 1.0) } else { 0.0 };
    ((px - ax - t * dx).powi(2) + (py - ay - t * dy).powi(2)).sqrt()
}

/// Indices kept by Douglas–Peucker on the open polyline `points[first..=last]`.
///
/// Written by hand instead of calling imageproc's `approximate_polygon_dp` because that one
/// measures distance to the infinite chord line, so a traced contour's one-pixel spur folding
/// back along the chord is dropped though it lies far outside tolerance, and it panics on an
/// empty curve or zero tolerance. This is the thesis's second method (§3.2.3): pending floating
/// points wait on a stack instead of recursing.
fn dp_open(points: &[[f32; 2]], first: usize, last: usize, tolerance: f64, keep: &mut [bool]) {
    let mut stack = vec![(first, last)];
    while let Some((anchor, floating)) = stack.pop() {
        let (Some(&a), Some(&b)) = (points.get(anchor), points.get(floating)) else { continue };
        let farthest = (anchor + 1..floating).filter_map(|i| points.get(i).map(|&p| (i, segment_distance(p, a, b)))).fold(
            None,
            |best: Option<(usize, f64)>, (i, d)| match best {
                Some((_, bd)) if bd >= d => best,
                _ => Some((i, d)),
            },
        );
        if let Some((i, d)) = farthest
            && d > tolerance
        {
            if let Some(k) = keep.get_mut(i) {
                *k = true;
            }
            stack.push((i, floating));
            stack.push((anchor, i));
        }
    }
}

/// Douglas–Peucker on a closed curve: the result is a subsequence of `points` and every input
/// point lies within `tolerance` of the closed simplified polygon. `tolerance <= 0` or fewer
/// than four points return the input unchanged.
///
/// The curve is split at its first point and the point farthest from it (OpenCV does the same
/// for closed curves), and each half is simplified as an open polyline.
pub fn simplify_closed(points: &[[f32; 2]], tolerance: f64) -> Vec<[f32; 2]> {
    if tolerance.is_nan() || tolerance <= 0.0 || points.len() < 4 {
        return points.to_vec();
    }
    let Some(&start) = points.first() else { return Vec::new() };
    let far = (1..points.len())
        .filter_map(|i| points.get(i).map(|&p| (i, segment_distance(p, start, start))))
        .fold((0, -1.0), |best, (i, d)| if d > best.1 { (i, d) } else { best })
        .0;
    if far == 0 {
        return vec![start];
    }
    // Close the loop by appending the start point, simplify both halves, then drop the duplicate.
    let mut ring = points.to_vec();
    ring.push(start);
    let mut keep = vec![false; ring.len()];
    let last = ring.len() - 1;
    for i in [0, far, last] {
        if let Some(k) = keep.get_mut(i) {
            *k = true;
        }
    }
    dp_open(&ring, 0, far, tolerance, &mut keep);
    dp_open(&ring, far, last, tolerance, &mut keep);
    ring.iter().zip(&keep).take(last).filter(|(_, k)| **k).map(|(p, _)| *p).collect()
}

/// Simplifies every contour (closed Douglas–Peucker) and recomputes its area.
pub fn simplify_contours(contours: &Contours, tolerance: f64) -> Contours {
    let contours_out = contours
        .contours
        .iter()
        .map(|c| {
            let points = simplify_closed(&c.points, tolerance);
            Contour { area: polygon_area(&points), points, ..c.clone() }
        })
        .collect();
    Contours { width: contours.width, height: contours.height, contours: contours_out }
}

fn int_points(points: &[[f32; 2]]) -> Vec<Point<i32>> {
    let mut pts: Vec<Point<i32>> = points.iter().map(|&[x, y]| Point::new(x.round() as i32, y.round() as i32)).collect();
    // imageproc treats an explicitly repeated first point as the closing edge; drop it to keep one convention.
    if pts.len() > 1 && pts.first() == pts.last() {
        pts.pop();
    }
    pts
}

/// Fills the contours into a mask: even depths fill, odd depths (holes) cut, parents before
/// children. Hole borders are traced on inside pixels, so after cutting a hole its border is
/// drawn back; a traced mask therefore round-trips.
pub fn fill_contours(contours: &Contours) -> Mask {
    let mut canvas = GrayImage::new(contours.width, contours.height);
    let mut order: Vec<&Contour> = contours.contours.iter().collect();
    order.sort_by_key(|c| c.depth);
    for c in order {
        let pts = int_points(&c.points);
        if pts.is_empty() {
            continue;
        }
        let fill = if c.is_hole() { 0 } else { 255 };
        draw_polygon_mut(&mut canvas, &pts, Luma([fill]));
        if c.is_hole() {
            draw_outline(&mut canvas, &c.points, Luma([255]));
        }
    }
    gray8_to_mask(canvas)
}

fn draw_outline<C: imageproc::drawing::Canvas>(canvas: &mut C, points: &[[f32; 2]], colour: C::Pixel) {
    match points {
        [] => {}
        [[x, y]] => {
            let (w, h) = canvas.dimensions();
            if *x >= 0.0 && *y >= 0.0 && (*x as u32) < w && (*y as u32) < h {
                canvas.draw_pixel(*x as u32, *y as u32, colour);
            }
        }
        _ => {
            let pts: Vec<Point<f32>> = points.iter().map(|&[x, y]| Point::new(x, y)).collect();
            draw_hollow_polygon_mut(canvas, &pts, colour);
        }
    }
}

/// Draws contour outlines over an RGBA copy of `image`: outer borders (even depth) in `outer`,
/// holes in `hole`.
pub fn overlay_contours(image: &Image, contours: &Contours, outer: [f32; 4], hole: [f32; 4]) -> Image {
    let mut canvas = to_rgba32f(image);
    for c in &contours.contours {
        let colour = if c.is_hole() { hole } else { outer };
        draw_outline(&mut canvas, &c.points, Rgba(colour));
    }
    from_rgba32f(canvas)
}

pyrograph_core::node! {
    /// Traces the borders of a mask with their hierarchy depth and area (Eigenfires thesis §3.2.1, border following).
    ///
    /// Depth 0 is an outermost border, 1 a hole in it, 2 an island in that hole; area is the shoelace area of
    /// the pixel-centre polygon. An empty mask gives no contours (not an error).
    #[node("imaging.contours", "Pre-processing", PerFrame)]
    pub struct TraceContours {
        /// Binary mask to trace
        mask: Arc<Mask>,
    }
    /// Every border, parents before children
    -> contours: Arc<Contours>
}

impl Cook for TraceContours {
    fn cook(self, _: &CookCtx) -> Result<Arc<Contours>, NodeError> {
        Ok(Arc::new(trace_contours(&self.mask)))
    }
}

pyrograph_core::node! {
    /// Depth- and area-based Hole Removal (Eigenfires thesis §3.2.2).
    ///
    /// Keeps contours with depth ≤ max_depth and area ≥ min_area; children of a dropped contour are dropped too.
    /// max_depth 0 keeps only outer flame borders; max_depth 1 on a dark-background mask whose HSV ranges take
    /// in the smoke keeps two nested contours in one step: the outer one bounds the smoke or soot and the inner
    /// one the bright flame.
    #[node("imaging.hole_removal", "Pre-processing", PerFrame)]
    pub struct HoleRemoval {
        /// Traced contours
        contours: Arc<Contours>,
        /// Deepest nesting level kept (0 = outer borders only)
        #[range(0, 1000)]
        max_depth: u32 = 0,
        /// Smallest area kept, in square pixels
        #[range(0.0, 1.0e9)]
        min_area: f64 = 100.0,
        /// Then keep only this many largest outer contours with their holes (0 = all); drops reflections and glow blobs
        #[range(0, 1_000_000)]
        keep_largest: usize = 0,
    }
    /// Kept contours, parents re-indexed
    -> contours: Arc<Contours>
}

impl Cook for HoleRemoval {
    fn cook(self, _: &CookCtx) -> Result<Arc<Contours>, NodeError> {
        let kept = remove_holes(&self.contours, self.max_depth, self.min_area);
        Ok(Arc::new(keep_largest(&kept, self.keep_largest)))
    }
}

pyrograph_core::node! {
    /// Contour optimization with the Douglas–Peucker algorithm on closed curves (Eigenfires thesis §3.2.3).
    ///
    /// Every removed point lies within `tolerance` pixels of the simplified polygon; areas are recomputed.
    #[node("imaging.simplify_contours", "Pre-processing", PerFrame)]
    pub struct SimplifyContours {
        /// Contours to simplify
        contours: Arc<Contours>,
        /// Largest distance in pixels a removed point may lie from the result; 0 keeps all
        #[range(0.0, 1000.0)]
        tolerance: f64 = 2.0,
    }
    /// Simplified contours
    -> contours: Arc<Contours>
}

impl Cook for SimplifyContours {
    fn cook(self, _: &CookCtx) -> Result<Arc<Contours>, NodeError> {
        Ok(Arc::new(simplify_contours(&self.contours, self.tolerance)))
    }
}

pyrograph_core::node! {
    /// Fills contours into a mask of the traced image's size, holes cut by depth parity (Eigenfires thesis §3.3.1, Fig. 20d).
    ///
    /// Even depths fill, odd depths cut; the result protects the flame in Hermite background removal.
    #[node("imaging.contour_mask", "Pre-processing", PerFrame)]
    pub struct ContourMask {
        /// Contours to fill
        contours: Arc<Contours>,
    }
    /// Filled mask
    -> mask: Arc<Mask>
}

impl Cook for ContourMask {
    fn cook(self, _: &CookCtx) -> Result<Arc<Mask>, NodeError> {
        Ok(Arc::new(fill_contours(&self.contours)))
    }
}

pyrograph_core::node! {
    /// Draws contours over an image for previews (Eigenfires thesis §3.2, Fig. 18).
    ///
    /// Outer borders and holes get different colours; the output is RGBA.
    #[node("imaging.contour_overlay", "Pre-processing", PerFrame)]
    pub struct ContourOverlay {
        /// Background image (gray or RGBA)
        image: Arc<Image>,
        /// Contours to draw
        contours: Arc<Contours>,
        /// Colour of outer borders (even depth)
        color: [f32; 4] = [0.0, 1.0, 0.0, 1.0],
        /// Colour of hole borders (odd depth)
        hole_color: [f32; 4] = [1.0, 0.0, 1.0, 1.0],
    }
    /// RGBA preview
    -> image: Arc<Image>
}

impl Cook for ContourOverlay {
    fn cook(self, _: &CookCtx) -> Result<Arc<Image>, NodeError> {
        Ok(Arc::new(overlay_contours(&self.image, &self.contours, self.color, self.hole_color)))
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    fn square(x0: f32, y0: f32, side: f32, depth: u32, parent: Option<usize>) -> Contour {
        let points = vec![[x0, y0], [x0 + side, y0], [x0 + side, y0 + side], [x0, y0 + side]];
        Contour { area: polygon_area(&points), points, depth, parent }
    }

    #[test]
    fn keep_largest_keeps_the_biggest_outer_contours_with_their_holes() {
        let contours = Contours {
            width: 100,
            height: 100,
            contours: vec![
                square(0.0, 0.0, 10.0, 0, None),
                square(20.0, 20.0, 30.0, 0, None),
                square(25.0, 25.0, 5.0, 1, Some(1)),
                square(60.0, 60.0, 20.0, 0, None),
            ],
        };
        let one = keep_largest(&contours, 1);
        assert_eq!(one.contours.len(), 2, "the 30-px square and its hole");
        assert_eq!(one.contours[0].area, 900.0);
        assert_eq!(one.contours[1].parent, Some(0), "hole re-indexed to its parent");
        let two = keep_largest(&contours, 2);
        let areas: Vec<f64> = two.contours.iter().map(|c| c.area).collect();
        assert_eq!(areas, vec![900.0, 25.0, 400.0]);
        assert_eq!(keep_largest(&contours, 0), contours);
    }

    /// A mask from rows of `#` (inside) and `.` (outside).
    pub(crate) fn mask(rows: &[&str]) -> Mask {
        let w = rows.first().map_or(0, |r| r.len()) as u32;
        let data = rows.iter().flat_map(|r| r.bytes().map(|b| if b == b'#' { 255 } else { 0 })).collect();
        Mask::from_vec(w, rows.len() as u32, data).unwrap()
    }

    /// A 9×9 square with a 3×3 hole, inside an 11×11 frame.
    fn ring() -> Mask {
        let rows: Vec<String> = (0..11)
            .map(|y| {
                (0..11)
                    .map(|x| {
                        if (1..=9).contains(&x) && (1..=9).contains(&y) && !((4..=6).contains(&x) && (4..=6).contains(&y)) {
                            '#'
                        } else {
                            '.'
                        }
                    })
                    .collect()
            })
            .collect();
        mask(&rows.iter().map(String::as_str).collect::<Vec<_>>())
    }

    fn contour(points: &[[f32; 2]], depth: u32, parent: Option<usize>, area: f64) -> Contour {
        Contour { points: points.to_vec(), depth, parent, area }
    }

    #[test]
    fn ring_has_an_outer_border_and_a_hole() {
        let c = trace_contours(&ring());
        assert_eq!((c.width, c.height, c.contours.len()), (11, 11, 2));
        let (outer, hole) = (&c.contours[0], &c.contours[1]);
        assert_eq!((outer.depth, outer.parent, outer.area), (0, None, 64.0));
        // The hole border runs on the inside pixels around the 3×3 hole, cutting its corners: a 4×4 square minus 4 half-pixel corners.
        assert_eq!((hole.depth, hole.parent, hole.area), (1, Some(0), 14.0));
        assert!(hole.is_hole() && !outer.is_hole());
    }

    #[test]
    fn empty_mask_gives_no_contours() {
        let c = trace_contours(&Mask::new(4, 3));
        assert_eq!((c.width, c.height), (4, 3));
        assert!(c.contours.is_empty());
        assert_eq!(fill_contours(&c), Mask::new(4, 3));
    }

    #[test]
    fn filled_contours_round_trip_a_ring() {
        let m = ring();
        assert_eq!(fill_contours(&trace_contours(&m)), m);
    }

    fn nested() -> Contours {
        // 0: big outer, 1: hole in it, 2: island in the hole, 3: small separate speck.
        let sq = |a: f32, b: f32| [[a, a], [b, a], [b, b], [a, b]];
        Contours {
            width: 40,
            height: 40,
            contours: vec![
                contour(&sq(0.0, 30.0), 0, None, 900.0),
                contour(&sq(5.0, 25.0), 1, Some(0), 400.0),
                contour(&sq(10.0, 20.0), 2, Some(1), 100.0),
                contour(&sq(32.0, 34.0), 0, None, 4.0),
            ],
        }
    }

    #[test]
    fn hole_removal_by_depth() {
        let c = nested();
        let depth0 = remove_holes(&c, 0, 0.0);
        assert_eq!(depth0.contours.iter().map(|c| c.area).collect::<Vec<_>>(), [900.0, 4.0]);
        let depth1 = remove_holes(&c, 1, 0.0);
        assert_eq!(
            depth1.contours.iter().map(|c| (c.area, c.parent)).collect::<Vec<_>>(),
            [(900.0, None), (400.0, Some(0)), (4.0, None)]
        );
    }

    #[test]
    fn hole_removal_by_area_drops_children_and_reindexes() {
        let c = nested();
        let kept = remove_holes(&c, 5, 100.0);
        assert_eq!(
            kept.contours.iter().map(|c| (c.area, c.parent)).collect::<Vec<_>>(),
            [(900.0, None), (400.0, Some(0)), (100.0, Some(1))]
        );
        let no_hole = remove_holes(&c, 5, 500.0);
        // The island's parent (the 400 px² hole) is gone, so the island goes with it.
        assert_eq!(no_hole.contours.iter().map(|c| c.area).collect::<Vec<_>>(), [900.0]);
    }

    #[test]
    fn simplify_keeps_the_corners_of_a_traced_square() {
        let m = mask(&["......", ".####.", ".####.", ".####.", ".####.", "......"]);
        let c = simplify_contours(&trace_contours(&m), 0.5);
        let mut pts = c.contours[0].points.clone();
        pts.sort_by(|a, b| a.partial_cmp(b).unwrap());
        assert_eq!(pts, [[1.0, 1.0], [1.0, 4.0], [4.0, 1.0], [4.0, 4.0]]);
        assert_eq!(c.contours[0].area, 9.0);
    }

    #[test]
    fn a_spur_folding_back_along_the_chord_is_kept() {
        // Out along x to 10 and back: an infinite-line distance would call every point on the chord.
        let spur: Vec<[f32; 2]> = (0..=10).chain((1..10).rev()).map(|x| [x as f32, 0.0]).chain([[0.0, 1.0]]).collect();
        let s = simplify_closed(&spur, 1.0);
        assert!(s.contains(&[10.0, 0.0]), "{s:?}");
    }

    #[test]
    fn simplify_with_zero_tolerance_or_few_points_is_identity() {
        let pts = [[0.0, 0.0], [1.0, 0.0], [2.0, 0.1], [1.0, 1.0]];
        assert_eq!(simplify_closed(&pts, 0.0), pts);
        assert_eq!(simplify_closed(&pts[..3], 5.0), &pts[..3]);
        assert!(simplify_closed(&[], 1.0).is_empty());
    }

    #[test]
    fn overlay_draws_outer_and_hole_colours() {
        let c = trace_contours(&ring());
        let img = Image::new(11, 11, pyrograph_core::Channels::Gray);
        let out = overlay_contours(&img, &c, [0.0, 1.0, 0.0, 1.0], [1.0, 0.0, 1.0, 1.0]);
        assert_eq!(out.channels(), pyrograph_core::Channels::Rgba);
        assert_eq!(out.pixel(1, 1), [0.0, 1.0, 0.0, 1.0]);
        assert_eq!(out.pixel(5, 3), [1.0, 0.0, 1.0, 1.0]);
        assert_eq!(out.pixel(0, 0), [0.0, 0.0, 0.0, 1.0]);
    }
}

#[cfg(test)]
mod proptests {
    use super::*;
    use proptest::prelude::*;

    fn arb_mask() -> impl Strategy<Value = Mask> {
        (1u32..16, 1u32..16).prop_flat_map(|(w, h)| {
            proptest::collection::vec(proptest::bool::weighted(0.55), (w * h) as usize)
                .prop_map(move |bits| Mask::from_vec(w, h, bits.into_iter().map(|b| if b { 255 } else { 0 }).collect()).unwrap())
        })
    }

    fn on_border(m: &Mask, x: i64, y: i64) -> bool {
        let inside =
            |x: i64, y: i64| x >= 0 && y >= 0 && x < m.width() as i64 && y < m.height() as i64 && m.get(x as u32, y as u32);
        if !inside(x, y) {
            return false;
        }
        (-1..=1).any(|dy| (-1..=1).any(|dx| (dx, dy) != (0, 0) && !inside(x + dx, y + dy)))
    }

    fn dist_to_polygon(p: [f32; 2], poly: &[[f32; 2]]) -> f64 {
        match poly {
            [] => f64::INFINITY,
            [a] => segment_distance(p, *a, *a),
            _ => (0..poly.len()).map(|i| segment_distance(p, poly[i], poly[(i + 1) % poly.len()])).fold(f64::INFINITY, f64::min),
        }
    }

    fn is_subsequence(sub: &[[f32; 2]], of: &[[f32; 2]]) -> bool {
        let mut it = of.iter();
        sub.iter().all(|p| it.any(|q| q == p))
    }

    /// The reference: imageproc's `find_contours` as `trace_contours` used it before the hand-written tracer.
    fn reference_trace(mask: &Mask) -> Contours {
        let traced = imageproc::contours::find_contours::<i32>(&crate::convert::mask_to_gray8(mask));
        let mut depths: Vec<u32> = Vec::with_capacity(traced.len());
        let mut contours = Vec::with_capacity(traced.len());
        for c in &traced {
            let depth = c.parent.and_then(|p| depths.get(p)).map_or(0, |d| d + 1);
            depths.push(depth);
            let points: Vec<[f32; 2]> = c.points.iter().map(|p| [p.x as f32, p.y as f32]).collect();
            contours.push(Contour { area: contour_area(&c.points), points, depth, parent: c.parent });
        }
        Contours { width: mask.width(), height: mask.height(), contours }
    }

    fn arb_sized_mask(max_side: u32) -> impl Strategy<Value = Mask> {
        (1u32..max_side, 1u32..max_side, 0.05f64..0.95).prop_flat_map(|(w, h, p)| {
            proptest::collection::vec(proptest::bool::weighted(p), (w * h) as usize)
                .prop_map(move |bits| Mask::from_vec(w, h, bits.into_iter().map(|b| if b { 255 } else { 0 }).collect()).unwrap())
        })
    }

    #[test]
    fn tracer_equals_imageprocs_on_blobs_touching_every_edge() {
        let m = super::tests::mask(&[
            "##..##########..#",
            "##..#........#..#",
            "....#..###...#...",
            "#...#..#.#...#..#",
            "##..##########.##",
        ]);
        assert_eq!(trace_contours(&m), reference_trace(&m));
        let full = Mask::from_vec(37, 5, vec![255; 185]).unwrap();
        assert_eq!(trace_contours(&full), reference_trace(&full));
        assert!(trace_contours(&Mask::new(0, 3)).contours.is_empty());
    }

    proptest! {
        /// Same borders, points, order, parents, depths and areas as imageproc's `find_contours`.
        #[test]
        fn tracer_equals_imageprocs(m in arb_sized_mask(48)) {
            prop_assert_eq!(trace_contours(&m), reference_trace(&m));
        }

        #[test]
        fn every_contour_point_lies_on_the_mask_border(m in arb_mask()) {
            let c = trace_contours(&m);
            for contour in &c.contours {
                prop_assert!(!contour.points.is_empty());
                for &[x, y] in &contour.points {
                    prop_assert!(on_border(&m, x as i64, y as i64), "({x}, {y}) is not a border pixel");
                }
                let parent_ok = contour.parent.is_none_or(|p| c.contours.get(p).is_some_and(|q| q.depth + 1 == contour.depth));
                prop_assert!(parent_ok);
            }
        }

        #[test]
        fn douglas_peucker_is_a_subsequence_within_tolerance(m in arb_mask(), tolerance in 0.1f64..4.0) {
            for contour in trace_contours(&m).contours {
                let s = simplify_closed(&contour.points, tolerance);
                prop_assert!(is_subsequence(&s, &contour.points));
                for &p in &contour.points {
                    let d = dist_to_polygon(p, &s);
                    prop_assert!(d <= tolerance + 1e-9, "{p:?} is {d} from {s:?}");
                }
            }
        }
    }
}
