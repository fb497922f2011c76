//! Reading a field between voxel centres (trilinear interpolation) near a given brick. A point is
//! looked up through the brick's 27-neighbour table, so a sample costs eight reads and no hash
//! lookup; points farther than seven voxels outside the brick are clamped to that reach (a
//! simulation's sub-steps are CFL-limited well inside it).

use glam::Vec3;

use super::topology::{NONE, Topology, VOXELS, slot, voxel};

/// The eight voxels around a point and their trilinear weights; [`NONE`] for a voxel outside the
/// active bricks (it reads as 0).
#[derive(Clone, Copy, Debug)]
pub struct Corners {
    /// Flat indices into a field (`brick · 512 + voxel`).
    pub at: [u32; 8],
    /// Weights, summing to 1.
    pub w: [f32; 8],
    /// All eight voxels lie in one brick, at `at[0]` + 0, 1, 8, 9, 64, 65, 72, 73.
    pub whole: bool,
}

impl Corners {
    /// The interpolated value of `field`.
    #[inline(always)]
    pub fn sample(&self, field: &[f32]) -> f32 {
        if self.whole {
            // One bounds check and no inactive corners to test: the common case.
            let f = &field[self.at[0] as usize..self.at[0] as usize + 74];
            let w = &self.w;
            // Starting from 0.0 as the loop does (so a −0 product sums to +0, as before).
            return ((((((0.0 + w[0] * f[0] + w[1] * f[1]) + w[2] * f[8]) + w[3] * f[9]) + w[4] * f[64]) + w[5] * f[65])
                + w[6] * f[72])
                + w[7] * f[73];
        }
        let mut s = 0.0;
        for k in 0..8 {
            let a = self.at[k];
            if a != NONE {
                s += self.w[k] * field[a as usize];
            }
        }
        s
    }

    /// The smallest and largest of the eight values of `field` (inactive voxels read 0).
    #[inline(always)]
    pub fn range(&self, field: &[f32]) -> (f32, f32) {
        if self.whole {
            // As in `sample`: one bounds check for the eight reads.
            let f = &field[self.at[0] as usize..self.at[0] as usize + 74];
            let v = [f[0], f[1], f[8], f[9], f[64], f[65], f[72], f[73]];
            return v.iter().fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), x| (lo.min(*x), hi.max(*x)));
        }
        let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
        for a in self.at {
            let v = if a == NONE { 0.0 } else { field[a as usize] };
            lo = lo.min(v);
            hi = hi.max(v);
        }
        (lo, hi)
    }
}

/// `x` rounded down, for `x` well inside `i32`'s range: by truncation, because `f32::floor` is a
/// libm call on a baseline x86-64 target and samplers floor every sample.
#[inline(always)]
pub fn floor_i(x: f32) -> i32 {
    let i = x as i32;
    i - i32::from(i as f32 > x)
}

/// The corners of index-space point `p` (voxel centres at integers), looked up from brick `b`.
/// A point more than seven voxels outside the brick is clamped to that reach; a non-finite one
/// reads the brick's first voxel.
#[inline(always)]
pub fn corners(top: &Topology, b: usize, p: Vec3) -> Corners {
    let o = top.origin(b).as_vec3();
    let p = if p.is_finite() { p.clamp(o - 7.0, o + 14.0) } else { o };
    // The point is clamped to a small finite range.
    let fi = glam::IVec3::new(floor_i(p.x), floor_i(p.y), floor_i(p.z));
    let fr = p - fi.as_vec3();
    let i = fi - top.origin(b);
    let wx = [1.0 - fr.x, fr.x];
    let wy = [1.0 - fr.y, fr.y];
    let wz = [1.0 - fr.z, fr.z];
    let mut out = Corners { at: [NONE; 8], w: [0.0; 8], whole: false };
    for k in 0..8 {
        out.w[k] = wx[k & 1] * wy[(k >> 1) & 1] * wz[k >> 2];
    }
    // Most points have all eight voxels in their own brick: no neighbour to look up.
    if i.cmpge(glam::IVec3::ZERO).all() && i.cmple(glam::IVec3::splat(6)).all() {
        let base = (b * VOXELS + voxel(i.x as usize, i.y as usize, i.z as usize)) as u32;
        out.at = [base, base + 1, base + 8, base + 9, base + 64, base + 65, base + 72, base + 73];
        out.whole = true;
        return out;
    }
    let n = top.neighbors(b);
    // Per axis: the brick offset and local coordinate of the lower and upper corner.
    let axis = |c: i32| [(c >> 3, (c & 7) as usize), ((c + 1) >> 3, ((c + 1) & 7) as usize)];
    let (ax, ay, az) = (axis(i.x), axis(i.y), axis(i.z));
    for k in 0..8 {
        let (x, y, z) = (ax[k & 1], ay[(k >> 1) & 1], az[k >> 2]);
        let nb = n[slot(x.0, y.0, z.0)];
        if nb != NONE {
            out.at[k] = nb * VOXELS as u32 + voxel(x.1, y.1, z.1) as u32;
        }
    }
    out
}

/// The value of `field` at brick `b`'s voxel `i` read through the neighbour table at offset
/// `d` (each in `-1..=1`), 0 outside the active bricks.
#[inline(always)]
pub fn offset(top: &Topology, field: &[f32], b: usize, i: usize, d: [i32; 3]) -> f32 {
    let l = [(i & 7) as i32 + d[0], ((i >> 3) & 7) as i32 + d[1], (i >> 6) as i32 + d[2]];
    let nb = top.neighbors(b)[slot(l[0] >> 3, l[1] >> 3, l[2] >> 3)];
    if nb == NONE {
        return 0.0;
    }
    field[nb as usize * VOXELS + voxel((l[0] & 7) as usize, (l[1] & 7) as usize, (l[2] & 7) as usize)]
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::IVec3;

    fn linear_field(top: &Topology) -> Vec<f32> {
        let mut f = vec![0.0; top.voxels()];
        for (b, c) in top.coords().iter().enumerate() {
            for i in 0..VOXELS {
                let g = (*c * 8) + IVec3::new((i & 7) as i32, ((i >> 3) & 7) as i32, (i >> 6) as i32);
                f[b * VOXELS + i] = 1.0 + 2.0 * g.x as f32 - 0.5 * g.y as f32 + 0.25 * g.z as f32;
            }
        }
        f
    }

    #[test]
    fn trilinear_sampling_is_exact_on_a_linear_field_across_bricks() {
        let mut coords = Vec::new();
        for z in -1..=1 {
            for y in -1..=1 {
                for x in -1..=1 {
                    coords.push(IVec3::new(x, y, z));
                }
            }
        }
        let top = Topology::new(coords);
        let f = linear_field(&top);
        let b = top.find(IVec3::ZERO).unwrap() as usize;
        for p in [Vec3::new(3.3, 4.1, 5.9), Vec3::new(7.5, 7.5, 7.5), Vec3::new(-0.5, 8.7, -3.2), Vec3::new(-6.0, 14.0, 0.1)] {
            let want = 1.0 + 2.0 * p.x - 0.5 * p.y + 0.25 * p.z;
            let c = corners(&top, b, p);
            assert!((c.sample(&f) - want).abs() < 1e-4, "{p}: {} vs {want}", c.sample(&f));
            assert!((c.w.iter().sum::<f32>() - 1.0).abs() < 1e-6);
            let (lo, hi) = c.range(&f);
            assert!(lo <= want + 1e-4 && want <= hi + 1e-4);
        }
        assert_eq!(offset(&top, &f, b, voxel(7, 0, 0), [1, -1, 0]), 1.0 + 16.0 + 0.5);
    }

    #[test]
    fn outside_the_active_bricks_reads_zero_and_far_points_are_clamped() {
        let top = Topology::new(vec![IVec3::ZERO]);
        let f = vec![1.0; VOXELS];
        let b = 0;
        assert_eq!(corners(&top, b, Vec3::splat(3.0)).sample(&f), 1.0);
        assert!((corners(&top, b, Vec3::new(7.5, 3.0, 3.0)).sample(&f) - 0.5).abs() < 1e-6);
        assert_eq!(corners(&top, b, Vec3::new(100.0, 3.0, 3.0)).sample(&f), 0.0);
        assert_eq!(corners(&top, b, Vec3::new(f32::NAN, 3.0, 3.0)).sample(&f), 1.0);
    }
}
