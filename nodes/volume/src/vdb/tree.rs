//! The tree of an OpenVDB grid in file order: a root table of 4096³ regions, each a 32³
//! internal node of 16³ internal nodes of 8³ leaves, visited depth first with children in
//! slot order (x-major: slot = x·N² + y·N + z). A brick of a volume is a leaf.

use std::collections::BTreeMap;

use glam::IVec3;

/// Slot of the 4-node holding leaf origin `v` within its 5-node.
pub fn slot5(v: IVec3) -> usize {
    ((((v.x & 4095) >> 7) << 10) | (((v.y & 4095) >> 7) << 5) | ((v.z & 4095) >> 7)) as usize
}

/// Slot of the leaf at origin `v` within its 4-node.
pub fn slot4(v: IVec3) -> usize {
    ((((v.x & 127) >> 3) << 8) | (((v.y & 127) >> 3) << 4) | ((v.z & 127) >> 3)) as usize
}

/// The origin of the 5-node holding voxel `v`.
pub fn origin5(v: IVec3) -> IVec3 {
    IVec3::new(v.x & !4095, v.y & !4095, v.z & !4095)
}

/// The x, y, z of `slot` in a node of `2^log2` children per axis.
pub fn slot_xyz(slot: usize, log2: u32) -> IVec3 {
    let m = (1 << log2) - 1;
    IVec3::new((slot >> (2 * log2)) as i32, ((slot >> log2) & m) as i32, (slot & m) as i32)
}

/// A brick's voxel index (x fastest) as OpenVDB's leaf index (x-major), and back: the two swap
/// the x and z bit groups.
#[inline(always)]
pub fn vdb_index(i: usize) -> usize {
    ((i & 7) << 6) | (((i >> 3) & 7) << 3) | (i >> 6)
}

/// Leaf origins (voxel coordinates, multiples of 8) grouped as the file lists them: by 5-node
/// origin (x, then y, then z), then 4-node slot, then leaf slot. Each value is the caller's leaf.
pub type Layout = BTreeMap<(i32, i32, i32), BTreeMap<usize, BTreeMap<usize, usize>>>;

/// The file order of leaves at `origins` (their positions in the slice are the map's values).
pub fn layout(origins: &[IVec3]) -> Layout {
    let mut out: Layout = BTreeMap::new();
    for (k, v) in origins.iter().enumerate() {
        let o = origin5(*v);
        out.entry((o.x, o.y, o.z)).or_default().entry(slot5(*v)).or_default().insert(slot4(*v), k);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slots_invert_and_negative_coordinates_land_in_their_own_nodes() {
        for v in [IVec3::new(8, 136, 4088), IVec3::new(-8, -4096, 120), IVec3::new(4096 + 128, 0, -136)] {
            let o = origin5(v);
            let o4 = o + (slot_xyz(slot5(v), 5) * 128);
            let leaf = o4 + (slot_xyz(slot4(v), 4) * 8);
            assert_eq!(leaf, v, "{v}");
        }
        assert_eq!(origin5(IVec3::new(-8, 0, 0)), IVec3::new(-4096, 0, 0));
        // Voxel (1, 2, 3) of a leaf is OpenVDB's index 83 (the spec's example).
        assert_eq!(vdb_index(1 | (2 << 3) | (3 << 6)), 83);
    }
}
