//! The §5.1.1 low-pass transition: the weights of two motions filtered along time.

use std::ops::RangeInclusive;

use super::distance::{check_range, row};
use crate::values::Weights;

pyrograph_core::choice! {
    /// The kernels of §5.1.1.
    pub enum Kernel {
        /// K = [1/3, 1/3, 1/3].
        Box3 = "box3",
        /// K = [1/5, 1/5, 1/5, 1/5, 1/5].
        Box5 = "box5",
        /// K = [1/5, 1/5, 3/5], mirrored on the T2 side.
        EndWeighted = "end_weighted",
    }
}

impl Kernel {
    /// The kernel's weights.
    pub fn weights(self) -> Vec<f64> {
        match self {
            Kernel::Box3 => vec![1.0 / 3.0; 3],
            Kernel::Box5 => vec![0.2; 5],
            Kernel::EndWeighted => vec![0.2, 0.2, 0.6],
        }
    }
}

/// The weights of the kernel named `name` (one of [`Kernel::NAMES`]).
pub fn lowpass_kernel(name: &str) -> Result<Vec<f64>, String> {
    Kernel::parse(name).map(Kernel::weights).ok_or_else(|| format!("unknown kernel '{name}' (box3, box5, end_weighted)"))
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
    if kernel.len().is_multiple_of(2) || kernel.is_empty() {
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
