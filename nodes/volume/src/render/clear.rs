//! Empty-space skipping inside the active bricks: a brick whose every sample reads nothing (no
//! smoke, no heat, no flame) is stepped over like an inactive one. A simulation keeps bricks
//! active around its smoke (its margin, and the box a cache or a dense grid fills), so a ray can
//! cross many such bricks; a march that stepped through them would add exactly nothing, because
//! a segment without density or emission neither absorbs nor glows. Skipping them is therefore
//! exact, frame for frame the same bytes, as production renderers skip empty space with a coarse
//! grid of maxima (Mitsuba 3's majorant grid, OpenVDB's tree of tiles).

use rayon::prelude::*;

use crate::grid::{NONE, Topology, VOXELS, slot, voxel};

/// Per brick of `top`: whether every trilinear sample whose nearest voxel lies in it reads at
/// most 0 from each of `fields` (so the march's clamped samples read exactly 0). Such a sample
/// reads the brick's voxels and the one-voxel shell around it, so the brick and the layers of
/// its 26 neighbours that face it must all be ≤ 0 (NaN counts as something there).
pub fn clear_bricks(top: &Topology, fields: &[&[f32]]) -> Vec<bool> {
    let nothing = |v: f32| v <= 0.0;
    let own: Vec<bool> = (0..top.len())
        .into_par_iter()
        .map(|b| fields.iter().all(|f| f[b * VOXELS..(b + 1) * VOXELS].iter().all(|v| nothing(*v))))
        .collect();
    (0..top.len()).into_par_iter().map(|b| own[b] && shell_clear(top, fields, &own, b, nothing)).collect()
}

/// Whether the voxels of brick `b`'s neighbours that touch it are all nothing.
fn shell_clear(top: &Topology, fields: &[&[f32]], own: &[bool], b: usize, nothing: impl Fn(f32) -> bool) -> bool {
    let n = top.neighbors(b);
    // Along each axis, the neighbour's layer facing `b`: its last, all or its first.
    let layer = |d: i32| match d {
        -1 => 7..8,
        1 => 0..1,
        _ => 0..8,
    };
    for dz in -1..=1 {
        for dy in -1..=1 {
            for dx in -1..=1 {
                let nb = n[slot(dx, dy, dz)];
                if (dx, dy, dz) == (0, 0, 0) || nb == NONE || own[nb as usize] {
                    continue;
                }
                let base = nb as usize * VOXELS;
                for z in layer(dz) {
                    for y in layer(dy) {
                        for x in layer(dx) {
                            if fields.iter().any(|f| !nothing(f[base + voxel(x, y, z)])) {
                                return false;
                            }
                        }
                    }
                }
            }
        }
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::IVec3;

    #[test]
    fn a_brick_is_clear_only_when_it_and_the_layers_touching_it_are_empty() {
        let coords: Vec<IVec3> = (0..4).map(|x| IVec3::new(x, 0, 0)).collect();
        let top = Topology::new(coords.clone());
        let at = |c: i32| top.find(IVec3::new(c, 0, 0)).unwrap() as usize;
        let mut f = vec![0.0f32; top.voxels()];
        // Smoke in brick 0's far face (x = 7), touching brick 1, and deep inside brick 3 (x = 3).
        f[at(0) * VOXELS + voxel(7, 4, 4)] = 0.5;
        f[at(3) * VOXELS + voxel(3, 4, 4)] = 0.5;
        let clear = clear_bricks(&top, &[&f]);
        let by = |c: i32| clear[at(c)];
        assert!(!by(0) && !by(1), "brick 1 reads brick 0's face");
        assert!(by(2), "brick 3's smoke is four voxels from brick 2");
        assert!(!by(3));
        // Negative values read as nothing; NaN as something.
        f[at(2) * VOXELS + voxel(0, 0, 0)] = -1.0;
        assert!(clear_bricks(&top, &[&f])[at(2)]);
        f[at(2) * VOXELS + voxel(0, 0, 0)] = f32::NAN;
        assert!(!clear_bricks(&top, &[&f])[at(2)]);
        // A second field counts as much as the first.
        let g = vec![0.1f32; top.voxels()];
        assert!(clear_bricks(&top, &[&f, &g]).iter().all(|c| !c));
    }
}
