//! The `volume.source` node: one emitter per connected geometry (or a sphere, or a point list),
//! all with the node's rates.

use std::sync::Arc;

use glam::Vec3;
use pyrograph_core::declare::{Anim, Cook};
use pyrograph_core::value::{Place, Points};
use pyrograph_core::{AtPort, Clip, ClipOf, CookCtx, NodeError, PortType, ValueType, port};
use pyrograph_nodes_cloth::state::ClothState;
use pyrograph_nodes_particles::types::{Mesh, SpreadState};
use pyrograph_render::Particles;

use super::value::{Emitter, Geometry, Rates, TimedPoint, VolumeSource};

/// Most surface samples a mesh emitter may make.
pub const MAX_MESH_POINTS: usize = 4 << 20;

pyrograph_core::choice! {
    /// What a source emits from besides its connected inputs.
    pub enum Shape {
        /// Only the connected inputs (particles, roots, spread, cloth, mesh).
        Inputs = "inputs",
        /// A sphere of `radius` at `center` (which may move), plus the connected inputs.
        Sphere = "sphere",
        /// The `points` list, each from its time on, plus the connected inputs.
        Points = "points",
    }
}

fn no_clip<T: ValueType>() -> ClipOf<Arc<T>> {
    ClipOf::new(Clip::from_frames(PortType::of::<T>(), 0.0, Vec::new()))
}

fn origin_point() -> Arc<Points> {
    Arc::new(Points::new(vec![(0.0, Place::At([0.0; 3]))]).expect("a point at the origin at time 0 is a valid list"))
}

pyrograph_core::node! {
    /// A source of fuel, heat, smoke and velocity for volume.simulate (Fedkiw, Stam & Jensen 2001 §3.4;
    /// Nguyen, Fedkiw & Jensen 2002 §3: fuel injected where the flame's blue core is): every particle of a
    /// particle clip (Perry's flames, embers), the static roots, the burning flame roots of a fire spread (a
    /// burning house pours smoke where its faces burn), the masses of cloth flames, samples of a mesh's surface,
    /// a sphere or a point list emit a soft sphere of `radius` each. Fuel and smoke are added per second,
    /// temperature is held at least at `hold_temperature`, and the air is pulled to `velocity` (plus `inherit` times
    /// each point's own velocity), each falling off smoothly to the sphere's rim. Every rate is sampled at
    /// every sub-step of the simulation, so a keyed burst or a moving torch emits when and where it should.
    #[node("volume.source", "Volume", Source)]
    pub struct Source {
        /// Particles that emit, per frame (particles.particle_flame, particles.embers).
        particles: ClipOf<Arc<Particles>> = no_clip::<Particles>(),
        /// Fixed points that emit (particles.roots, particles.mesh_roots).
        roots: Arc<Particles> = Arc::new(Particles::default()),
        /// A fire spread whose live flame roots emit (particles.fire_spread).
        spread: ClipOf<Arc<SpreadState>> = no_clip::<SpreadState>(),
        /// Cloth flames whose masses emit (cloth.mass_spring_flame).
        cloth: ClipOf<Arc<ClothState>> = no_clip::<ClothState>(),
        /// A mesh whose surface emits (particles.mesh_load); also the surface `face(F)` points refer to.
        mesh: Arc<Mesh> = Arc::new(Mesh::default()),
        /// What else emits: only the inputs, a sphere, or the point list.
        shape: Shape = Shape::Sphere,
        /// Centre of the sphere (shape sphere).
        center: Anim<[f32; 3]> = Anim::constant([0.0, 0.0, 0.0]),
        /// Points that emit (shape points): `(x, y, z)`, `face(F)` on the mesh, or `(seconds, point)` to start later.
        points: Arc<Points> = origin_point(),
        /// Distance between the samples a mesh's surface emits from.
        #[range(1e-4, 1e4)]
        mesh_spacing: f32 = 0.05,
        /// Fuel added per second at each splat's centre.
        #[range(0.0, 1e6)]
        fuel_rate: Anim<f32> = Anim::constant(4.0),
        /// Smoke density added per second at each splat's centre.
        #[range(0.0, 1e6)]
        smoke_rate: Anim<f32> = Anim::constant(0.5),
        /// Temperature each splat holds its centre at (at least).
        #[range(0.0, 1e6)]
        hold_temperature: Anim<f32> = Anim::constant(1.0),
        /// Velocity each splat gives the air, world units per second.
        velocity: Anim<[f32; 3]> = Anim::constant([0.0, 1.0, 0.0]),
        /// Radius of each splat, world units.
        #[range(1e-5, 1e5)]
        radius: Anim<f32> = Anim::constant(0.2),
        /// Fraction of each point's own velocity (particles' velocity, a root's or spread root's direction, a mesh's normal) added to `velocity`.
        #[range(-1e3, 1e3)]
        inherit: f32 = 0.0,
    }
    /// The emitters.
    -> source: Arc<VolumeSource>
}

impl Cook for Source {
    fn cook(self, _: &CookCtx) -> Result<Arc<VolumeSource>, NodeError> {
        let rates = Rates {
            fuel: self.fuel_rate.clone(),
            smoke: self.smoke_rate.clone(),
            temperature: self.hold_temperature.clone(),
            velocity: self.velocity.clone(),
            radius: self.radius.clone(),
            inherit: self.inherit,
        };
        let mut emitters = Vec::new();
        let mut add =
            |label: &str, geometry: Geometry| emitters.push(Emitter { label: label.into(), geometry, rates: rates.clone() });
        if !self.particles.is_empty() {
            add(port!(Source, particles), Geometry::Particles(self.particles.clone().into_inner()));
        }
        if !self.roots.particles.is_empty() {
            let points =
                self.roots.particles.iter().map(|q| TimedPoint { position: q.position, velocity: q.velocity, start: 0.0 });
            add(port!(Source, roots), Geometry::Points(Arc::new(finite(points.collect()).at_port(port!(Source, roots))?)));
        }
        if !self.spread.is_empty() {
            add(port!(Source, spread), Geometry::Spread(self.spread.clone().into_inner()));
        }
        if !self.cloth.is_empty() {
            add(port!(Source, cloth), Geometry::Cloth(self.cloth.clone().into_inner()));
        }
        if !self.mesh.triangles.is_empty() && self.shape != Shape::Points {
            let samples = surface_samples(&self.mesh, self.mesh_spacing).at_port(port!(Source, mesh_spacing))?;
            add(port!(Source, mesh), Geometry::Points(Arc::new(finite(samples).at_port(port!(Source, mesh))?)));
        }
        match self.shape {
            Shape::Inputs => {}
            Shape::Sphere => add(port!(Source, center), Geometry::Sphere(self.center.clone())),
            Shape::Points => add(
                port!(Source, points),
                Geometry::Points(Arc::new(listed_points(&self.points, &self.mesh).at_port(port!(Source, points))?)),
            ),
        }
        if emitters.is_empty() {
            return Err(NodeError::port(
                port!(Source, shape),
                "nothing emits: connect particles, roots, a spread, cloth or a mesh, or set shape to sphere or points",
            ));
        }
        Ok(Arc::new(VolumeSource { emitters }))
    }
}

/// `points` when every position and velocity is finite, else which is not.
fn finite(points: Vec<TimedPoint>) -> Result<Vec<TimedPoint>, String> {
    match points.iter().position(|q| !q.position.iter().chain(&q.velocity).all(|x| x.is_finite())) {
        Some(k) => Err(format!("point {k} has a non-finite position or velocity")),
        None => Ok(points),
    }
}

/// The point list as emitting points: positions as written, faces on the mesh.
fn listed_points(points: &Points, mesh: &Mesh) -> Result<Vec<TimedPoint>, String> {
    let mut out = Vec::with_capacity(points.points().len());
    for (k, (time, place)) in points.points().iter().enumerate() {
        let position = match place {
            Place::At(p) => p.map(|x| x as f32),
            Place::Face(face, bary) => {
                let Some(tri) = mesh.triangles.get(*face as usize) else {
                    return Err(format!(
                        "point {}: face {face} is past the {} faces of the connected mesh (connect a mesh to use faces)",
                        k + 1,
                        mesh.triangles.len()
                    ));
                };
                let b = bary.map_or([1.0 / 3.0; 3], |b| b.map(|c| c as f32));
                let v = tri.map(|i| Vec3::from_array(mesh.positions[i as usize]));
                (v[0] * b[0] + v[1] * b[1] + v[2] * b[2]).to_array()
            }
        };
        out.push(TimedPoint { position, velocity: [0.0; 3], start: *time as f32 });
    }
    Ok(out)
}

/// Points over a mesh's surface about `spacing` apart: each triangle is cut into k² smaller ones
/// (k = its longest edge / spacing, rounded up) and each small one emits from its centre, with the
/// face normal as its velocity.
pub fn surface_samples(mesh: &Mesh, spacing: f32) -> Result<Vec<TimedPoint>, String> {
    let mut out = Vec::new();
    for (t, tri) in mesh.triangles.iter().enumerate() {
        let v = tri.map(|i| Vec3::from_array(mesh.positions[i as usize]));
        let longest = (v[1] - v[0]).length().max((v[2] - v[1]).length()).max((v[0] - v[2]).length());
        let k = (longest / spacing).ceil().max(1.0);
        if !k.is_finite() || out.len() as f32 + k * k > MAX_MESH_POINTS as f32 {
            return Err(format!(
                "sampling the mesh every {spacing} would make over {MAX_MESH_POINTS} points (at face {t}); raise mesh_spacing"
            ));
        }
        let k = k as usize;
        let normal = mesh.normals.get(t).copied().unwrap_or([0.0, 1.0, 0.0]);
        let (e1, e2) = ((v[1] - v[0]) / k as f32, (v[2] - v[0]) / k as f32);
        for i in 0..k {
            for j in 0..k - i {
                // The centre of the small triangle pointing the same way as the face...
                let p = v[0] + e1 * (i as f32 + 1.0 / 3.0) + e2 * (j as f32 + 1.0 / 3.0);
                out.push(TimedPoint { position: p.to_array(), velocity: normal, start: 0.0 });
                // ... and of the one pointing the other way, between three of those.
                if i + j + 1 < k {
                    let q = v[0] + e1 * (i as f32 + 2.0 / 3.0) + e2 * (j as f32 + 2.0 / 3.0);
                    out.push(TimedPoint { position: q.to_array(), velocity: normal, start: 0.0 });
                }
            }
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_triangle_is_covered_by_k_squared_samples_inside_it() {
        let mesh = Mesh {
            positions: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            triangles: vec![[0, 1, 2]],
            normals: vec![[0.0, 0.0, 1.0]],
            ..Mesh::default()
        };
        let s = surface_samples(&mesh, 0.26).unwrap();
        // Longest edge √2 / 0.26 → k = 6: 36 small triangles.
        assert_eq!(s.len(), 36);
        assert!(s.iter().all(|q| q.position[0] > 0.0 && q.position[1] > 0.0 && q.position[0] + q.position[1] < 1.0));
        assert!(s.iter().all(|q| q.velocity == [0.0, 0.0, 1.0]));
        let e = surface_samples(&mesh, 1e-4).unwrap_err().to_string();
        assert!(e.contains("mesh_spacing") && e.contains("raise"), "{e}");
    }
}
