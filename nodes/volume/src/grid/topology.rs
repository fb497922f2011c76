//! Which bricks of a sparse grid are active: their coordinates in a fixed order, a map from
//! coordinate to index, and for each brick the indices of its 26 neighbours, so a stencil or a
//! sample near a brick's edge finds the next brick with one table read instead of a hash lookup.

use foldhash::HashMap;
use glam::IVec3;

/// log2 of a brick's edge in voxels.
pub const LOG2: i32 = 3;
/// A brick's edge in voxels (8, as OpenVDB's leaf nodes and Houdini's sparse pyro tiles).
pub const DIM: usize = 8;
/// Voxels in a brick.
pub const VOXELS: usize = DIM * DIM * DIM;
/// No brick there.
pub const NONE: u32 = u32::MAX;

/// The index of voxel `(x, y, z)` inside a brick (each in `0..8`): x fastest, then y, then z.
#[inline(always)]
pub fn voxel(x: usize, y: usize, z: usize) -> usize {
    x | (y << 3) | (z << 6)
}

/// The slot of the neighbour at offset `(dx, dy, dz)` (each in `-1..=1`) in [`Topology::neighbors`].
#[inline(always)]
pub fn slot(dx: i32, dy: i32, dz: i32) -> usize {
    ((dx + 1) + 3 * (dy + 1) + 9 * (dz + 1)) as usize
}

/// The brick holding voxel `v` (floor division by 8).
#[inline(always)]
pub fn brick_of(v: IVec3) -> IVec3 {
    IVec3::new(v.x >> LOG2, v.y >> LOG2, v.z >> LOG2)
}

/// The active bricks of a sparse grid, sorted by z, then y, then x (so every pass visits them in
/// the same order and results do not depend on how the set was built).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Topology {
    coords: Vec<IVec3>,
    /// foldhash, seeded per process: a march looks a brick up each time a ray enters an inactive
    /// one, and SipHash cost a tenth of a render.
    index: HashMap<IVec3, u32>,
    neighbors: Vec<[u32; 27]>,
}

impl Topology {
    /// The bricks at `coords` (brick coordinates: voxel coordinates divided by 8), duplicates
    /// removed.
    pub fn new(mut coords: Vec<IVec3>) -> Topology {
        coords.sort_unstable_by_key(|c| (c.z, c.y, c.x));
        coords.dedup();
        let index: HashMap<IVec3, u32> = coords.iter().enumerate().map(|(i, c)| (*c, i as u32)).collect();
        let neighbors = coords
            .iter()
            .map(|c| {
                let mut n = [NONE; 27];
                for dz in -1..=1 {
                    for dy in -1..=1 {
                        for dx in -1..=1 {
                            n[slot(dx, dy, dz)] = index.get(&(*c + IVec3::new(dx, dy, dz))).copied().unwrap_or(NONE);
                        }
                    }
                }
                n
            })
            .collect();
        Topology { coords, index, neighbors }
    }

    /// Number of active bricks.
    pub fn len(&self) -> usize {
        self.coords.len()
    }

    /// No active brick.
    pub fn is_empty(&self) -> bool {
        self.coords.is_empty()
    }

    /// Active voxels (every voxel of an active brick).
    pub fn voxels(&self) -> usize {
        self.coords.len() * VOXELS
    }

    /// The brick coordinates, in order.
    pub fn coords(&self) -> &[IVec3] {
        &self.coords
    }

    /// The index of the brick at `c`, if active.
    pub fn find(&self, c: IVec3) -> Option<u32> {
        self.index.get(&c).copied()
    }

    /// The 27 neighbour slots of brick `b` (itself in the middle), [`NONE`] where inactive.
    #[inline(always)]
    pub fn neighbors(&self, b: usize) -> &[u32; 27] {
        &self.neighbors[b]
    }

    /// The voxel coordinate of brick `b`'s first voxel.
    #[inline(always)]
    pub fn origin(&self, b: usize) -> IVec3 {
        self.coords[b] << LOG2
    }

    /// The first and last voxel of the active bricks' bounding box (`None` when empty).
    pub fn voxel_bounds(&self) -> Option<(IVec3, IVec3)> {
        let first = *self.coords.first()?;
        let (lo, hi) = self.coords.iter().fold((first, first), |(lo, hi), c| (lo.min(*c), hi.max(*c)));
        Some((lo << LOG2, ((hi + IVec3::ONE) << LOG2) - IVec3::ONE))
    }
}

/// A field laid out on `to` holding `from`'s values where the two share bricks and `fill`
/// elsewhere (bricks activated or retired between two steps).
pub fn remap<T: Copy + Send + Sync>(from: &Topology, to: &Topology, data: &[T], fill: T) -> Vec<T> {
    use rayon::prelude::*;
    let mut out = vec![fill; to.voxels()];
    out.par_chunks_mut(VOXELS).zip(to.coords.par_iter()).for_each(|(dst, c)| {
        if let Some(b) = from.find(*c) {
            dst.copy_from_slice(&data[b as usize * VOXELS..(b as usize + 1) * VOXELS]);
        }
    });
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bricks_are_sorted_deduplicated_and_know_their_neighbours() {
        let t = Topology::new(vec![IVec3::new(1, 0, 0), IVec3::ZERO, IVec3::new(0, 0, 1), IVec3::ZERO, IVec3::new(-1, 0, 0)]);
        assert_eq!(t.coords(), &[IVec3::new(-1, 0, 0), IVec3::ZERO, IVec3::new(1, 0, 0), IVec3::new(0, 0, 1)]);
        let centre = t.find(IVec3::ZERO).unwrap() as usize;
        let n = t.neighbors(centre);
        assert_eq!(n[slot(0, 0, 0)], centre as u32);
        assert_eq!(n[slot(1, 0, 0)], t.find(IVec3::X).unwrap());
        assert_eq!(n[slot(-1, 0, 0)], t.find(-IVec3::X).unwrap());
        assert_eq!(n[slot(0, 0, 1)], t.find(IVec3::Z).unwrap());
        assert_eq!(n[slot(0, 1, 0)], NONE);
        assert_eq!(t.voxel_bounds(), Some((IVec3::new(-8, 0, 0), IVec3::new(15, 7, 15))));
        assert_eq!(brick_of(IVec3::new(-1, 8, 15)), IVec3::new(-1, 1, 1));
    }

    #[test]
    fn remapping_keeps_shared_bricks_and_fills_new_ones() {
        let a = Topology::new(vec![IVec3::ZERO, IVec3::X]);
        let b = Topology::new(vec![IVec3::X, IVec3::Y]);
        let data: Vec<f32> = (0..a.voxels()).map(|i| i as f32).collect();
        let out = remap(&a, &b, &data, -1.0);
        let x = b.find(IVec3::X).unwrap() as usize;
        assert_eq!(&out[x * VOXELS..(x + 1) * VOXELS], &data[VOXELS..2 * VOXELS]);
        let y = b.find(IVec3::Y).unwrap() as usize;
        assert!(out[y * VOXELS..(y + 1) * VOXELS].iter().all(|v| *v == -1.0));
    }
}
