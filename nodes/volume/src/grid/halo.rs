//! A brick with a one-voxel border read from its six face neighbours: a 10³ tile every 7-point
//! stencil (divergence, gradient, Laplacian, curl) reads with plain indexing, so the stencils have
//! no edge cases and no per-voxel brick lookups. Edge and corner cells of the border are not read
//! by a 7-point stencil and stay at the fill value.

use super::topology::{NONE, Topology, VOXELS, slot, voxel};

/// Cells of a tile.
pub const TILE: usize = 1000;

/// The tile index of brick voxel `(x, y, z)`, each in `-1..=8`.
#[inline(always)]
pub const fn t(x: i32, y: i32, z: i32) -> usize {
    ((x + 1) + 10 * (y + 1) + 100 * (z + 1)) as usize
}

/// Steps between neighbouring cells of a tile along x, y and z.
pub const STRIDE: [usize; 3] = [1, 10, 100];

/// Fills `tile` with brick `b` of `field` and the face cells of its neighbours; cells outside the
/// active bricks read `fill`.
pub fn gather(top: &Topology, field: &[f32], b: usize, fill: f32, tile: &mut [f32; TILE]) {
    let n = top.neighbors(b);
    let brick = &field[b * VOXELS..(b + 1) * VOXELS];
    for z in 0..8 {
        for y in 0..8 {
            let row = &brick[voxel(0, y, z)..voxel(0, y, z) + 8];
            let at = t(0, y as i32, z as i32);
            tile[at..at + 8].copy_from_slice(row);
        }
    }
    // The faces across x: one value per row, strided.
    for (s, dst, src) in [(slot(-1, 0, 0), -1, 7usize), (slot(1, 0, 0), 8, 0)] {
        let nb = n[s];
        for z in 0..8 {
            for y in 0..8 {
                tile[t(dst, y as i32, z as i32)] = if nb == NONE { fill } else { field[nb as usize * VOXELS + voxel(src, y, z)] };
            }
        }
    }
    // The faces across y and z: whole rows.
    for (s, dst, src, axis) in
        [(slot(0, -1, 0), -1, 7usize, 1), (slot(0, 1, 0), 8, 0, 1), (slot(0, 0, -1), -1, 7, 2), (slot(0, 0, 1), 8, 0, 2)]
    {
        let nb = n[s];
        for c in 0..8 {
            let (at, from) =
                if axis == 1 { (t(0, dst, c as i32), voxel(0, src, c)) } else { (t(0, c as i32, dst), voxel(0, c, src)) };
            let row = &mut tile[at..at + 8];
            if nb == NONE {
                row.fill(fill);
            } else {
                let b = nb as usize * VOXELS + from;
                row.copy_from_slice(&field[b..b + 8]);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::IVec3;

    #[test]
    fn a_tile_reads_its_face_neighbours_and_the_fill_beyond() {
        let top = Topology::new(vec![IVec3::ZERO, IVec3::X, IVec3::new(0, 0, -1)]);
        // Each voxel holds its global x + 100 y + 10000 z.
        let mut field = vec![0.0; top.voxels()];
        for (b, c) in top.coords().iter().enumerate() {
            for i in 0..VOXELS {
                let g = (*c * 8) + IVec3::new((i & 7) as i32, ((i >> 3) & 7) as i32, (i >> 6) as i32);
                field[b * VOXELS + i] = (g.x + 100 * g.y + 10000 * g.z) as f32;
            }
        }
        let mut tile = [0.0; TILE];
        let b = top.find(IVec3::ZERO).unwrap() as usize;
        gather(&top, &field, b, -5.0, &mut tile);
        assert_eq!(tile[t(3, 4, 5)], 3.0 + 400.0 + 50000.0);
        assert_eq!(tile[t(8, 2, 1)], 8.0 + 200.0 + 10000.0, "from the +x brick");
        assert_eq!(tile[t(1, 2, -1)], 1.0 + 200.0 - 10000.0, "from the −z brick");
        assert_eq!(tile[t(-1, 2, 1)], -5.0, "no −x brick");
        assert_eq!(tile[t(2, 8, 1)], -5.0, "no +y brick");
    }
}
