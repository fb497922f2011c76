//! Recognition and motion transitions in fire space (thesis §4.5 eq. 21, §5.1.1 low-pass filter,
//! §5.1.2.1 Direct Bridging, §5.1.2.2 End Growing Connection, Algorithm 1).
//!
//! Every distance is eq. 21, `D_ab = ‖Ω_a − Ω_b‖`, over the first `e` components (the E for
//! detection). Frames are rows of the database's training weights.

use std::cmp::Reverse;
use std::collections::{BinaryHeap, HashMap, HashSet};
use std::ops::RangeInclusive;
use std::sync::Arc;

use pyrograph_core::{
    Basis, CookCtx, FnNode, FrameItem, FrameList, FrameRef, Inputs, NodeDesc, NodeError, PortDesc, PortType, Registry, TimeDep,
    Value, Weights,
};
use rayon::prelude::*;

use crate::pca::components_to_use;

/// Adds this module's node types.
pub fn register(registry: &mut Registry) {
    registry.add(FnNode::new(recognize_desc(), cook_recognize));
    registry.add(FnNode::new(lowpass_desc(), cook_lowpass));
    registry.add(FnNode::new(direct_bridging_desc(), cook_direct_bridging));
    registry.add(FnNode::new(end_growing_desc(), cook_end_growing));
}

/// Eq. 21 over the first `e` components.
pub fn distance(a: &[f32], b: &[f32], e: usize) -> f64 {
    sq_distance(&a[..e], &b[..e]).sqrt()
}

/// `‖a − b‖²` over the whole slices: the differences are squared and summed in 16 independent f32
/// lanes (the compiler vectorises them) and the lanes are added in f64, so a 1,100-component
/// distance costs one pass over the two rows. The result is symmetric bit for bit.
fn sq_distance(a: &[f32], b: &[f32]) -> f64 {
    const LANES: usize = 16;
    let mut acc = [0.0_f32; LANES];
    let (ca, cb) = (a.chunks_exact(LANES), b.chunks_exact(LANES));
    let tail: f64 = ca.remainder().iter().zip(cb.remainder()).map(|(x, y)| f64::from(x - y).powi(2)).sum();
    for (x, y) in ca.zip(cb) {
        for l in 0..LANES {
            let d = x[l] - y[l];
            acc[l] += d * d;
        }
    }
    acc.iter().map(|&v| f64::from(v)).sum::<f64>() + tail
}

fn row(db: &Weights, i: usize) -> &[f32] {
    &db.data[i * db.components..(i + 1) * db.components]
}

/// Database rows per parallel task of a distance pass.
const ROWS_PER_TASK: usize = 128;

/// Distances (eq. 21) from `query` to every database frame, in parallel.
pub fn distances_to(db: &Weights, query: &[f32], e: usize) -> Vec<f64> {
    let q = &query[..e];
    let mut out = vec![0.0_f64; db.frames];
    out.par_chunks_mut(ROWS_PER_TASK).enumerate().for_each(|(t, chunk)| {
        for (k, d) in chunk.iter_mut().enumerate() {
            *d = sq_distance(&row(db, t * ROWS_PER_TASK + k)[..e], q).sqrt();
        }
    });
    out
}

/// Distances from database frames `a` and `b` to every database frame in one parallel pass over
/// the weights (each row is read once for both).
fn distances_from_two(db: &Weights, a: usize, b: usize, e: usize) -> (Vec<f64>, Vec<f64>) {
    let (qa, qb) = (&row(db, a)[..e], &row(db, b)[..e]);
    let mut da = vec![0.0_f64; db.frames];
    let mut dbv = vec![0.0_f64; db.frames];
    da.par_chunks_mut(ROWS_PER_TASK).zip(dbv.par_chunks_mut(ROWS_PER_TASK)).enumerate().for_each(|(t, (oa, ob))| {
        for (k, (x, y)) in oa.iter_mut().zip(ob.iter_mut()).enumerate() {
            let r = &row(db, t * ROWS_PER_TASK + k)[..e];
            *x = sq_distance(r, qa).sqrt();
            *y = sq_distance(r, qb).sqrt();
        }
    });
    (da, dbv)
}

/// Distance between database frames `a` and `b`.
pub fn frame_distance(db: &Weights, a: usize, b: usize, e: usize) -> f64 {
    distance(row(db, a), row(db, b), e)
}

/// Eq. 21 recognition (§4.5): the database frame nearest to `query` whose distance is at least
/// `theta_min` (closer frames are rejected as near-copies) and that is not `excluded`.
pub fn recognize(db: &Weights, query: &[f32], e: usize, theta_min: f64, excluded: &[bool]) -> Option<(usize, f64)> {
    distances_to(db, query, e)
        .into_iter()
        .enumerate()
        .filter(|&(i, d)| d >= theta_min && !excluded.get(i).copied().unwrap_or(false))
        .min_by(|a, b| a.1.total_cmp(&b.1))
}

/// The kernels of §5.1.1.
pub fn lowpass_kernel(name: &str) -> Result<Vec<f64>, String> {
    match name {
        "box3" => Ok(vec![1.0 / 3.0; 3]),
        "box5" => Ok(vec![0.2; 5]),
        "end_weighted" => Ok(vec![0.2, 0.2, 0.6]),
        other => Err(format!("unknown kernel '{other}' (box3, box5, end_weighted)")),
    }
}

/// Checks that a frame range is non-empty and inside a database of `frames` frames.
pub fn check_range(r: &RangeInclusive<usize>, frames: usize, what: &str) -> Result<(), String> {
    if r.is_empty() {
        return Err(format!("{what} {}-{} is empty (its end is before its start)", r.start(), r.end()));
    }
    if *r.end() >= frames {
        return Err(format!("{what} {}-{} goes past the database's last frame {}", r.start(), r.end(), frames.saturating_sub(1)));
    }
    Ok(())
}

/// §5.1.1 low-pass transition from motion `t1` to `t2` (database frame ranges): the weights of
/// `T1 + T2` are filtered along time with `kernel` (its mirror image on the T2 side) over the
/// first `e` components, and the filtered vectors at the last `span` frames of T1 and the first
/// `span` of T2 are returned; they replace those frames (with `box3` and span 2: four morphed
/// frames instead of the last two of T1 and the first two of T2, Fig. 34). Components past `e`
/// are zero, except that each is copied from the original frame with probability `detail`
/// (seeded), to bring back fine detail.
#[allow(clippy::too_many_arguments)] // the parameters of §5.1.1
pub fn lowpass_transition(
    db: &Weights,
    t1: RangeInclusive<usize>,
    t2: RangeInclusive<usize>,
    e: usize,
    kernel: &[f64],
    span: usize,
    detail: f64,
    seed: u64,
) -> Result<Vec<Vec<f32>>, String> {
    check_range(&t1, db.frames, "T1")?;
    check_range(&t2, db.frames, "T2")?;
    if kernel.len() % 2 == 0 || kernel.is_empty() {
        return Err("the kernel needs an odd length".into());
    }
    let seq: Vec<usize> = t1.clone().chain(t2.clone()).collect();
    let len1 = t1.clone().count();
    let len2 = seq.len() - len1;
    if span == 0 || span > len1 || span > len2 {
        return Err(format!("span {span} must be 1..={} (the shorter motion's length)", len1.min(len2)));
    }
    let h = kernel.len() / 2;
    let mut rng = seed ^ 0x9E37_79B9_7F4A_7C15;
    let mut out = Vec::with_capacity(2 * span);
    for p in (len1 - span)..(len1 + span) {
        let k: Vec<f64> = if p < len1 { kernel.to_vec() } else { kernel.iter().rev().copied().collect() };
        let mut v = vec![0.0_f32; db.components];
        for (t, &kw) in k.iter().enumerate() {
            let q = (p + t).saturating_sub(h).min(seq.len() - 1);
            let r = row(db, seq[q]);
            for c in 0..e {
                v[c] += (kw * f64::from(r[c])) as f32;
            }
        }
        if detail > 0.0 {
            let r = row(db, seq[p]);
            for c in e..db.components {
                rng = rng.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                if ((rng >> 11) as f64 / (1u64 << 53) as f64) < detail {
                    v[c] = r[c];
                }
            }
        }
        out.push(v);
    }
    Ok(out)
}

/// §5.1.2.1 Direct Bridging from frame `alpha` to `beta`: the line between them in fire space is
/// divided into `steps + 1` equal parts and, for each of the `steps` points on it, the nearest
/// database frame is taken that is not `excluded`, not already taken, and at least `theta_min`
/// from the frame before it.
pub fn direct_bridging(
    db: &Weights,
    alpha: usize,
    beta: usize,
    steps: usize,
    e: usize,
    theta_min: f64,
    excluded: &[bool],
) -> Result<Vec<usize>, String> {
    let (a, b) = (row(db, alpha), row(db, beta));
    let mut taken: HashSet<usize> = [alpha, beta].into_iter().collect();
    let mut path = Vec::with_capacity(steps);
    let mut prev = alpha;
    for s in 1..=steps {
        let t = s as f32 / (steps + 1) as f32;
        let point: Vec<f32> = (0..db.components).map(|c| a[c] + (b[c] - a[c]) * t).collect();
        let from_prev = distances_to(db, row(db, prev), e);
        let best = distances_to(db, &point, e)
            .into_iter()
            .enumerate()
            .filter(|&(i, _)| !taken.contains(&i) && !excluded[i] && from_prev[i] >= theta_min)
            .min_by(|x, y| x.1.total_cmp(&y.1));
        let Some((f, _)) = best else {
            return Err(format!(
                "step {s} of {steps}: no database frame is at least theta_min = {theta_min} from frame {prev} \
                 outside the excluded frames; lower theta_min"
            ));
        };
        taken.insert(f);
        path.push(f);
        prev = f;
    }
    Ok(path)
}

/// The result of [`end_growing`].
#[derive(Clone, Debug, PartialEq)]
pub struct EndGrowing {
    /// Frames between α and β (both excluded), in playing order.
    pub path: Vec<usize>,
    /// The shared image where the two ends met, if they met in one.
    pub shared: Option<usize>,
    /// Steps of Algorithm 1 taken (two frames each).
    pub steps: usize,
}

/// θ_min of End Growing (§5.1.2.2): one threshold for the whole database, or the thesis' adaptive
/// mode, one threshold per source clip ("a proper θ_min for fire A is around 500, and for fire C
/// is about 1500 … we should force the algorithm to use the threshold corresponding to that
/// specific form of fire in recognition steps, because we already know which frames belong to
/// which type of fire").
#[derive(Clone, Debug, PartialEq)]
pub enum ThetaMin {
    /// One θ_min for every comparison.
    Fixed(f64),
    /// The θ_min of each database frame (that of its source clip). A comparison between frames
    /// `a` and `b` uses the mean of their two thresholds: the clip's own threshold inside one
    /// clip, and the average of the two (the thesis' choice when mixing fires) across clips.
    PerFrame(Vec<f64>),
}

impl ThetaMin {
    /// Per-frame thresholds from one θ_min per source clip: frames whose source is clip `c` get
    /// `per_clip[c]`.
    pub fn per_clip(sources: &[FrameRef], per_clip: &[f64]) -> Result<Self, String> {
        if let Some(t) = per_clip.iter().find(|t| !t.is_finite() || **t < 0.0) {
            return Err(format!("θ_min {t} is not a finite number ≥ 0"));
        }
        sources
            .iter()
            .enumerate()
            .map(|(f, s)| {
                per_clip.get(s.clip as usize).copied().ok_or_else(|| {
                    format!("database frame {f} comes from clip {} but only {} thresholds are given", s.clip + 1, per_clip.len())
                })
            })
            .collect::<Result<Vec<f64>, String>>()
            .map(ThetaMin::PerFrame)
    }

    /// The threshold for a comparison between database frames `a` and `b`.
    pub fn between(&self, a: usize, b: usize) -> f64 {
        match self {
            ThetaMin::Fixed(t) => *t,
            ThetaMin::PerFrame(t) => 0.5 * (t[a] + t[b]),
        }
    }
}

/// Measured thresholds, one per source clip (the "analysis stage" of §5.1.2 and §4.5: thresholds
/// of the fires differ up to five times "for their succeeding frames"): `scale` times the median
/// eq. 21 distance between succeeding frames of each clip (database rows `f`, `f + 1` whose
/// sources are frames `i`, `i + 1` of one clip). Clips with no succeeding pair get 0.
pub fn clip_thresholds(db: &Weights, sources: &[FrameRef], e: usize, scale: f64) -> Result<Vec<f64>, String> {
    if sources.len() != db.frames {
        return Err(format!("the basis lists {} source frames but the weights have {} rows", sources.len(), db.frames));
    }
    let clips = sources.iter().map(|s| s.clip as usize + 1).max().unwrap_or(0);
    let mut steps: Vec<Vec<f64>> = vec![Vec::new(); clips];
    for f in 1..db.frames {
        let (p, c) = (sources[f - 1], sources[f]);
        if p.clip == c.clip && p.index + 1 == c.index {
            steps[c.clip as usize].push(frame_distance(db, f - 1, f, e));
        }
    }
    Ok(steps
        .into_iter()
        .map(|mut d| {
            if d.is_empty() {
                return 0.0;
            }
            d.sort_by(f64::total_cmp);
            scale * d[d.len() / 2]
        })
        .collect())
}

/// Distance rows of the frames End Growing has stood on, so every later distance to them is a
/// look-up; a pair of frames neither of which has a row is computed directly.
struct DistanceRows<'a> {
    db: &'a Weights,
    e: usize,
    rows: HashMap<usize, Vec<f64>>,
}

impl DistanceRows<'_> {
    /// Makes sure the rows of `a` and `b` exist (one pass over the weights for both).
    fn ensure(&mut self, a: usize, b: usize) {
        match (self.rows.contains_key(&a), self.rows.contains_key(&b)) {
            (true, true) => {}
            (false, false) if a != b => {
                let (ra, rb) = distances_from_two(self.db, a, b, self.e);
                self.rows.insert(a, ra);
                self.rows.insert(b, rb);
            }
            (false, _) => {
                self.rows.insert(a, distances_to(self.db, row(self.db, a), self.e));
            }
            (true, false) => {
                self.rows.insert(b, distances_to(self.db, row(self.db, b), self.e));
            }
        }
    }

    fn row(&self, a: usize) -> &[f64] {
        self.rows.get(&a).map_or(&[], Vec::as_slice)
    }

    fn d(&self, a: usize, b: usize) -> f64 {
        match (self.rows.get(&a), self.rows.get(&b)) {
            (Some(r), _) => r[b],
            (None, Some(r)) => r[a],
            (None, None) => frame_distance(self.db, a, b, self.e),
        }
    }
}

/// One side's candidates in order of distance, sorted lazily: Algorithm 1 usually takes one of
/// the first few, so a heap is built in linear time and only the frames looked at are popped.
struct Nearest {
    heap: BinaryHeap<Reverse<(u64, usize)>>,
    order: Vec<usize>,
}

impl Nearest {
    /// Candidates `i` with `keep(i)`, ordered by `ds[i]` (≥ 0, so the bit patterns order as the
    /// values), ties by frame index.
    fn new(ds: &[f64], keep: impl Fn(usize) -> bool) -> Self {
        let heap = ds.iter().enumerate().filter(|&(i, _)| keep(i)).map(|(i, d)| Reverse((d.to_bits(), i))).collect();
        Nearest { heap, order: Vec::new() }
    }

    /// The `j`-th nearest candidate.
    fn get(&mut self, j: usize) -> Option<usize> {
        while self.order.len() <= j {
            let Reverse((_, i)) = self.heap.pop()?;
            self.order.push(i);
        }
        Some(self.order[j])
    }
}

/// §5.1.2.2 End Growing Connection (Algorithm 1). Two paths grow from `alpha` and `beta`; in each
/// step both ends move to the nearest frames `α_j`, `β_k` (sorted by distance, those nearer than
/// `theta_min`, `excluded` ones and the side's own path rejected) for which the four distances
/// `D = ‖α−β‖`, `D12 = ‖α_j−β_k‖`, `D1 = ‖α−β_k‖`, `D2 = ‖β−α_j‖` satisfy `D − D12 ≥ θ_min`
/// (the gap shrinks by at least θ_min); otherwise the candidate that moves away from the other
/// side (`D1 − D > θ_min` or `D2 − D > θ_min`), or both, is replaced by the next one. After each
/// step every element of the α path is compared with every element of the β path: a shared
/// image or a pair closer than θ_min joins them (elements grown beyond the join are dropped).
/// At most `ceil(max_steps / 2)` steps; no join by then is an error. With `optimize`, frames
/// whose removal shortens the larger of their two hops are dropped (Optimize_Path).
#[allow(clippy::too_many_arguments)] // the parameters of Algorithm 1
pub fn end_growing(
    db: &Weights,
    alpha: usize,
    beta: usize,
    max_steps: usize,
    e: usize,
    theta_min: f64,
    excluded: &[bool],
    optimize: bool,
) -> Result<EndGrowing, String> {
    end_growing_adaptive(db, alpha, beta, max_steps, e, &ThetaMin::Fixed(theta_min), excluded, optimize)
}

/// [`end_growing`] with a [`ThetaMin`]: a fixed θ_min or the adaptive one (per source clip) of
/// §5.1.2.2. Each comparison of Algorithm 1 uses the threshold of the frames it compares.
///
/// Every distance is looked up in the distance rows of the frames the two ends stood on: each
/// step makes one pass over the weights for the two new ends (both rows at once), and the join
/// test and the four distances need no further pass.
#[allow(clippy::too_many_arguments)] // the parameters of Algorithm 1
pub fn end_growing_adaptive(
    db: &Weights,
    alpha: usize,
    beta: usize,
    max_steps: usize,
    e: usize,
    theta: &ThetaMin,
    excluded: &[bool],
    optimize: bool,
) -> Result<EndGrowing, String> {
    let m = db.frames;
    if alpha >= m || beta >= m {
        return Err(format!("α = {alpha} or β = {beta} is past the database's {m} frames"));
    }
    if e > db.components {
        return Err(format!("{e} components asked, the weights have {}", db.components));
    }
    if excluded.len() != m {
        return Err(format!("the exclusion mask has {} entries for {m} frames", excluded.len()));
    }
    if let ThetaMin::PerFrame(t) = theta
        && t.len() != m
    {
        return Err(format!("{} per-frame thresholds for {m} frames", t.len()));
    }
    let mut rows = DistanceRows { db, e, rows: HashMap::new() };
    let mut a_path = vec![alpha];
    let mut b_path = vec![beta];
    let finish = |rows: &DistanceRows<'_>, a_path: &[usize], b_path: &[usize], steps: usize| -> Option<EndGrowing> {
        // Shortest join over all pairs (p, q), p + q minimal.
        let mut best: Option<(usize, usize, bool)> = None;
        for (p, &x) in a_path.iter().enumerate() {
            for (q, &y) in b_path.iter().enumerate() {
                let shared = x == y;
                if !(shared || rows.d(x, y) < theta.between(x, y)) {
                    continue;
                }
                if best.is_none_or(|(bp, bq, _)| p + q < bp + bq) {
                    best = Some((p, q, shared));
                }
            }
        }
        let (p, q, shared) = best?;
        let mut path: Vec<usize> = a_path[1..=p].to_vec();
        let tail = if shared { &b_path[1..q] } else { &b_path[1..=q] };
        path.extend(tail.iter().rev());
        path.retain(|&f| f != alpha && f != beta);
        Some(EndGrowing { path, shared: shared.then_some(a_path[p]), steps })
    };
    let optimized = |mut r: EndGrowing| {
        if optimize {
            r.path = optimize_path(db, alpha, beta, r.path, e);
        }
        r
    };
    if let Some(r) = finish(&rows, &a_path, &b_path, 0) {
        return Ok(optimized(r));
    }
    let mut on_a = vec![false; m];
    let mut on_b = vec![false; m];
    on_a[alpha] = true;
    on_b[beta] = true;
    let steps = max_steps.div_ceil(2);
    for step in 1..=steps {
        let (ca, cb) = (*a_path.last().unwrap_or(&alpha), *b_path.last().unwrap_or(&beta));
        rows.ensure(ca, cb);
        let big_d = rows.d(ca, cb);
        // Candidates of one side: θ_min ≤ hop < gap (the path is built of "short distances less
        // than the difference between α and β, and larger than θ_min"), not excluded, not on the
        // own path.
        let candidates = |from: usize, own: &[bool]| {
            let ds = rows.row(from);
            Nearest::new(ds, |i| {
                ds[i] >= theta.between(from, i) && ds[i] < big_d && !excluded[i] && !own[i] && i != alpha && i != beta
            })
        };
        let mut la = candidates(ca, &on_a);
        let mut lb = candidates(cb, &on_b);
        let (mut j, mut k) = (0, 0);
        let mut found = false;
        while !found {
            let (Some(aj), Some(bk)) = (la.get(j), lb.get(k)) else { break };
            // Line 7: a candidate that is already on the other side's path is a shared image.
            if on_b[aj] {
                a_path.push(aj);
                on_a[aj] = true;
                found = true;
                continue;
            }
            if on_a[bk] {
                b_path.push(bk);
                on_b[bk] = true;
                found = true;
                continue;
            }
            let d12 = rows.d(aj, bk);
            if big_d - d12 < theta.between(aj, bk) {
                let short_to_alpha = rows.d(ca, bk) - big_d <= theta.between(ca, bk);
                let short_to_beta = rows.d(cb, aj) - big_d <= theta.between(cb, aj);
                if short_to_alpha && short_to_beta {
                    j += 1;
                    k += 1;
                } else {
                    if !short_to_alpha {
                        k += 1;
                    }
                    if !short_to_beta {
                        j += 1;
                    }
                }
            } else {
                a_path.push(aj);
                b_path.push(bk);
                on_a[aj] = true;
                on_b[bk] = true;
                found = true;
            }
        }
        if !found {
            let t = theta.between(ca, cb);
            return Err(format!(
                "step {step}: no pair of frames brings the two ends (frames {ca} and {cb}, {big_d:.4} apart) closer by \
                 theta_min = {t}; lower theta_min or use Direct Bridging"
            ));
        }
        if let Some(r) = finish(&rows, &a_path, &b_path, step) {
            return Ok(optimized(r));
        }
    }
    Err(format!(
        "the two ends did not meet within {max_steps} steps (still {:.4} apart); allow more steps, lower theta_min \
         or use Direct Bridging / the low-pass filter",
        rows.d(*a_path.last().unwrap_or(&alpha), *b_path.last().unwrap_or(&beta))
    ))
}

/// Optimize_Path of Algorithm 1: repeatedly drops the interior frame whose removal lowers the
/// larger of its two hops the most (a detour), so the largest jump never grows.
pub fn optimize_path(db: &Weights, alpha: usize, beta: usize, path: Vec<usize>, e: usize) -> Vec<usize> {
    let mut full: Vec<usize> = std::iter::once(alpha).chain(path).chain(std::iter::once(beta)).collect();
    loop {
        let mut best: Option<(usize, f64)> = None;
        for i in 1..full.len().saturating_sub(1) {
            let (p, c, n) = (full[i - 1], full[i], full[i + 1]);
            let worst = frame_distance(db, p, c, e).max(frame_distance(db, c, n, e));
            let gain = worst - frame_distance(db, p, n, e);
            if gain > 0.0 && best.is_none_or(|(_, g)| gain > g) {
                best = Some((i, gain));
            }
        }
        match best {
            Some((i, _)) => {
                full.remove(i);
            }
            None => break,
        }
    }
    full[1..full.len() - 1].to_vec()
}

/// Largest distance between consecutive frames of `alpha, path…, beta`.
pub fn largest_jump(db: &Weights, alpha: usize, path: &[usize], beta: usize, e: usize) -> f64 {
    let full: Vec<usize> = std::iter::once(alpha).chain(path.iter().copied()).chain(std::iter::once(beta)).collect();
    full.windows(2).map(|w| frame_distance(db, w[0], w[1], e)).fold(0.0, f64::max)
}

/// A mask of excluded frames: all of `ranges`, plus `near` frames before `alpha` and after `beta`.
pub fn exclusion_mask(frames: usize, ranges: &[RangeInclusive<usize>]) -> Vec<bool> {
    let mut ex = vec![false; frames];
    for r in ranges {
        for i in r.clone() {
            if let Some(x) = ex.get_mut(i) {
                *x = true;
            }
        }
    }
    ex
}

// ---------------------------------------------------------------------------------------------
// Nodes
// ---------------------------------------------------------------------------------------------

fn frames_value(frames: impl IntoIterator<Item = usize>) -> Value {
    Value::FrameList(Arc::new(FrameList { items: frames.into_iter().map(|f| FrameItem::Frame(f as u32)).collect() }))
}

fn motion_ports(d: NodeDesc) -> NodeDesc {
    d.input(PortDesc::new("weights", PortType::Weights, "The database's training weights."))
        .input(PortDesc::int("t1_start", 0, (0, 100_000_000), "First database frame of motion T1."))
        .input(PortDesc::int("t1_end", 0, (0, 100_000_000), "Last database frame of T1 (α, inclusive)."))
        .input(PortDesc::int("t2_start", 1, (0, 100_000_000), "First database frame of motion T2 (β)."))
        .input(PortDesc::int("t2_end", 1, (0, 100_000_000), "Last database frame of T2 (inclusive)."))
}

fn ranges(i: &Inputs<'_>, frames: usize) -> Result<(RangeInclusive<usize>, RangeInclusive<usize>), NodeError> {
    let t1 = i.usize("t1_start")?..=i.usize("t1_end")?;
    let t2 = i.usize("t2_start")?..=i.usize("t2_end")?;
    check_range(&t1, frames, "T1").map_err(|m| NodeError::port("t1_end", m))?;
    check_range(&t2, frames, "T2").map_err(|m| NodeError::port("t2_end", m))?;
    Ok((t1, t2))
}

fn theta(i: &Inputs<'_>) -> Result<f64, NodeError> {
    i.float("theta_min")
}

fn recognize_desc() -> NodeDesc {
    NodeDesc::new(
        "eigen.recognize",
        "Eigenfires",
        TimeDep::WholeClip,
        "Finds the database frame most similar to each query: minimum D_ab = ‖Ω_a − Ω_b‖ (thesis §4.5, eq. 21).\n\n\
         Frames closer than theta_min are rejected (near-copies cause slow motion); the nearest of the rest wins. \
         The query is each row of query, or database frame `frame` when frame ≥ 0 (that frame and `exclude` \
         frames either side of it are skipped).",
    )
    .input(PortDesc::new("weights", PortType::Weights, "The database's training weights."))
    .input(PortDesc {
        default: Some(Value::Weights(Arc::new(Weights::default()))),
        ..PortDesc::new(
            "query",
            PortType::Weights,
            "Weights to recognize (e.g. eigen.project of new frames); unused when frame ≥ 0.",
        )
    })
    .input(PortDesc::int("frame", -1, (-1, 100_000_000), "Query this database frame instead; -1 = use query."))
    .input(PortDesc::int("exclude", 0, (0, 100_000), "With frame: also skip this many frames either side of it."))
    .input(PortDesc::int("components", 0, (0, 1_000_000), "E for detection; 0 = all."))
    .input(PortDesc::float("theta_min", 0.0, (0.0, 1e9), "Minimum distance θ_min; nearer frames are rejected."))
    .output("frames", PortType::FrameList, "The recognized database frame per query.")
    .output("distance", PortType::Float, "Distance of the first query's match.")
}

fn cook_recognize(i: &Inputs<'_>, _: &CookCtx) -> Result<Vec<Value>, NodeError> {
    let db = i.weights("weights")?;
    let e = components_to_use(i.usize("components")?, db.components, "components")?;
    let theta_min = theta(i)?;
    let frame = i.int("frame")?;
    let mut excluded = vec![false; db.frames];
    let queries: Vec<Vec<f32>> = if frame >= 0 {
        let f = frame as usize;
        if f >= db.frames {
            return Err(NodeError::port("frame", format!("frame {f} is past the database's {} frames", db.frames)));
        }
        let near = i.usize("exclude")?;
        excluded[f.saturating_sub(near)..=(f + near).min(db.frames - 1)].iter_mut().for_each(|x| *x = true);
        vec![row(db, f).to_vec()]
    } else {
        let q = i.weights("query")?;
        if q.frames == 0 {
            return Err(NodeError::port("query", "no query: connect weights to query or set frame"));
        }
        if q.components < e {
            return Err(NodeError::port("query", format!("has {} components, detection uses {e}", q.components)));
        }
        (0..q.frames).map(|r| row(q, r).to_vec()).collect()
    };
    let mut found = Vec::with_capacity(queries.len());
    let mut first = 0.0;
    for (qi, q) in queries.iter().enumerate() {
        let (f, d) = recognize(db, q, e, theta_min, &excluded).ok_or_else(|| {
            NodeError::port(
                "theta_min",
                format!("no database frame is at least theta_min = {theta_min} from query {qi} (and not excluded); lower it"),
            )
        })?;
        if qi == 0 {
            first = d;
        }
        found.push(f);
    }
    Ok(vec![frames_value(found), Value::Float(first)])
}

fn lowpass_desc() -> NodeDesc {
    motion_ports(NodeDesc::new(
        "eigen.lowpass_transition",
        "Eigenfires",
        TimeDep::WholeClip,
        "Morphs from motion T1 to T2 by low-pass filtering their weights along time (thesis §5.1.1, Fig. 34).\n\n\
         The weight vectors of T1 + T2 are filtered with the kernel over the first `components` eigenfires (50 in \
         the thesis); the filtered vectors at the last `span` frames of T1 and the first `span` of T2 are the \
         output and replace those frames (box3, span 2: four morphed frames). end_weighted is K = [1/5, 1/5, 3/5], \
         mirrored on the T2 side. detail copies each weight past `components` from the original frame with that \
         probability, to bring back fine detail.",
    ))
    .input(PortDesc::int("components", 50, (1, 1_000_000), "Eigenfires filtered (low frequencies)."))
    .input(PortDesc::choice("kernel", &["box3", "box5", "end_weighted"], "box3", "Filter kernel."))
    .input(PortDesc::int("span", 2, (1, 10_000), "Morphed frames on each side of the seam."))
    .input(PortDesc::float("detail", 0.0, (0.0, 1.0), "Probability of copying each weight past `components` from the original."))
    .input(PortDesc::int("seed", 0, (0, i64::MAX), "Seed of the detail copy."))
    .output("frames", PortType::FrameList, "2·span synthesized weight vectors (the transition).")
}

fn cook_lowpass(i: &Inputs<'_>, _: &CookCtx) -> Result<Vec<Value>, NodeError> {
    let db = i.weights("weights")?;
    let (t1, t2) = ranges(i, db.frames)?;
    let e = components_to_use(i.usize("components")?, db.components, "components")?;
    let kernel = lowpass_kernel(i.choice("kernel")?).map_err(|m| NodeError::port("kernel", m))?;
    let out = lowpass_transition(db, t1, t2, e, &kernel, i.usize("span")?, i.float("detail")?, i.int("seed")? as u64)
        .map_err(|m| NodeError::port("span", m))?;
    Ok(vec![Value::FrameList(Arc::new(FrameList { items: out.into_iter().map(FrameItem::Weights).collect() }))])
}

fn direct_bridging_desc() -> NodeDesc {
    motion_ports(NodeDesc::new(
        "eigen.direct_bridging",
        "Eigenfires",
        TimeDep::WholeClip,
        "Connects motion T1 to T2 through real frames near the straight line between them (thesis §5.1.2.1, Fig. 36).\n\n\
         The line from α (last frame of T1) to β (first frame of T2) is divided into steps + 1 parts; for each of \
         the `steps` points the nearest database frame is taken, outside T1 and T2, not taken before, and at least \
         theta_min from the previous frame.",
    ))
    .input(PortDesc::int("steps", 3, (1, 100_000), "Number of frames N to insert."))
    .input(PortDesc::int("components", 0, (0, 1_000_000), "E for detection; 0 = all."))
    .input(PortDesc::float("theta_min", 0.0, (0.0, 1e9), "Minimum distance θ_min between consecutive frames."))
    .output("frames", PortType::FrameList, "The inserted database frames.")
}

fn cook_direct_bridging(i: &Inputs<'_>, _: &CookCtx) -> Result<Vec<Value>, NodeError> {
    let db = i.weights("weights")?;
    let (t1, t2) = ranges(i, db.frames)?;
    let e = components_to_use(i.usize("components")?, db.components, "components")?;
    let excluded = exclusion_mask(db.frames, &[t1.clone(), t2.clone()]);
    let path = direct_bridging(db, *t1.end(), *t2.start(), i.usize("steps")?, e, theta(i)?, &excluded)
        .map_err(|m| NodeError::port("theta_min", m))?;
    Ok(vec![frames_value(path)])
}

fn end_growing_desc() -> NodeDesc {
    motion_ports(NodeDesc::new(
        "eigen.end_growing",
        "Eigenfires",
        TimeDep::WholeClip,
        "Connects motion T1 to T2 by growing paths of similar frames from both ends until they meet (thesis §5.1.2.2, Algorithm 1).\n\n\
         From α (last frame of T1) and β (first frame of T2) each step moves both ends to the nearest frames that \
         shrink the gap by at least theta_min (Algorithm 1's four distances); frames nearer than theta_min, the last \
         `exclude` frames of T1, the first `exclude` of T2 and each side's own path are rejected. The paths join at a \
         shared image or when two of their frames are closer than theta_min; failing that within `steps` it is an \
         error. optimize drops detours (Optimize_Path).\n\n\
         theta_mode is the thesis' adaptive θ_min (§5.1.2.2, end): `fixed` uses theta_min everywhere; `per_clip` \
         gives each source clip (fire A, B, C) its own threshold from theta_per_clip (\"2, 2, 6\"); `measured` sets \
         each clip's threshold to theta_scale × the median distance between its succeeding frames. A comparison \
         uses the mean of the two frames' thresholds. The adaptive modes need the database's basis (frame sources).",
    ))
    .input(PortDesc::int("steps", 40, (1, 100_000), "Maximum number of frames N (two per step)."))
    .input(PortDesc::int("components", 0, (0, 1_000_000), "E for detection; 0 = all."))
    .input(PortDesc::float("theta_min", 0.0, (0.0, 1e9), "Minimum threshold θ_min."))
    .input(PortDesc::int("exclude", 7, (0, 100_000), "Frames at the end of T1 and the start of T2 that may not be picked."))
    .input(PortDesc::bool("optimize", true, "Drop frames whose removal lowers the larger of their two hops."))
    .input(PortDesc::choice("theta_mode", &["fixed", "per_clip", "measured"], "fixed", "One θ_min, one per source clip, or measured per clip."))
    .input(PortDesc::string("theta_per_clip", "", "per_clip: θ_min of clip 1, 2, 3 (comma separated)."))
    .input(PortDesc::float("theta_scale", 1.0, (0.0, 1e6), "measured: θ_min = scale × median distance of succeeding frames."))
    .input(PortDesc {
        default: Some(Value::Basis(Arc::new(Basis::default()))),
        ..PortDesc::new("basis", PortType::Basis, "The database's basis: where each frame came from (adaptive modes only).")
    })
    .output("frames", PortType::FrameList, "The inserted database frames.")
    .output("steps_taken", PortType::Int, "Steps of Algorithm 1 used.")
    .output("thresholds", PortType::String, "The θ_min used per source clip (comma separated).")
}

fn cook_end_growing(i: &Inputs<'_>, _: &CookCtx) -> Result<Vec<Value>, NodeError> {
    let db = i.weights("weights")?;
    let (t1, t2) = ranges(i, db.frames)?;
    let e = components_to_use(i.usize("components")?, db.components, "components")?;
    let near = i.usize("exclude")?;
    let excluded = end_exclusion(db.frames, &t1, &t2, near);
    let (theta_min, per_clip) = adaptive_theta(i, db, e)?;
    let r = end_growing_adaptive(db, *t1.end(), *t2.start(), i.usize("steps")?, e, &theta_min, &excluded, i.bool("optimize")?)
        .map_err(|m| NodeError::port("steps", m))?;
    let shown = per_clip.iter().map(|t| format!("{t}")).collect::<Vec<_>>().join(", ");
    Ok(vec![frames_value(r.path), Value::Int(r.steps as i64), Value::String(shown)])
}

/// The node's θ_min (fixed, per clip or measured) and the thresholds per clip it stands for.
fn adaptive_theta(i: &Inputs<'_>, db: &Weights, e: usize) -> Result<(ThetaMin, Vec<f64>), NodeError> {
    let mode = i.choice("theta_mode")?;
    if mode == "fixed" {
        let t = theta(i)?;
        return Ok((ThetaMin::Fixed(t), vec![t]));
    }
    let basis = i.basis("basis")?;
    if basis.sources.len() != db.frames {
        return Err(NodeError::port(
            "basis",
            format!(
                "theta_mode {mode} needs the database's basis (it lists {} source frames, the weights have {} rows)",
                basis.sources.len(),
                db.frames
            ),
        ));
    }
    let per_clip = if mode == "per_clip" {
        parse_thresholds(i.string("theta_per_clip")?).map_err(|m| NodeError::port("theta_per_clip", m))?
    } else {
        clip_thresholds(db, &basis.sources, e, i.float("theta_scale")?).map_err(|m| NodeError::port("basis", m))?
    };
    let t = ThetaMin::per_clip(&basis.sources, &per_clip).map_err(|m| NodeError::port("theta_per_clip", m))?;
    Ok((t, per_clip))
}

/// Parses "θ1, θ2, θ3" (commas or spaces) into thresholds.
pub fn parse_thresholds(text: &str) -> Result<Vec<f64>, String> {
    let out = text
        .split(|c: char| c == ',' || c.is_whitespace())
        .filter(|s| !s.is_empty())
        .map(|s| s.parse::<f64>().map_err(|_| format!("'{s}' is not a number")))
        .collect::<Result<Vec<f64>, String>>()?;
    if out.is_empty() {
        return Err("no thresholds given: write one θ_min per source clip, e.g. \"2, 2, 6\"".into());
    }
    Ok(out)
}

/// The frames End Growing may not pick: the last `near` frames of T1 and the first `near` of T2.
pub fn end_exclusion(frames: usize, t1: &RangeInclusive<usize>, t2: &RangeInclusive<usize>, near: usize) -> Vec<bool> {
    let a = t1.end().saturating_sub(near.saturating_sub(1)).max(*t1.start())..=*t1.end();
    let b = *t2.start()..=(t2.start() + near.saturating_sub(1)).min(*t2.end());
    if near == 0 { vec![false; frames] } else { exclusion_mask(frames, &[a, b]) }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn db_from(points: &[Vec<f32>]) -> Weights {
        let c = points[0].len();
        Weights::new(points.len(), c, points.concat()).unwrap()
    }

    #[test]
    fn recognition_rejects_frames_nearer_than_theta_min() {
        let db = db_from(&[vec![0.0, 0.0], vec![0.1, 0.0], vec![1.0, 0.0], vec![3.0, 0.0]]);
        let none = vec![false; 4];
        assert_eq!(recognize(&db, &[0.0, 0.0], 2, 0.0, &none), Some((0, 0.0)));
        assert_eq!(recognize(&db, &[0.0, 0.0], 2, 0.5, &none).map(|r| r.0), Some(2));
        assert_eq!(recognize(&db, &[0.0, 0.0], 2, 10.0, &none), None);
    }

    #[test]
    #[allow(clippy::reversed_empty_ranges)]
    fn lowpass_box3_averages_across_the_seam() {
        // T1 = frames 0..=2 at x = 0, T2 = frames 3..=5 at x = 3: seam outputs (0+0+3)/3 and (0+3+3)/3.
        let db = db_from(&[vec![0.0, 9.0], vec![0.0, 9.0], vec![0.0, 9.0], vec![3.0, 9.0], vec![3.0, 9.0], vec![3.0, 9.0]]);
        let out = lowpass_transition(&db, 0..=2, 3..=5, 1, &[1.0 / 3.0; 3], 2, 0.0, 0).unwrap();
        let xs: Vec<f32> = out.iter().map(|v| v[0]).collect();
        for (x, want) in xs.iter().zip([0.0, 1.0, 2.0, 3.0]) {
            assert!((x - want).abs() < 1e-6, "{xs:?}");
        }
        assert!(out.iter().all(|v| v[1] == 0.0), "components past E are zero without detail");
        let full = lowpass_transition(&db, 0..=2, 3..=5, 1, &[1.0 / 3.0; 3], 2, 1.0, 0).unwrap();
        assert!(full.iter().all(|v| v[1] == 9.0), "detail 1 copies them all");
        assert!(lowpass_transition(&db, 2..=1, 3..=5, 1, &[1.0 / 3.0; 3], 2, 0.0, 0).unwrap_err().contains("empty"));
    }

    /// A synthetic database: a noisy cloud, plus a planted chain of points from α to β.
    fn planted(chain: usize, seed: u64) -> (Weights, usize, usize, Vec<usize>) {
        let dims = 6;
        let mut s = seed;
        let mut pts: Vec<Vec<f32>> = Vec::new();
        // Far-away clutter that should never be chosen.
        for _ in 0..200 {
            let v: Vec<f32> = (0..dims).map(|_| 50.0 + 40.0 * crate::pca::tests::lcg(&mut s)).collect();
            pts.push(v);
        }
        let alpha = pts.len();
        let start = vec![0.0_f32; dims];
        let mut end = vec![0.0_f32; dims];
        end[0] = 10.0;
        end[1] = 4.0;
        let mut chain_ids = Vec::new();
        for i in 0..=chain + 1 {
            let t = i as f32 / (chain + 1) as f32;
            let mut v: Vec<f32> = start.iter().zip(&end).map(|(a, b)| a + (b - a) * t).collect();
            v[2] = (t * std::f32::consts::PI).sin() * 2.0; // a curved path
            if i > 0 && i <= chain {
                chain_ids.push(pts.len());
            }
            pts.push(v);
        }
        let beta = pts.len() - 1;
        (db_from(&pts), alpha, beta, chain_ids)
    }

    #[test]
    fn end_growing_finds_a_planted_path() {
        let (db, alpha, beta, chain) = planted(9, 11);
        let ex = vec![false; db.frames];
        let step = frame_distance(&db, chain[0], chain[1], 6);
        let r = end_growing(&db, alpha, beta, 30, 6, step * 0.5, &ex, true).unwrap();
        assert!(!r.path.is_empty());
        assert!(r.path.iter().all(|f| chain.contains(f)), "path {:?} leaves the planted chain {chain:?}", r.path);
        // Monotone along the chain and the largest hop is small.
        assert!(r.path.windows(2).all(|w| w[0] < w[1]), "{:?}", r.path);
        assert!(largest_jump(&db, alpha, &r.path, beta, 6) < 3.0 * step);
    }

    #[test]
    fn end_growing_fails_clearly_when_theta_min_is_too_large() {
        let (db, alpha, beta, _) = planted(9, 12);
        let ex = vec![false; db.frames];
        let err = end_growing(&db, alpha, beta, 10, 6, 10.0, &ex, true).unwrap_err();
        // Ends nearer than θ_min need no frames at all (stop case 2).
        assert!(end_growing(&db, alpha, beta, 10, 6, 1e6, &ex, true).unwrap().path.is_empty());
        assert!(err.contains("theta_min"), "{err}");
    }

    #[test]
    fn direct_bridging_follows_the_bridge_and_respects_exclusions() {
        let (db, alpha, beta, chain) = planted(9, 13);
        let ex = vec![false; db.frames];
        let path = direct_bridging(&db, alpha, beta, 4, 6, 0.0, &ex).unwrap();
        assert_eq!(path.len(), 4);
        assert!(path.iter().all(|f| chain.contains(f)));
        let mut ex = vec![false; db.frames];
        chain.iter().for_each(|&c| ex[c] = true);
        let away = direct_bridging(&db, alpha, beta, 2, 6, 0.0, &ex).unwrap();
        assert!(away.iter().all(|f| !chain.contains(f)));
        assert!(direct_bridging(&db, alpha, beta, 2, 6, 1e6, &ex).unwrap_err().contains("theta_min"));
    }

    #[test]
    fn optimize_path_drops_a_detour() {
        let db = db_from(&[vec![0.0, 0.0], vec![1.0, 5.0], vec![1.0, 0.0], vec![2.0, 0.0]]);
        assert_eq!(optimize_path(&db, 0, 3, vec![1, 2], 2), vec![2]);
    }

    /// Two fires on a line: fire A (clip 0) steps 1 apart from α = 0 to 8; fire C (clip 1) steps 3
    /// apart down from β = 20 to 11, with a near-copy 1.2 above each frame. The proper θ_min is
    /// about 0.8 for A and 2.5 for C.
    fn two_fires() -> (Weights, Vec<FrameRef>, usize, usize) {
        let mut pts: Vec<(f32, u32)> = Vec::new();
        for i in 0..=8 {
            pts.push((i as f32, 0));
        }
        for i in 0..4 {
            let y = 20.0 - 3.0 * i as f32;
            pts.push((y, 1));
            pts.push((y + 1.2, 1));
        }
        let beta = pts.iter().position(|p| p.0 == 20.0).unwrap();
        let mut index = [0_u32; 2];
        let sources = pts
            .iter()
            .map(|&(_, c)| {
                index[c as usize] += 1;
                FrameRef { clip: c, index: index[c as usize] - 1 }
            })
            .collect();
        let rows: Vec<Vec<f32>> = pts.iter().enumerate().map(|(i, p)| vec![p.0, 1e-3 * i as f32]).collect();
        (db_from(&rows), sources, 0, beta)
    }

    /// The smallest hop between consecutive frames of `α, path…, β` that stay in clip `c`.
    fn smallest_hop_in(db: &Weights, sources: &[FrameRef], alpha: usize, path: &[usize], beta: usize, c: u32) -> f64 {
        let full: Vec<usize> = std::iter::once(alpha).chain(path.iter().copied()).chain(std::iter::once(beta)).collect();
        full.windows(2)
            .filter(|w| sources[w[0]].clip == c && sources[w[1]].clip == c)
            .map(|w| frame_distance(db, w[0], w[1], 2))
            .fold(f64::INFINITY, f64::min)
    }

    #[test]
    fn adaptive_theta_min_uses_each_fires_own_threshold() {
        let (db, sources, alpha, beta) = two_fires();
        let ex = vec![false; db.frames];
        // Per clip (fire A 0.8, fire C 2.5): every frame of A in order, then C's frames without
        // their near-copies (database rows 15, 13, 11 are x = 11, 14, 17).
        let theta = ThetaMin::per_clip(&sources, &[0.8, 2.5]).unwrap();
        let r = end_growing_adaptive(&db, alpha, beta, 40, 2, &theta, &ex, false).unwrap();
        assert_eq!(r.path, vec![1, 2, 3, 4, 5, 6, 7, 8, 15, 13, 11]);
        assert!(smallest_hop_in(&db, &sources, alpha, &r.path, beta, 0) >= 0.8);
        assert!(smallest_hop_in(&db, &sources, alpha, &r.path, beta, 1) >= 2.5);
        // One θ_min cannot do both: fire A's stalls on fire C's near-copies, a middle one skips
        // frames of A (fast forward) and takes C's near-copies (slow motion), fire C's skips A.
        assert!(end_growing(&db, alpha, beta, 40, 2, 0.8, &ex, false).is_err());
        let mid = end_growing(&db, alpha, beta, 40, 2, 1.5, &ex, false).unwrap();
        assert!(smallest_hop_in(&db, &sources, alpha, &mid.path, beta, 0) >= 2.0, "{:?}", mid.path);
        assert!(smallest_hop_in(&db, &sources, alpha, &mid.path, beta, 1) < 2.5, "{:?}", mid.path);
        let big = end_growing(&db, alpha, beta, 40, 2, 2.5, &ex, false).unwrap();
        assert!(smallest_hop_in(&db, &sources, alpha, &big.path, beta, 0) >= 2.5, "{:?}", big.path);
        // Equal thresholds per clip behave exactly as the fixed θ_min.
        let same = end_growing_adaptive(&db, alpha, beta, 40, 2, &ThetaMin::per_clip(&sources, &[1.5, 1.5]).unwrap(), &ex, false);
        assert_eq!(same.unwrap(), mid);
    }

    #[test]
    fn measured_thresholds_are_the_median_succeeding_hop_per_clip() {
        // Clip 0 frames 1 apart (one jump of 5), clip 1 frames 3 apart.
        let xs = [0.0_f32, 1.0, 2.0, 7.0, 8.0, 100.0, 103.0, 106.0];
        let db = db_from(&xs.iter().map(|&x| vec![x]).collect::<Vec<_>>());
        let sources: Vec<FrameRef> =
            (0..8).map(|i| if i < 5 { FrameRef { clip: 0, index: i } } else { FrameRef { clip: 1, index: i - 5 } }).collect();
        let t = clip_thresholds(&db, &sources, 1, 0.5).unwrap();
        assert_eq!(t, vec![0.5, 1.5]);
        let theta = ThetaMin::per_clip(&sources, &t).unwrap();
        assert_eq!(theta.between(0, 1), 0.5);
        assert_eq!(theta.between(6, 7), 1.5);
        assert_eq!(theta.between(0, 7), 1.0, "across clips: the mean");
        assert!(ThetaMin::per_clip(&sources, &[1.0]).unwrap_err().contains("clip 2"));
        assert!(clip_thresholds(&db, &sources[..3], 1, 1.0).is_err());
        assert_eq!(parse_thresholds("2, 2 6").unwrap(), vec![2.0, 2.0, 6.0]);
        assert!(parse_thresholds("2, x").unwrap_err().contains("'x'"));
        assert!(parse_thresholds(" ").is_err());
    }

    #[test]
    fn end_growing_rejects_bad_arguments() {
        let (db, alpha, beta, _) = planted(3, 14);
        let ex = vec![false; db.frames];
        assert!(end_growing(&db, alpha, db.frames, 10, 6, 0.1, &ex, true).is_err());
        assert!(end_growing(&db, alpha, beta, 10, 7, 0.1, &ex, true).is_err());
        assert!(end_growing(&db, alpha, beta, 10, 6, 0.1, &ex[1..], true).is_err());
        assert!(end_growing_adaptive(&db, alpha, beta, 10, 6, &ThetaMin::PerFrame(vec![0.1; 3]), &ex, true).is_err());
    }

    #[test]
    fn fast_distances_match_the_plain_sum() {
        let mut s = 3;
        let a: Vec<f32> = (0..1100).map(|_| crate::pca::tests::lcg(&mut s)).collect();
        let b: Vec<f32> = (0..1100).map(|_| crate::pca::tests::lcg(&mut s)).collect();
        for e in [1, 15, 16, 17, 1100] {
            let plain = a[..e].iter().zip(&b[..e]).map(|(x, y)| f64::from(x - y).powi(2)).sum::<f64>().sqrt();
            assert!((distance(&a, &b, e) - plain).abs() < 1e-5 * plain.max(1e-3), "e={e}");
            assert_eq!(distance(&a, &b, e), distance(&b, &a, e));
        }
    }
}
