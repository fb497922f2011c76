//! The training's elementwise passes over the frames, compiled twice: for plain x86-64 (the
//! release build's target, whose SSE2 handles two f64 or four f32 lanes per instruction) and for
//! AVX2, chosen at run time. At 500 frames of 205×335 these passes ran at half numpy's speed
//! (numpy picks AVX2/AVX-512 loops at run time too). Each function does the same operations in
//! the same order in both builds (no fused multiply-adds, no reassociation), so results are
//! bit-identical whichever runs.

/// Defines `pub(super) fn $name` that runs `$generic` compiled with AVX2 when the CPU has it.
macro_rules! dispatch {
    ($(#[$doc:meta])* $name:ident, $avx2:ident, $generic:ident, ($($arg:ident: $ty:ty),*) -> $ret:ty) => {
        $(#[$doc])*
        pub(super) fn $name($($arg: $ty),*) -> $ret {
            #[cfg(target_arch = "x86_64")]
            if std::arch::is_x86_feature_detected!("avx2") {
                // SAFETY: the CPU supports AVX2, checked just above; the function only lets the
                // compiler vectorize safe code with it.
                return unsafe { $avx2($($arg),*) };
            }
            $generic($($arg),*)
        }

        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = "avx2")]
        fn $avx2($($arg: $ty),*) -> $ret {
            $generic($($arg),*)
        }
    };
}

dispatch!(
    /// `acc += col`, widened to f64.
    accumulate, accumulate_avx2, accumulate_generic, (acc: &mut [f64], col: &[f32]) -> ()
);
dispatch!(
    /// `acc += c0; acc += c1; acc += c2; acc += c3`, widened to f64, in that order (the same sums
    /// as four calls of [`accumulate`], with a quarter of the accumulator's loads and stores).
    accumulate4, accumulate4_avx2, accumulate4_generic, (acc: &mut [f64], cols: [&[f32]; 4]) -> ()
);
dispatch!(
    /// `v -= mean`, sample by sample.
    subtract, subtract_avx2, subtract_generic, (v: &mut [f32], mean: &[f32]) -> ()
);
dispatch!(
    /// `Σ x²` in f64.
    sum_of_squares, sum_of_squares_avx2, sum_of_squares_generic, (u: &[f32]) -> f64
);
dispatch!(
    /// `x = x · s`, the product taken in f64.
    scale, scale_avx2, scale_generic, (u: &mut [f32], s: f64) -> ()
);

#[inline(always)]
fn accumulate_generic(acc: &mut [f64], col: &[f32]) {
    acc.iter_mut().zip(col).for_each(|(a, &v)| *a += f64::from(v));
}

#[inline(always)]
fn accumulate4_generic(acc: &mut [f64], [c0, c1, c2, c3]: [&[f32]; 4]) {
    let len = acc.len().min(c0.len()).min(c1.len()).min(c2.len()).min(c3.len());
    let (acc, c0, c1, c2, c3) = (&mut acc[..len], &c0[..len], &c1[..len], &c2[..len], &c3[..len]);
    for i in 0..len {
        acc[i] = (((acc[i] + f64::from(c0[i])) + f64::from(c1[i])) + f64::from(c2[i])) + f64::from(c3[i]);
    }
}

#[inline(always)]
fn subtract_generic(v: &mut [f32], mean: &[f32]) {
    v.iter_mut().zip(mean).for_each(|(v, &mu)| *v -= mu);
}

/// Eight independent partial sums: one running sum is a chain of dependent additions that runs
/// at a quarter of the speed and does not vectorize.
#[inline(always)]
fn sum_of_squares_generic(u: &[f32]) -> f64 {
    let mut acc = [0.0_f64; 8];
    let mut blocks = u.chunks_exact(8);
    for block in blocks.by_ref() {
        for (a, &x) in acc.iter_mut().zip(block) {
            *a += f64::from(x) * f64::from(x);
        }
    }
    let tail: f64 = blocks.remainder().iter().map(|&x| f64::from(x) * f64::from(x)).sum();
    acc.iter().sum::<f64>() + tail
}

#[inline(always)]
fn scale_generic(u: &mut [f32], s: f64) {
    u.iter_mut().for_each(|x| *x = (f64::from(*x) * s) as f32);
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The dispatched (AVX2 on this CPU, when it has it) and the plain builds agree bit for bit.
    #[test]
    fn the_avx2_and_plain_builds_agree_bit_for_bit() {
        let xs: Vec<f32> = (0..1037).map(|i| ((i * 7919) % 1013) as f32 / 977.0 - 0.3).collect();
        let ys: Vec<f32> = (0..1037).map(|i| ((i * 104_729) % 1009) as f32 / 1001.0).collect();
        assert_eq!(sum_of_squares(&xs).to_bits(), sum_of_squares_generic(&xs).to_bits());
        let (mut a, mut b) = (vec![0.25_f64; 1037], vec![0.25_f64; 1037]);
        accumulate(&mut a, &xs);
        accumulate_generic(&mut b, &xs);
        assert_eq!(a, b);
        accumulate4(&mut a, [&xs, &ys, &ys, &xs]);
        for c in [&xs, &ys, &ys, &xs] {
            accumulate_generic(&mut b, c);
        }
        assert_eq!(a, b);
        let (mut a, mut b) = (xs.clone(), xs.clone());
        subtract(&mut a, &ys);
        subtract_generic(&mut b, &ys);
        assert_eq!(a, b);
        scale(&mut a, 1.0 / 3.7);
        scale_generic(&mut b, 1.0 / 3.7);
        assert_eq!(a, b);
    }
}
