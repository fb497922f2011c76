//! §5.1.2.1 Direct Bridging: real frames near the straight line between two motions.

use std::collections::HashSet;

use super::distance::{distances_to, row};
use crate::values::Weights;

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
