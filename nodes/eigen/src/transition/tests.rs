use super::*;
use crate::values::{FrameRef, Weights};

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
        let v: Vec<f32> = (0..dims).map(|_| 50.0 + 40.0 * pyrograph_testing::lcg(&mut s)).collect();
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
fn end_growing_refuses_the_same_frame_at_both_ends() {
    // α = β used to reach the shared-image join with nothing on either side and slice out of range.
    let (db, alpha, _, _) = planted(9, 14);
    let ex = vec![false; db.frames];
    let err = end_growing(&db, alpha, alpha, 10, 6, 0.5, &ex, true).unwrap_err();
    assert!(err.contains("same frame"), "{err}");
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
    let a: Vec<f32> = (0..1100).map(|_| pyrograph_testing::lcg(&mut s)).collect();
    let b: Vec<f32> = (0..1100).map(|_| pyrograph_testing::lcg(&mut s)).collect();
    for e in [1, 15, 16, 17, 1100] {
        let plain = a[..e].iter().zip(&b[..e]).map(|(x, y)| f64::from(x - y).powi(2)).sum::<f64>().sqrt();
        assert!((distance(&a, &b, e) - plain).abs() < 1e-5 * plain.max(1e-3), "e={e}");
        assert_eq!(distance(&a, &b, e), distance(&b, &a, e));
    }
}
