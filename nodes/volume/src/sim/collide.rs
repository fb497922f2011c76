//! Colliders as solid voxels: a floor below a height, and a closed mesh voxelised once per
//! simulation by ray parity along z (a voxel centre is inside when a ray from it crosses the
//! surface an odd number of times), with the voxels the surface passes through along every axis
//! marked too, so thin or open shells still block the flow.

use std::collections::HashMap;

use glam::{IVec3, Vec2, Vec3};
use pyrograph_nodes_particles::types::Mesh;
use rayon::prelude::*;

use crate::grid::{Topology, VOXELS, brick_of, voxel};

/// Most voxels a collider's bounding box may span when voxelised.
pub const MAX_COLLIDER_VOXELS: u64 = 1 << 28;

/// The solid voxels of a simulation.
#[derive(Clone, Debug, Default)]
pub struct Solids {
    /// Voxel centres below this index-space height are solid.
    floor: Option<f32>,
    /// Solid voxels of the collider mesh: per brick, one bit per voxel.
    mesh: HashMap<IVec3, [u64; 8]>,
}

impl Solids {
    /// A floor at world height `floor` (if any) and the voxels of `mesh` (if it has faces) at voxel
    /// size `h`. Errors when the mesh's bounding box spans more than [`MAX_COLLIDER_VOXELS`].
    pub fn new(floor: Option<f32>, mesh: &Mesh, h: f32) -> Result<Solids, String> {
        let mut s = Solids { floor: floor.map(|y| y / h), mesh: HashMap::new() };
        if !mesh.triangles.is_empty() {
            s.voxelise(mesh, h)?;
        }
        Ok(s)
    }

    /// Whether nothing is solid.
    pub fn is_empty(&self) -> bool {
        self.floor.is_none() && self.mesh.is_empty()
    }

    fn set(&mut self, v: IVec3) {
        let l = v & IVec3::splat(7);
        let i = voxel(l.x as usize, l.y as usize, l.z as usize);
        self.mesh.entry(brick_of(v)).or_insert([0; 8])[i >> 6] |= 1 << (i & 63);
    }

    fn voxelise(&mut self, mesh: &Mesh, h: f32) -> Result<(), String> {
        let tris: Vec<[Vec3; 3]> =
            mesh.triangles.iter().map(|t| t.map(|i| Vec3::from_array(mesh.positions[i as usize]) / h)).collect();
        let (lo, hi) = tris.iter().flatten().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| (lo.min(*p), hi.max(*p)));
        let span = (hi - lo + 2.0).max(Vec3::ONE);
        if !span.is_finite() || (span.x as f64) * (span.y as f64) * (span.z as f64) > MAX_COLLIDER_VOXELS as f64 {
            return Err(format!(
                "the collider spans {:.0} × {:.0} × {:.0} voxels, more than {MAX_COLLIDER_VOXELS}; raise voxel_size",
                span.x, span.y, span.z
            ));
        }
        // Crossings of the rays along each axis through voxel centres: (column, depth). The rays
        // pass a hair off the centres, so none runs exactly along an edge two triangles share
        // (which would count one crossing twice or not at all).
        const NUDGE: Vec2 = Vec2::new(1.234_567e-4, 2.345_678e-4);
        for axis in 0..3 {
            let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
            let mut columns: HashMap<(i32, i32), Vec<f32>> = HashMap::new();
            for t in &tris {
                let p = t.map(|q| Vec2::new(q[u], q[v]));
                let (a, b) = (p[0].min(p[1]).min(p[2]).ceil().as_ivec2(), p[0].max(p[1]).max(p[2]).floor().as_ivec2());
                for j in a.y..=b.y {
                    for i in a.x..=b.x {
                        if let Some(w) = barycentric(p, Vec2::new(i as f32, j as f32) + NUDGE) {
                            let depth = w[0] * t[0][axis] + w[1] * t[1][axis] + w[2] * t[2][axis];
                            columns.entry((i, j)).or_default().push(depth);
                        }
                    }
                }
            }
            for ((i, j), mut depths) in columns {
                depths.sort_by(f32::total_cmp);
                let at = |d: i32| {
                    let mut c = IVec3::ZERO;
                    (c[axis], c[u], c[v]) = (d, i, j);
                    c
                };
                for d in &depths {
                    self.set(at(d.round() as i32));
                }
                // Parity fill along z only: a mesh seen edge-on along one axis stays consistent.
                if axis == 2 {
                    for pair in depths.chunks_exact(2) {
                        for d in pair[0].ceil() as i32..=pair[1].floor() as i32 {
                            self.set(at(d));
                        }
                    }
                }
            }
        }
        Ok(())
    }

    /// One flag per voxel of `top`: solid or not.
    pub fn mask(&self, top: &Topology) -> Vec<bool> {
        let mut out = vec![false; top.voxels()];
        if self.is_empty() {
            return out;
        }
        out.par_chunks_mut(VOXELS).zip(top.coords().par_iter()).for_each(|(o, c)| {
            let bits = self.mesh.get(c);
            let y0 = (c.y * 8) as f32;
            for (i, s) in o.iter_mut().enumerate() {
                let below = self.floor.is_some_and(|f| y0 + (((i >> 3) & 7) as f32) < f);
                *s = below || bits.is_some_and(|b| b[i >> 6] >> (i & 63) & 1 == 1);
            }
        });
        out
    }
}

/// The barycentric coordinates of `q` in triangle `p`, if strictly inside.
fn barycentric(p: [Vec2; 3], q: Vec2) -> Option<[f32; 3]> {
    let area = (p[1] - p[0]).perp_dot(p[2] - p[0]);
    if area.abs() < 1e-12 {
        return None;
    }
    let w0 = (p[1] - q).perp_dot(p[2] - q) / area;
    let w1 = (p[2] - q).perp_dot(p[0] - q) / area;
    let w2 = 1.0 - w0 - w1;
    (w0 > 0.0 && w1 > 0.0 && w2 > 0.0).then_some([w0, w1, w2])
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cube(lo: f32, hi: f32) -> Mesh {
        let v = |x: f32, y: f32, z: f32| [x, y, z];
        let positions = vec![
            v(lo, lo, lo),
            v(hi, lo, lo),
            v(hi, hi, lo),
            v(lo, hi, lo),
            v(lo, lo, hi),
            v(hi, lo, hi),
            v(hi, hi, hi),
            v(lo, hi, hi),
        ];
        let quads = [[0, 3, 2, 1], [4, 5, 6, 7], [0, 1, 5, 4], [2, 3, 7, 6], [1, 2, 6, 5], [0, 4, 7, 3]];
        let triangles = quads.iter().flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]).collect();
        Mesh { positions, triangles, ..Mesh::default() }
    }

    #[test]
    fn a_closed_cube_fills_its_inside_and_nothing_outside() {
        let h = 0.1;
        let s = Solids::new(None, &cube(-0.44, 0.44), h).unwrap();
        let top = Topology::new((0..8).map(|k| IVec3::new(k & 1, (k >> 1) & 1, k >> 2) - IVec3::ONE).collect());
        let mask = s.mask(&top);
        let at = |v: IVec3| {
            let b = top.find(brick_of(v)).unwrap() as usize;
            let l = v & IVec3::splat(7);
            mask[b * VOXELS + voxel(l.x as usize, l.y as usize, l.z as usize)]
        };
        // Centres at −0.4..0.4 are inside (±4 voxels); ±5 is outside.
        assert!(at(IVec3::new(0, 0, 0)) && at(IVec3::new(-4, 3, -2)) && at(IVec3::new(4, 4, 0)));
        assert!(!at(IVec3::new(5, 0, 0)) && !at(IVec3::new(0, -6, 0)) && !at(IVec3::new(-8, 0, -8)));
        let solid = mask.iter().filter(|s| **s).count();
        assert!(solid > 0);
    }

    #[test]
    fn a_floor_makes_everything_below_it_solid() {
        let s = Solids::new(Some(0.25), &Mesh::default(), 0.1).unwrap();
        let top = Topology::new(vec![IVec3::ZERO]);
        let mask = s.mask(&top);
        assert!(mask[voxel(3, 2, 3)] && !mask[voxel(3, 3, 3)]);
        let huge = Solids::new(None, &cube(-1e6, 1e6), 0.1).unwrap_err();
        assert!(huge.contains("raise voxel_size"), "{huge}");
    }
}
