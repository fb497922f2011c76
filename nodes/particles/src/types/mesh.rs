//! Values of fire spread over polygon meshes (Perry 1994 §3.3–3.4): triangle meshes with face
//! adjacency, and the state of a spreading fire at one moment.

use std::hash::Hash;

use pyrograph_core::fingerprint::{Fingerprinter, hash_f32s};
use pyrograph_core::{TypeInfo, ValueType};

/// Marks a boundary edge in [`Mesh::neighbors`].
pub const NO_NEIGHBOR: u32 = u32::MAX;

/// A triangle mesh with face adjacency (Perry §3.3.2).
#[derive(Clone, Debug, PartialEq, Default)]
pub struct Mesh {
    /// Vertex positions.
    pub positions: Vec<[f32; 3]>,
    /// Triangles as vertex indices, counter-clockwise seen from outside.
    pub triangles: Vec<[u32; 3]>,
    /// Unit face normals, one per triangle.
    pub normals: Vec<[f32; 3]>,
    /// For triangle `t`, the triangle across edge `i` (from vertex `i` to vertex `i+1`), or [`NO_NEIGHBOR`].
    pub neighbors: Vec<[u32; 3]>,
    /// For triangle `t` and edge `i`, the rotation (unit quaternion `[x, y, z, w]`, about the shared
    /// edge) taking this face's normal to the neighbour's (Perry §3.3.2); identity on boundary edges.
    pub edge_rotations: Vec<[[f32; 4]; 3]>,
    /// For each triangle, the index of the source polygon it was cut from (OBJ face or primitive quad).
    pub polygons: Vec<u32>,
}

impl ValueType for Mesh {
    const INFO: &'static TypeInfo =
        &TypeInfo { name: "Mesh", doc: "A triangle mesh with face adjacency (Perry 1994 §3.3.2).", color: [150, 200, 150] };

    fn hash_into(&self, h: &mut Fingerprinter) {
        (self.positions.len(), &self.triangles, &self.neighbors, &self.polygons).hash(h);
        self.positions.iter().chain(&self.normals).for_each(|p| hash_f32s(h, p));
        self.edge_rotations.iter().flatten().for_each(|q| hash_f32s(h, q));
    }

    fn byte_size(&self) -> usize {
        (self.positions.len() + self.normals.len() + 2 * self.triangles.len()) * 12
            + self.edge_rotations.len() * 48
            + self.polygons.len() * 4
    }

    fn summary(&self) -> String {
        format!("Mesh {} vertices, {} triangles", self.positions.len(), self.triangles.len())
    }
}

/// A live flame root dropped by the spreading boundary (Perry §3.4).
#[derive(Clone, Debug, PartialEq, Default)]
pub struct FlameRoot {
    /// World position.
    pub position: [f32; 3],
    /// Initial velocity direction (the face normal).
    pub direction: [f32; 3],
    /// Seconds since it was dropped.
    pub age: f32,
    /// Lifetime l_f in seconds.
    pub lifetime: f32,
    /// Stable id (a seed for the flame's noise).
    pub id: u32,
}

/// A char mark where a flame died (Perry §3.4.1).
#[derive(Clone, Debug, PartialEq, Default)]
pub struct CharMark {
    /// World position.
    pub position: [f32; 3],
    /// Face normal there.
    pub normal: [f32; 3],
    /// Seconds since the flame died.
    pub age: f32,
}

/// A spreading fire at one moment (Perry §3.3–3.4).
#[derive(Clone, Debug, PartialEq, Default)]
pub struct SpreadState {
    /// Simulation time in seconds.
    pub time: f32,
    /// Boundary polylines (closed unless a point stopped at a mesh boundary), world positions.
    pub boundaries: Vec<Vec<[f32; 3]>>,
    /// Live flame roots.
    pub roots: Vec<FlameRoot>,
    /// Control points that stopped (mesh boundary or burnt region).
    pub extinguished: Vec<[f32; 3]>,
    /// Char marks.
    pub char_marks: Vec<CharMark>,
    /// Flame roots dropped since ignition (live or dead).
    pub flames_dropped: u64,
}

impl ValueType for SpreadState {
    const INFO: &'static TypeInfo = &TypeInfo {
        name: "SpreadState",
        doc: "A fire spreading over a mesh at one moment (Perry 1994 §3.3–3.4).",
        color: [150, 200, 150],
    };

    fn hash_into(&self, h: &mut Fingerprinter) {
        (self.time.to_bits(), self.boundaries.len(), self.roots.len(), self.extinguished.len(), self.char_marks.len()).hash(h);
        self.flames_dropped.hash(h);
        self.boundaries.iter().flatten().chain(&self.extinguished).for_each(|p| hash_f32s(h, p));
        for r in &self.roots {
            (r.id, r.age.to_bits(), r.lifetime.to_bits()).hash(h);
            hash_f32s(h, &r.position);
            hash_f32s(h, &r.direction);
        }
        for c in &self.char_marks {
            c.age.to_bits().hash(h);
            hash_f32s(h, &c.position);
            hash_f32s(h, &c.normal);
        }
    }

    fn byte_size(&self) -> usize {
        (self.boundaries.iter().map(Vec::len).sum::<usize>() + self.extinguished.len()) * 12
            + self.roots.len() * std::mem::size_of::<FlameRoot>()
            + self.char_marks.len() * std::mem::size_of::<CharMark>()
    }

    fn summary(&self) -> String {
        let points: usize = self.boundaries.iter().map(Vec::len).sum();
        format!(
            "SpreadState t={} {} boundary points, {} flames, {} char marks",
            self.time,
            points,
            self.roots.len(),
            self.char_marks.len()
        )
    }
}
