//! `imaging.fire_regions`: every fire in a frame, not only the largest. The thesis (§3.3) keeps
//! the one flame it filmed; a plate may hold several (a row of candles, a forest fire seen
//! through trees), and keeping only the largest outline drops the others. This node lists each
//! fire (box, area, centroid) and keeps all of them above a size, the largest, or one by index.

use std::hash::Hash;
use std::sync::Arc;

use pyrograph_core::fingerprint::Fingerprinter;
use pyrograph_core::{Contour, Contours, Cook, CookCtx, NodeError, TypeInfo, ValueType};

use super::contours::retain_contours;

pub use crate::blobs::RegionSelect;

/// One fire in a frame.
#[derive(Clone, Debug, PartialEq)]
pub struct Region {
    /// Box around its outline, `[x_min, y_min, x_max, y_max]` in pixels.
    pub bounds: [f64; 4],
    /// Area inside its outline less its holes, in square pixels.
    pub area: f64,
    /// Centroid of its outline's polygon, in pixels.
    pub centroid: [f64; 2],
}

/// The fires found in one frame, largest first.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FireRegions {
    /// Size of the frame they were found in.
    pub width: u32,
    /// Height of that frame.
    pub height: u32,
    /// The fires, largest first.
    pub regions: Vec<Region>,
}

impl ValueType for FireRegions {
    const INFO: &'static TypeInfo = &TypeInfo {
        name: "FireRegions",
        doc: "The separate fires of a frame, largest first: each one's box, area and centroid (extends Eigenfires thesis §3.3 to several fires).",
        color: [240, 150, 60],
    };

    fn hash_into(&self, h: &mut Fingerprinter) {
        (self.width, self.height).hash(h);
        for r in &self.regions {
            (r.bounds.map(f64::to_bits), r.area.to_bits(), r.centroid.map(f64::to_bits)).hash(h);
        }
    }

    fn byte_size(&self) -> usize {
        self.regions.len() * std::mem::size_of::<Region>()
    }

    fn summary(&self) -> String {
        let areas: Vec<String> = self.regions.iter().take(8).map(|r| format!("{:.0}", r.area)).collect();
        let more = if self.regions.len() > 8 { ", …" } else { "" };
        format!("FireRegions {} fire(s) in {}×{} (areas {}{more})", self.regions.len(), self.width, self.height, areas.join(", "))
    }
}

pyrograph_core::node! {
    /// Keeps every fire of a frame, not only the largest (extends Eigenfires thesis §3.3, which keeps the one flame it filmed, to plates with several fires).
    ///
    /// Each outermost contour is a fire; those smaller than min_share of the largest one's area or than min_area pixels are left out (sparks, specks), and so are those within merge times a larger fire's size of it, taken for its glow, a reflection or a detached tip. select keeps all the fires, only the largest, or the one at index (largest first). Outputs the kept contours with their holes (for imaging.contour_mask, imaging.pose_normalize), every fire above the size as regions (box, area, centroid) and their count.
    #[node("imaging.fire_regions", "Pre-processing", PerFrame)]
    pub struct FireRegionsNode {
        /// Contours of the fire mask (imaging.contours or imaging.hole_removal)
        contours: Arc<Contours>,
        /// all: every fire above the size; largest: the largest; index: one fire by its rank
        select: RegionSelect = RegionSelect::All,
        /// A fire smaller than this share of the largest fire's area is left out
        #[range(0.0, 1.0)]
        min_share: f64 = 0.05,
        /// A fire smaller than this many square pixels is left out
        #[range(0.0, 1.0e12)]
        min_area: f64 = 0.0,
        /// A blob closer to a larger fire than this many times that fire's size (its box's longer side) is taken for its glow, a reflection or a detached tip and left out, so fires closer together than this are kept as one, the largest; 0 keeps every blob as a fire of its own
        #[range(0.0, 100.0)]
        merge: f64 = 1.0,
        /// With select = index: the fire to keep, 0 for the largest
        #[range(0, 100_000)]
        index: usize = 0,
    }
    pub struct FireRegionsOut {
        /// The kept fires' contours with their holes
        contours: Arc<Contours>,
        /// Every fire above the size and apart from larger ones, largest first: box, area, centroid
        regions: Arc<FireRegions>,
        /// How many fires are above the size and apart from larger ones
        count: i64,
    }
}

impl Cook for FireRegionsNode {
    fn cook(self, ctx: &CookCtx) -> Result<FireRegionsOut, NodeError> {
        let (kept, regions) = fire_regions(&self.contours, self.min_share, self.min_area, self.merge);
        let chosen: Vec<usize> = match self.select {
            RegionSelect::All => kept.clone(),
            RegionSelect::Largest => kept.iter().take(1).copied().collect(),
            RegionSelect::Index => {
                if self.index >= kept.len() && !kept.is_empty() {
                    // One wording for every frame, so a clip reports it once (see CookCtx::warn).
                    ctx.warn(format!("select = index {} but some frames hold fewer fires: those frames keep none", self.index));
                }
                kept.get(self.index).copied().into_iter().collect()
            }
        };
        let contours = retain_contours(&self.contours, |i, c| c.parent.is_some() || chosen.contains(&i));
        let count = regions.regions.len() as i64;
        Ok(FireRegionsOut { contours: Arc::new(contours), regions: Arc::new(regions), count })
    }
}

/// The fires of `contours`: outermost outlines at least `min_share` of the largest one's area
/// and `min_area` square pixels, those lying within `merge` times a larger fire's size (the
/// longer side of its box) of it taken as part of that fire (its glow, a reflection, a detached
/// tip) and left out. Returns the fires' indices in `contours` and their regions, largest first.
pub fn fire_regions(contours: &Contours, min_share: f64, min_area: f64, merge: f64) -> (Vec<usize>, FireRegions) {
    let list = &contours.contours;
    // A fire's area is its outline's less the holes directly inside it.
    let mut area: Vec<f64> = list.iter().map(|c| if c.parent.is_none() { c.area } else { 0.0 }).collect();
    for c in list.iter().filter(|c| c.is_hole()) {
        if let Some(p) = c.parent.filter(|p| list[*p].parent.is_none()) {
            area[p] -= c.area;
        }
    }
    let mut outer: Vec<usize> = (0..list.len()).filter(|i| list[*i].parent.is_none()).collect();
    outer.sort_by(|a, b| area[*b].total_cmp(&area[*a]).then(a.cmp(b)));
    let largest = outer.first().map_or(0.0, |i| area[*i]);
    let floor = (min_share * largest).max(min_area);
    let mut kept: Vec<usize> = Vec::new();
    let mut regions: Vec<Region> = Vec::new();
    for i in outer.into_iter().filter(|i| area[*i] > 0.0 && area[*i] >= floor) {
        let r = region(&list[i], area[i]);
        // Largest first, so a blob near a kept fire is the smaller of the two.
        if !regions.iter().any(|fire| box_gap(&fire.bounds, &r.bounds) <= merge * longer_side(&fire.bounds)) {
            kept.push(i);
            regions.push(r);
        }
    }
    (kept, FireRegions { width: contours.width, height: contours.height, regions })
}

/// The distance between two boxes (0 when they overlap).
fn box_gap(a: &[f64; 4], b: &[f64; 4]) -> f64 {
    let gx = (b[0] - a[2]).max(a[0] - b[2]).max(0.0);
    let gy = (b[1] - a[3]).max(a[1] - b[3]).max(0.0);
    gx.hypot(gy)
}

/// A box's longer side.
fn longer_side(b: &[f64; 4]) -> f64 {
    (b[2] - b[0]).max(b[3] - b[1])
}

/// A fire's box and centroid from its outline, with its area.
fn region(c: &Contour, area: f64) -> Region {
    let bounds = c.points.iter().fold([f64::INFINITY, f64::INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY], |b, p| {
        let (x, y) = (f64::from(p[0]), f64::from(p[1]));
        [b[0].min(x), b[1].min(y), b[2].max(x), b[3].max(y)]
    });
    // The polygon's centroid (shoelace); the mean of the vertices for a degenerate one.
    let n = c.points.len();
    let (mut a2, mut cx, mut cy) = (0.0, 0.0, 0.0);
    for k in 0..n {
        let (p, q) = (c.points[k], c.points[(k + 1) % n]);
        let (px, py, qx, qy) = (f64::from(p[0]), f64::from(p[1]), f64::from(q[0]), f64::from(q[1]));
        let cross = px * qy - qx * py;
        (a2, cx, cy) = (a2 + cross, cx + (px + qx) * cross, cy + (py + qy) * cross);
    }
    let centroid = if a2.abs() > 1e-9 {
        [cx / (3.0 * a2), cy / (3.0 * a2)]
    } else {
        let m = |k: usize| c.points.iter().map(|p| f64::from(p[k])).sum::<f64>() / n.max(1) as f64;
        [m(0), m(1)]
    };
    Region { bounds, area, centroid }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::preprocess::contours::tests::mask;
    use crate::preprocess::contours::trace_contours;

    /// Three fires: a 6×4 block with a one-pixel hole, a 4×3 block and a 2×2 speck.
    fn three_fires() -> Contours {
        trace_contours(&mask(&[
            "..............",
            ".######..####.",
            ".######..####.",
            ".##.###..####.",
            ".######.......",
            "..............",
            "..........##..",
            "..........##..",
        ]))
    }

    #[test]
    fn every_fire_above_the_share_is_kept_and_listed_largest_first() {
        let c = three_fires();
        let (kept, regions) = fire_regions(&c, 0.25, 0.0, 0.0);
        assert_eq!(kept.len(), 2, "the speck is under a quarter of the largest");
        let r = &regions.regions;
        assert!(r[0].area > r[1].area, "{r:?}");
        assert!(r[0].bounds[0] < 2.0 && r[1].bounds[0] > 8.0, "{r:?}");
        assert!((r[1].centroid[0] - 10.5).abs() < 0.6 && (r[1].centroid[1] - 2.0).abs() < 0.6, "{r:?}");
        // All three with no share; none of them under min_area 100.
        assert_eq!(fire_regions(&c, 0.0, 0.0, 0.0).0.len(), 3);
        assert!(fire_regions(&c, 0.0, 100.0, 0.0).0.is_empty());
        // The largest fire's box is 5 px wide (through pixel centres); the 4×3 block is 3 px to
        // its right and the speck 4.5 px from it: merged from 0.6 and 0.9 times its size on.
        assert_eq!(fire_regions(&c, 0.0, 0.0, 0.5).0.len(), 3);
        assert_eq!(fire_regions(&c, 0.0, 0.0, 0.6).0.len(), 2);
        assert_eq!(fire_regions(&c, 0.0, 0.0, 1.0).0.len(), 1);
    }

    #[test]
    fn the_node_keeps_all_the_largest_or_one_by_index_with_its_holes() {
        let c = Arc::new(three_fires());
        let cook = |select, index| {
            let node = FireRegionsNode { contours: c.clone(), select, min_share: 0.25, min_area: 0.0, merge: 0.0, index };
            node.cook(&CookCtx::new()).unwrap()
        };
        let all = cook(RegionSelect::All, 0);
        assert_eq!(all.count, 2);
        assert_eq!(all.contours.contours.iter().filter(|c| c.parent.is_none()).count(), 2);
        let largest = cook(RegionSelect::Largest, 0);
        assert_eq!(largest.contours.contours.len(), 2, "the largest fire and its hole");
        let second = cook(RegionSelect::Index, 1);
        assert_eq!(second.contours.contours.len(), 1);
        assert!(second.contours.contours[0].points.iter().all(|p| p[0] >= 9.0));
        assert!(cook(RegionSelect::Index, 5).contours.contours.is_empty());
        assert_eq!(cook(RegionSelect::Index, 5).regions.regions.len(), 2, "regions list every fire whatever is kept");
    }
}
