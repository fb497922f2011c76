//! Particles, the drawing primitive of Perry 1994 §3.2.1 (camera-facing fuzzy N-gons), shared by
//! the particle-flame and cloth-flame nodes that make and draw them.

use std::hash::Hash;

use pyrograph_core::fingerprint::{Fingerprinter, hash_f32s};
use pyrograph_core::{TypeInfo, ValueType};

/// One particle: a camera-facing fuzzy N-gon (Perry 1994 §3.2.1), or a root, or a light.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct Particle {
    /// World position.
    pub position: [f32; 3],
    /// Velocity (for roots: the initial direction of the flame).
    pub velocity: [f32; 3],
    /// Half extents of the N-gon along the billboard's x and y.
    pub size: [f32; 2],
    /// Straight RGBA of the centre vertex.
    pub center: [f32; 4],
    /// Straight RGBA of the rim vertices.
    pub edge: [f32; 4],
    /// A free scalar: the age for flame particles, the intensity for lights.
    pub weight: f32,
    /// Which flame (or other group) the particle belongs to.
    pub group: u32,
}

/// A set of particles at one moment.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct Particles {
    /// The particles, in drawing order.
    pub particles: Vec<Particle>,
    /// Triangles per particle N-gon.
    pub sides: u32,
    /// Simulation time, in frames.
    pub time: f32,
    /// The particles of one group, in order, are the successive steps of one trajectory (Perry's
    /// long exposure, §3.2.2): a renderer may draw each group as one continuous swept shape.
    pub trails: bool,
}

impl ValueType for Particles {
    const INFO: &'static TypeInfo = &TypeInfo {
        name: "Particles",
        doc: "A set of particles: flame roots, flame trajectories or lights (Perry 1994 §3.2.1).",
        color: [245, 110, 180],
    };

    fn hash_into(&self, h: &mut Fingerprinter) {
        (self.particles.len(), self.sides, self.time.to_bits(), self.trails).hash(h);
        for q in &self.particles {
            let floats = [q.position.as_slice(), &q.velocity, &q.size, &q.center, &q.edge, &[q.weight]];
            floats.iter().for_each(|f| hash_f32s(h, f));
            q.group.hash(h);
        }
    }

    fn byte_size(&self) -> usize {
        self.particles.len() * std::mem::size_of::<Particle>()
    }

    fn summary(&self) -> String {
        format!("Particles {} ({}-gons)", self.particles.len(), self.sides)
    }
}
