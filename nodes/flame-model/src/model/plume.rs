//! One frame's flame (Stich & Magnor §3, §5): the gray values thresholded, specks removed, and
//! the single plume kept with its moments; a frame of two or more plumes is told apart.

use super::fit_settings::FitSettings;
use super::shape::{Moments, plumes};

/// One frame's single flame: the cleaned gray values inside its bounding box, and its moments.
#[derive(Clone, Debug, PartialEq)]
pub struct Plume {
    /// Left column of the box in the frame.
    pub x0: usize,
    /// Top row of the box in the frame.
    pub y0: usize,
    /// Box width.
    pub width: usize,
    /// Box height.
    pub height: usize,
    /// Gray values (background and specks zeroed), row-major `width × height`.
    pub data: Vec<f32>,
    /// Moments in frame coordinates.
    pub moments: Moments,
}

impl Plume {
    /// Bilinear sample at frame point (x, y) (pixel centres at +0.5), 0 outside the box.
    pub(super) fn sample(&self, x: f64, y: f64) -> f32 {
        let fx = x - 0.5 - self.x0 as f64;
        let fy = y - 0.5 - self.y0 as f64;
        if fx <= -1.0 || fy <= -1.0 || fx >= self.width as f64 || fy >= self.height as f64 {
            return 0.0;
        }
        let (ix, iy) = (fx.floor(), fy.floor());
        let (tx, ty) = ((fx - ix) as f32, (fy - iy) as f32);
        let (ix, iy) = (ix as isize, iy as isize);
        let at = |cx: isize, cy: isize| -> f32 {
            if cx < 0 || cy < 0 || cx >= self.width as isize || cy >= self.height as isize {
                0.0
            } else {
                self.data[cy as usize * self.width + cx as usize]
            }
        };
        let top = at(ix, iy) * (1.0 - tx) + at(ix + 1, iy) * tx;
        let bottom = at(ix, iy + 1) * (1.0 - tx) + at(ix + 1, iy + 1) * tx;
        top * (1.0 - ty) + bottom * ty
    }
}

/// What one frame holds.
#[derive(Clone, Debug, PartialEq)]
pub enum Frame {
    /// One flame.
    Flame(Plume),
    /// Nothing above the threshold.
    Empty,
    /// This many disjoint plumes (two or more): the model cannot represent it (§5).
    Plumes(usize),
}

/// Thresholds a row-major gray frame and isolates its flame.
pub fn analyse_frame(gray: &[f32], width: usize, height: usize, s: &FitSettings) -> Frame {
    let clean: Vec<f32> = gray.iter().map(|&v| if v > s.threshold && v.is_finite() { v } else { 0.0 }).collect();
    let (labels, masses) = plumes(&clean, width, height);
    let total: f64 = masses.iter().sum();
    if total <= 0.0 {
        return Frame::Empty;
    }
    let big = masses.iter().filter(|&&m| m >= s.min_plume * total).count();
    if big >= 2 {
        return Frame::Plumes(big);
    }
    let Some(keep) = masses.iter().enumerate().max_by(|a, b| a.1.total_cmp(b.1)).map(|(i, _)| i as u32 + 1) else {
        return Frame::Empty;
    };
    let (mut x0, mut y0, mut x1, mut y1) = (usize::MAX, usize::MAX, 0, 0);
    for (p, &l) in labels.iter().enumerate() {
        if l == keep {
            let (x, y) = (p % width, p / width);
            x0 = x0.min(x);
            y0 = y0.min(y);
            x1 = x1.max(x);
            y1 = y1.max(y);
        }
    }
    let (bw, bh) = (x1 + 1 - x0, y1 + 1 - y0);
    let mut data = vec![0.0_f32; bw * bh];
    for y in 0..bh {
        for x in 0..bw {
            let p = (y0 + y) * width + x0 + x;
            if labels[p] == keep {
                data[y * bw + x] = clean[p];
            }
        }
    }
    let moments = Moments::of_image(&data, bw, bh).translated(x0 as f64, y0 as f64);
    Frame::Flame(Plume { x0, y0, width: bw, height: bh, data, moments })
}
