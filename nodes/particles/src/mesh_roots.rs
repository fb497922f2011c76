//! Flame roots on a mesh (`particles.mesh_roots`): points spread over the upward-facing surface
//! of a mesh — the logs of a campfire, a brazier's coals — where particle flames start.

use std::sync::Arc;

use glam::Vec3;
use pyrograph_core::declare::Cook;
use pyrograph_core::{CookCtx, NodeError, port};
use pyrograph_render::{Particle, Particles};

use crate::flame::unit_random;
use crate::types::Mesh;

pyrograph_core::node! {
    /// Flame roots p(0) on a mesh (Perry 1994 §3.4: flames start on the burning surface, v_p along its
    /// normal): `count` points spread over the faces whose normal points up at least `facing`, each face
    /// chosen with probability proportional to its area, at a random point of it (seeded). A root's
    /// direction leans from the face normal towards straight up by `upright`. Output particles carry the
    /// root in `position` and the direction in `velocity`, like particles.roots.
    #[node("particles.mesh_roots", "Particles", Source)]
    pub struct MeshRoots {
        /// The surface (particles.mesh_load).
        mesh: Arc<Mesh>,
        /// Number of roots.
        #[range(1, 100_000)]
        count: usize = 64,
        /// Least upward component of a face normal for roots on it (−1: every face).
        #[range(-1.0, 1.0)]
        facing: f32 = 0.3,
        /// How far roots sit off the surface, along the face normal.
        #[range(0.0, 1000.0)]
        offset: f32 = 0.0,
        /// 0: flames start along the face normal; 1: straight up.
        #[range(0.0, 1.0)]
        upright: f32 = 0.6,
        /// Seed of the placement.
        #[range(0, u32::MAX)]
        seed: u32 = 0,
    }
    /// Root particles.
    -> roots: Arc<Particles>
}

/// Roots on `mesh` (see `particles.mesh_roots`); `None` when no face faces up enough.
pub fn mesh_roots(mesh: &Mesh, count: usize, facing: f32, offset: f32, upright: f32, seed: u32) -> Option<Vec<Particle>> {
    let corner = |t: usize, k: usize| Vec3::from_array(mesh.positions[mesh.triangles[t][k] as usize]);
    // Cumulative area of the faces that qualify.
    let mut faces = Vec::new();
    let mut cumulative = Vec::new();
    let mut total = 0.0f32;
    for t in 0..mesh.triangles.len() {
        let n = Vec3::from_array(mesh.normals[t]);
        if n.y < facing {
            continue;
        }
        let area = 0.5 * (corner(t, 1) - corner(t, 0)).cross(corner(t, 2) - corner(t, 0)).length();
        if area > 0.0 && area.is_finite() {
            total += area;
            faces.push(t);
            cumulative.push(total);
        }
    }
    if faces.is_empty() {
        return None;
    }
    let roots = (0..count)
        .map(|i| {
            let pick = unit_random(seed, i, 21) * total;
            let f = faces[cumulative.partition_point(|&c| c < pick).min(faces.len() - 1)];
            // A uniform point of the triangle (square-root warp of two uniforms).
            let (a, b) = (unit_random(seed, i, 22).sqrt(), unit_random(seed, i, 23));
            let p = corner(f, 0) * (1.0 - a) + corner(f, 1) * (a * (1.0 - b)) + corner(f, 2) * (a * b);
            let n = Vec3::from_array(mesh.normals[f]);
            let dir = (n * (1.0 - upright) + Vec3::Y * upright).normalize_or(Vec3::Y);
            Particle { position: (p + n * offset).to_array(), velocity: dir.to_array(), group: i as u32, ..Particle::default() }
        })
        .collect();
    Some(roots)
}

impl Cook for MeshRoots {
    fn cook(self, _: &CookCtx) -> Result<Arc<Particles>, NodeError> {
        if self.mesh.normals.len() != self.mesh.triangles.len() {
            return Err(NodeError::port(
                port!(MeshRoots, mesh),
                "the mesh has no face normals: load it with particles.mesh_load",
            ));
        }
        let particles =
            mesh_roots(&self.mesh, self.count, self.facing, self.offset, self.upright, self.seed).ok_or_else(|| {
                NodeError::port(
                    port!(MeshRoots, facing),
                    format!("no face of the mesh has a normal pointing up by {} or more: lower facing", self.facing),
                )
            })?;
        Ok(Arc::new(Particles { particles, sides: 0, time: 0.0, trails: false }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{build_mesh, cube};

    #[test]
    fn roots_lie_on_the_faces_that_face_up() {
        let mesh = build_mesh(&cube(2.0, 2), 0, true).unwrap();
        let roots = mesh_roots(&mesh, 200, 0.5, 0.0, 0.0, 3).unwrap();
        assert_eq!(roots.len(), 200);
        for r in &roots {
            let p = Vec3::from_array(r.position);
            assert!((p.y - 1.0).abs() < 1e-5 && p.x.abs() <= 1.0 + 1e-5 && p.z.abs() <= 1.0 + 1e-5, "on the top face: {p}");
            assert!((Vec3::from_array(r.velocity) - Vec3::Y).length() < 1e-5);
        }
        // Spread over the face, not bunched: every quadrant of the top gets some.
        let quadrants = |sx: f32, sz: f32| roots.iter().filter(|r| r.position[0] * sx > 0.0 && r.position[2] * sz > 0.0).count();
        assert!([(1.0, 1.0), (1.0, -1.0), (-1.0, 1.0), (-1.0, -1.0)].iter().all(|&(x, z)| quadrants(x, z) > 25));
        // Every face, leaning upright: directions between the normal and up.
        let all = mesh_roots(&mesh, 300, -1.0, 0.1, 0.5, 3).unwrap();
        assert!(all.iter().any(|r| r.position[1] < -0.9), "the bottom face gets roots too");
        assert!(mesh_roots(&mesh, 5, 1.01, 0.0, 0.0, 3).is_none());
    }
}
