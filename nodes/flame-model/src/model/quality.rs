//! How well a clip suits the generic flame model (Stich & Magnor §3 assumes the whole flame in
//! the picture, its base at the bottom) and how well each frame is fitted: flames cut by an edge
//! of the frame, and the eigenflames' reconstruction error of every normalized frame (§3.2).

use pyrograph_nodes_eigen::pca::{self, Database};
use pyrograph_nodes_eigen::values::FrameRef;
use pyrograph_nodes_imaging::auto_crop::{BASE_OUTSIDE, edge_warning, is_framing_problem};

use super::fit_settings::FitSettings;
use super::plume::Plume;

/// The fit quality of one frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameQuality {
    /// Frame of the clip.
    pub frame: usize,
    /// ‖x − x̂‖ / ‖x‖ of its normalized image x and the eigenflames' reconstruction x̂ (N_e of them;
    /// for a used frame, those of the final fit).
    pub residual: f64,
    /// The flame touches an edge of the picture.
    pub edge: bool,
    /// The frame is a row of the fitted parameters (not dropped by `max_residual`).
    pub used: bool,
}

/// The picture's four edges: name and outward normal (x right, y down).
const EDGES: [(&str, [f64; 2]); 4] = [("left", [-1.0, 0.0]), ("top", [0.0, -1.0]), ("right", [1.0, 0.0]), ("bottom", [0.0, 1.0])];

/// Which frames' flames touch which edges of the picture, and where the base and tip point.
pub struct EdgeReport {
    /// Per flame frame: it touches any edge.
    pub touches: Vec<bool>,
    /// Per edge (left, top, right, bottom): how many flame frames touch it.
    count: [usize; 4],
    /// Unit main axis, base → tip.
    axis: [f64; 2],
}

impl EdgeReport {
    /// Edges touched by `flames` (tight boxes of the thresholded plumes) in a `frame_size` picture.
    pub fn of(flames: &[&Plume], (width, height): (u32, u32), axis: [f64; 2]) -> EdgeReport {
        let (w, h) = (width as usize, height as usize);
        let per_frame: Vec<[bool; 4]> =
            flames.iter().map(|p| [p.x0 == 0, p.y0 == 0, p.x0 + p.width >= w, p.y0 + p.height >= h]).collect();
        let mut count = [0; 4];
        for t in &per_frame {
            for (c, &hit) in count.iter_mut().zip(t) {
                *c += usize::from(hit);
            }
        }
        EdgeReport { touches: per_frame.iter().map(|t| t.iter().any(|&b| b)).collect(), count, axis }
    }

    /// The most touched edge on the side `dir` points to (within 60° of its normal), if it is a
    /// framing problem (imaging.auto_crop's rule: a quarter of the frames or more).
    fn cut_towards(&self, dir: [f64; 2]) -> Option<(&'static str, usize)> {
        let n = self.touches.len();
        EDGES
            .iter()
            .zip(self.count)
            .filter(|((_, e), k)| e[0] * dir[0] + e[1] * dir[1] > 0.5 && is_framing_problem(*k, n))
            .map(|((name, _), k)| (*name, k))
            .max_by_key(|&(_, k)| k)
    }

    /// The message when the flame's base is outside the picture (imaging.auto_crop's words).
    pub fn base_cut(&self) -> Option<String> {
        let n = self.touches.len();
        self.cut_towards([-self.axis[0], -self.axis[1]]).map(|(edge, k)| edge_warning(edge, k, n, BASE_OUTSIDE))
    }

    /// The message when the flame's tip is outside the picture.
    pub fn tip_cut(&self) -> Option<String> {
        let n = self.touches.len();
        self.cut_towards(self.axis).map(|(edge, k)| {
            edge_warning(
                edge,
                k,
                n,
                "its tip is outside the picture, so the fitted heights are cut; crop higher or use a clip where the whole \
                 flame is visible",
            )
        })
    }
}

/// Trains the eigenflames on the rows `subset` of `data` (normalized images, one after another)
/// and scores each of those rows by its relative reconstruction error with the N_e eigenflames
/// kept. `kept[f]` is row f's frame in the clip.
pub fn train_scored(s: &FitSettings, data: &[f32], subset: &[usize], kept: &[usize]) -> Result<(Database, Vec<f64>), String> {
    let n = s.norm_size().0 as usize * s.norm_size().1 as usize;
    let rows: Vec<f32> = subset.iter().flat_map(|&f| data[f * n..(f + 1) * n].iter().copied()).collect();
    let sources = subset.iter().map(|&f| FrameRef { clip: 0, index: kept[f] as u32 }).collect();
    // `train` consumes its frames (made mean-free in place); the originals are scored against.
    let db = pca::train(s.norm_size().0, s.norm_size().1, rows.clone(), sources, s.n_e)?;
    let back = pca::reconstruct(&db.basis, &db.weights, db.basis.components())?;
    let residuals = rows
        .chunks_exact(n)
        .zip(back.chunks_exact(n))
        .map(|(x, r)| {
            let err: f64 = x.iter().zip(r).map(|(a, b)| f64::from(a - b).powi(2)).sum();
            let norm: f64 = x.iter().map(|a| f64::from(*a).powi(2)).sum();
            if norm > 0.0 { (err / norm).sqrt() } else { 0.0 }
        })
        .collect();
    Ok((db, residuals))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::shape::Moments;

    fn plume(x0: usize, y0: usize, width: usize, height: usize) -> Plume {
        Plume { x0, y0, width, height, data: vec![1.0; width * height], moments: Moments::of_image(&[1.0], 1, 1) }
    }

    #[test]
    fn a_flame_cut_by_the_bottom_edge_is_a_cut_base_and_one_by_the_top_a_cut_tip() {
        let up = [0.0, -1.0];
        let cut: Vec<Plume> = (0..8).map(|i| plume(40, 10, 20, if i < 6 { 90 } else { 80 })).collect();
        let refs: Vec<&Plume> = cut.iter().collect();
        let r = EdgeReport::of(&refs, (100, 100), up);
        let base = r.base_cut().expect("base cut");
        assert!(base.contains("bottom edge in 75 % of frames") && base.contains("base is outside the picture"), "{base}");
        assert!(r.tip_cut().is_none());
        assert_eq!(r.touches, vec![true, true, true, true, true, true, false, false]);
        // The same boxes, flame pointing down (hanging from the top): the bottom is its tip.
        let r = EdgeReport::of(&refs, (100, 100), [0.0, 1.0]);
        assert!(r.base_cut().is_none());
        assert!(r.tip_cut().unwrap().contains("tip is outside"));
        // Exactly a quarter of the frames counts (6 of 24, where adding 1/24 six times falls short of 0.25).
        let quarter: Vec<Plume> = (0..24).map(|i| plume(40, 10, 20, if i < 6 { 90 } else { 80 })).collect();
        let refs: Vec<&Plume> = quarter.iter().collect();
        assert!(EdgeReport::of(&refs, (100, 100), up).base_cut().is_some_and(|m| m.contains("in 25 % of frames")));
        // Touching now and then (under a quarter of the frames) is a flare, not a framing problem.
        let flare: Vec<Plume> = (0..8).map(|i| plume(40, 10, 20, if i == 0 { 90 } else { 80 })).collect();
        let refs: Vec<&Plume> = flare.iter().collect();
        assert!(EdgeReport::of(&refs, (100, 100), up).base_cut().is_none());
    }
}
