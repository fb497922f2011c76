//! §5.1.2.2 End Growing Connection (Algorithm 1), with the thesis' adaptive θ_min per source clip.

use std::cmp::Reverse;
use std::collections::{BinaryHeap, HashMap};
use std::ops::RangeInclusive;

use super::distance::{distances_from_two, distances_to, exclusion_mask, frame_distance, row};
use crate::values::{FrameRef, Weights};

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
    check_inputs(db, (alpha, beta), e, theta, excluded)?;
    let m = db.frames;
    let mut rows = DistanceRows { db, e, rows: HashMap::new() };
    let a_path = vec![alpha];
    let b_path = vec![beta];
    let optimized = |mut r: EndGrowing| {
        if optimize {
            r.path = optimize_path(db, alpha, beta, r.path, e);
        }
        r
    };
    if let Some(r) = join(&rows, theta, (alpha, beta), &a_path, &b_path, 0) {
        return Ok(optimized(r));
    }
    let mut on_a = vec![false; m];
    let mut on_b = vec![false; m];
    on_a[alpha] = true;
    on_b[beta] = true;
    let mut paths = Paths { a: a_path, b: b_path, on_a, on_b };
    let steps = max_steps.div_ceil(2);
    for step in 1..=steps {
        let (ca, cb) = (*paths.a.last().unwrap_or(&alpha), *paths.b.last().unwrap_or(&beta));
        rows.ensure(ca, cb);
        let big_d = rows.d(ca, cb);
        if !grow_step(&rows, theta, excluded, (alpha, beta), (ca, cb), big_d, &mut paths) {
            let t = theta.between(ca, cb);
            return Err(format!(
                "step {step}: no pair of frames brings the two ends (frames {ca} and {cb}, {big_d:.4} apart) closer by \
                 theta_min = {t}; lower theta_min or use Direct Bridging"
            ));
        }
        if let Some(r) = join(&rows, theta, (alpha, beta), &paths.a, &paths.b, step) {
            return Ok(optimized(r));
        }
    }
    Err(format!(
        "the two ends did not meet within {max_steps} steps (still {:.4} apart); allow more steps, lower theta_min \
         or use Direct Bridging / the low-pass filter",
        rows.d(*paths.a.last().unwrap_or(&alpha), *paths.b.last().unwrap_or(&beta))
    ))
}

/// Checks the arguments of [`end_growing_adaptive`] against the database.
fn check_inputs(
    db: &Weights,
    (alpha, beta): (usize, usize),
    e: usize,
    theta: &ThetaMin,
    excluded: &[bool],
) -> Result<(), String> {
    let m = db.frames;
    if alpha >= m || beta >= m {
        return Err(format!("α = {alpha} or β = {beta} is past the database's {m} frames"));
    }
    if alpha == beta {
        return Err(format!("α and β are the same frame ({alpha}): there is no gap to bridge"));
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
    Ok(())
}

/// The two paths of Algorithm 1, grown from α and β, and which frames each holds.
struct Paths {
    /// The α path, α first.
    a: Vec<usize>,
    /// The β path, β first.
    b: Vec<usize>,
    /// Frames on the α path.
    on_a: Vec<bool>,
    /// Frames on the β path.
    on_b: Vec<bool>,
}

/// The shortest join of the two paths after `steps` steps, if they meet: over all pairs (p, q),
/// p + q minimal, of a shared image or a pair closer than θ_min; elements grown beyond the join
/// are dropped.
fn join(
    rows: &DistanceRows<'_>,
    theta: &ThetaMin,
    (alpha, beta): (usize, usize),
    a_path: &[usize],
    b_path: &[usize],
    steps: usize,
) -> Option<EndGrowing> {
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
}

/// One step of Algorithm 1 from the ends `ca`, `cb` (`big_d` apart): moves both ends to the
/// nearest pair of candidates that closes the gap by θ_min, or one end onto a frame of the other
/// path (a shared image). Returns whether a step was found.
fn grow_step(
    rows: &DistanceRows<'_>,
    theta: &ThetaMin,
    excluded: &[bool],
    (alpha, beta): (usize, usize),
    (ca, cb): (usize, usize),
    big_d: f64,
    paths: &mut Paths,
) -> bool {
    // Candidates of one side: θ_min ≤ hop < gap (the path is built of "short distances less
    // than the difference between α and β, and larger than θ_min"), not excluded, not on the
    // own path.
    let candidates = |from: usize, own: &[bool]| {
        let ds = rows.row(from);
        Nearest::new(ds, |i| {
            ds[i] >= theta.between(from, i) && ds[i] < big_d && !excluded[i] && !own[i] && i != alpha && i != beta
        })
    };
    let mut la = candidates(ca, &paths.on_a);
    let mut lb = candidates(cb, &paths.on_b);
    let (mut j, mut k) = (0, 0);
    let mut found = false;
    while !found {
        let (Some(aj), Some(bk)) = (la.get(j), lb.get(k)) else { break };
        // Line 7: a candidate that is already on the other side's path is a shared image.
        if paths.on_b[aj] {
            paths.a.push(aj);
            paths.on_a[aj] = true;
            found = true;
            continue;
        }
        if paths.on_a[bk] {
            paths.b.push(bk);
            paths.on_b[bk] = true;
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
            paths.a.push(aj);
            paths.b.push(bk);
            paths.on_a[aj] = true;
            paths.on_b[bk] = true;
            found = true;
        }
    }
    found
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
