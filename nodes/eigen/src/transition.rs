//! Recognition and motion transitions in fire space (thesis §4.5 eq. 21, §5.1.1 low-pass filter,
//! §5.1.2.1 Direct Bridging, §5.1.2.2 End Growing Connection, Algorithm 1).
//!
//! Every distance is eq. 21, `D_ab = ‖Ω_a − Ω_b‖`, over the first `e` components (the E for
//! detection). Frames are rows of the database's training weights.

use std::collections::HashSet;
use std::ops::RangeInclusive;
use std::sync::Arc;

use pyrograph_core::{
    CookCtx, FnNode, FrameItem, FrameList, Inputs, NodeDesc, NodeError, PortDesc, PortType, Registry, TimeDep, Value, Weights,
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
    a[..e].iter().zip(&b[..e]).map(|(x, y)| f64::from(x - y).powi(2)).sum::<f64>().sqrt()
}

fn row(db: &Weights, i: usize) -> &[f32] {
    &db.data[i * db.components..(i + 1) * db.components]
}

/// Distances (eq. 21) from `query` to every database frame, in parallel.
pub fn distances_to(db: &Weights, query: &[f32], e: usize) -> Vec<f64> {
    (0..db.frames).into_par_iter().map(|i| distance(row(db, i), query, e)).collect()
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
    let d = |x: usize, y: usize| frame_distance(db, x, y, e);
    let mut a_path = vec![alpha];
    let mut b_path = vec![beta];
    let finish = |a_path: &[usize], b_path: &[usize], steps: usize| -> Option<EndGrowing> {
        // Shortest join over all pairs (p, q), p + q minimal.
        let mut best: Option<(usize, usize, bool)> = None;
        for (p, &x) in a_path.iter().enumerate() {
            for (q, &y) in b_path.iter().enumerate() {
                let shared = x == y;
                if !(shared || d(x, y) < theta_min) {
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
    if let Some(r) = finish(&a_path, &b_path, 0) {
        return Ok(optimized(r));
    }
    // Candidates of one side: θ_min ≤ hop < gap (the path is built of "short distances less than
    // the difference between α and β, and larger than θ_min"), not excluded, not on the own path.
    let sorted = |from: usize, own: &[usize], gap: f64| -> Vec<usize> {
        let ds = distances_to(db, row(db, from), e);
        let mut idx: Vec<usize> = (0..db.frames)
            .filter(|&i| ds[i] >= theta_min && ds[i] < gap && !excluded[i] && !own.contains(&i) && i != alpha && i != beta)
            .collect();
        idx.sort_by(|&x, &y| ds[x].total_cmp(&ds[y]));
        idx
    };
    let steps = max_steps.div_ceil(2);
    for step in 1..=steps {
        let (ca, cb) = (*a_path.last().unwrap_or(&alpha), *b_path.last().unwrap_or(&beta));
        let big_d = d(ca, cb);
        let la = sorted(ca, &a_path, big_d);
        let lb = sorted(cb, &b_path, big_d);
        let (mut j, mut k) = (0, 0);
        let mut found = false;
        while j < la.len() && k < lb.len() && !found {
            let (aj, bk) = (la[j], lb[k]);
            // Line 7: a candidate that is already on the other side's path is a shared image.
            if b_path.contains(&aj) || a_path.contains(&bk) {
                if b_path.contains(&aj) {
                    a_path.push(aj);
                } else {
                    b_path.push(bk);
                }
                found = true;
                continue;
            }
            let d12 = d(aj, bk);
            if big_d - d12 < theta_min {
                let short_to_alpha = d(ca, bk) - big_d <= theta_min;
                let short_to_beta = d(cb, aj) - big_d <= theta_min;
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
                found = true;
            }
        }
        if !found {
            return Err(format!(
                "step {step}: no pair of frames brings the two ends (frames {ca} and {cb}, {big_d:.4} apart) closer by \
                 theta_min = {theta_min}; lower theta_min or use Direct Bridging"
            ));
        }
        if let Some(r) = finish(&a_path, &b_path, step) {
            return Ok(optimized(r));
        }
    }
    Err(format!(
        "the two ends did not meet within {max_steps} steps (still {:.4} apart); allow more steps, lower theta_min \
         or use Direct Bridging / the low-pass filter",
        d(*a_path.last().unwrap_or(&alpha), *b_path.last().unwrap_or(&beta))
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
         error. optimize drops detours (Optimize_Path).",
    ))
    .input(PortDesc::int("steps", 40, (1, 100_000), "Maximum number of frames N (two per step)."))
    .input(PortDesc::int("components", 0, (0, 1_000_000), "E for detection; 0 = all."))
    .input(PortDesc::float("theta_min", 0.0, (0.0, 1e9), "Minimum threshold θ_min."))
    .input(PortDesc::int("exclude", 7, (0, 100_000), "Frames at the end of T1 and the start of T2 that may not be picked."))
    .input(PortDesc::bool("optimize", true, "Drop frames whose removal lowers the larger of their two hops."))
    .output("frames", PortType::FrameList, "The inserted database frames.")
    .output("steps_taken", PortType::Int, "Steps of Algorithm 1 used.")
}

fn cook_end_growing(i: &Inputs<'_>, _: &CookCtx) -> Result<Vec<Value>, NodeError> {
    let db = i.weights("weights")?;
    let (t1, t2) = ranges(i, db.frames)?;
    let e = components_to_use(i.usize("components")?, db.components, "components")?;
    let near = i.usize("exclude")?;
    let excluded = end_exclusion(db.frames, &t1, &t2, near);
    let r = end_growing(db, *t1.end(), *t2.start(), i.usize("steps")?, e, theta(i)?, &excluded, i.bool("optimize")?)
        .map_err(|m| NodeError::port("steps", m))?;
    Ok(vec![frames_value(r.path), Value::Int(r.steps as i64)])
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
}
