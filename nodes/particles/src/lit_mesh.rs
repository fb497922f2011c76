//! A mesh drawn opaque and lit by a key light and the point lights of the flames (Perry 1994
//! §3.2.4): the burning object of `particles.render_fire` and the logs of `particles.render_flames`.

use glam::Vec3;
use pyrograph_render::{Blend, DrawList, Particle, Particles, Vertex, View};
use rayon::prelude::*;

use crate::types::Mesh;

/// Flame lights as columns (position, and colour times intensity), so the sum over them in
/// [`shade`] vectorizes.
struct LightColumns {
    x: Vec<f32>,
    y: Vec<f32>,
    z: Vec<f32>,
    r: Vec<f32>,
    g: Vec<f32>,
    b: Vec<f32>,
}

impl LightColumns {
    fn new(lights: &Particles) -> LightColumns {
        let col = |f: fn(&Particle) -> f32| lights.particles.iter().map(f).collect();
        LightColumns {
            x: col(|q| q.position[0]),
            y: col(|q| q.position[1]),
            z: col(|q| q.position[2]),
            r: col(|q| q.center[0] * q.weight),
            g: col(|q| q.center[1] * q.weight),
            b: col(|q| q.center[2] * q.weight),
        }
    }
}

/// Light arriving at `p` with normal `n`: key light plus Σ I·rgb·cosθ / (1 + d²) over `lights`
/// (cosθ taken as 1 for a light exactly at `p`).
fn shade(p: Vec3, n: Vec3, lights: &LightColumns, look: &MeshShading) -> Vec3 {
    // Eight partial sums over fixed-size chunks, so the loop runs eight lights at a time
    // (floats do not reassociate on their own).
    const LANES: usize = 8;
    let mut sums = [[0.0f32; LANES]; 3];
    let mut add = |k: usize, [x, y, z, r, g, b]: [f32; 6]| {
        let (dx, dy, dz) = (x - p.x, y - p.y, z - p.z);
        let d2 = dx * dx + dy * dy + dz * dz;
        let cos = if d2 > 0.0 { ((n.x * dx + n.y * dy + n.z * dz) / d2.sqrt()).max(0.0) } else { 1.0 };
        let f = cos / (1.0 + d2);
        sums[0][k] += r * f;
        sums[1][k] += g * f;
        sums[2][k] += b * f;
    };
    let c = [&lights.x, &lights.y, &lights.z, &lights.r, &lights.g, &lights.b];
    let full = lights.x.len() / LANES * LANES;
    for start in (0..full).step_by(LANES) {
        for k in 0..LANES {
            add(k, c.map(|col| col[start + k]));
        }
    }
    for i in full..lights.x.len() {
        add(i - full, c.map(|col| col[i]));
    }
    let [r, g, b] = sums.map(|lanes| lanes.iter().sum::<f32>());
    Vec3::splat(look.ambient + look.sun * n.dot(look.sun_direction).max(0.0)) + Vec3::new(r, g, b)
}

/// A mesh corner's shading key: its position's and its face normal's bits (flat-shaded faces
/// that share a vertex light it differently; triangles of one face share the value, also when
/// the mesh repeats the vertex per triangle).
type CornerKey = ([u32; 3], [u32; 3]);

/// How [`draw_mesh`] lights a mesh: albedo × (ambient + key light + flame lights).
#[derive(Clone, Copy, Debug)]
pub struct MeshShading {
    /// Albedo.
    pub albedo: Vec3,
    /// Ambient light.
    pub ambient: f32,
    /// Unit direction towards the key light.
    pub sun_direction: Vec3,
    /// Key light strength.
    pub sun: f32,
}

/// `mesh` as opaque Gouraud triangles lit by `look` and the point `lights` (§3.2.4).
pub fn draw_mesh(view: &View, mesh: &Mesh, lights: &Particles, look: &MeshShading) -> Vec<DrawList> {
    let albedo = look.albedo;
    let key =
        |t: usize, i: u32| -> CornerKey { (mesh.positions[i as usize].map(f32::to_bits), mesh.normals[t].map(f32::to_bits)) };
    // Shading sums over every flame light, so it is done once per distinct (vertex, normal)
    // rather than once per triangle corner (a grid mesh shares each vertex among six).
    let mut keys: Vec<CornerKey> =
        mesh.triangles.iter().enumerate().flat_map(|(t, tri)| tri.iter().map(move |&i| key(t, i))).collect();
    keys.par_sort_unstable();
    keys.dedup();
    let lights = LightColumns::new(lights);
    let colors: Vec<[f32; 4]> = keys
        .par_iter()
        .map(|&(p, n)| {
            let p = Vec3::from_array(p.map(f32::from_bits));
            let c = albedo * shade(p, Vec3::from_array(n.map(f32::from_bits)), &lights, look);
            [c.x, c.y, c.z, 1.0]
        })
        .collect();
    let color_of = |k: CornerKey| keys.binary_search(&k).map_or([0.0, 0.0, 0.0, 1.0], |j| colors[j]);
    let chunk = (mesh.triangles.len() / (rayon::current_num_threads() * 4)).max(256);
    mesh.triangles
        .par_chunks(chunk)
        .enumerate()
        .map(|(ci, tris)| {
            let mut list = DrawList::new(view);
            for (k, tri) in tris.iter().enumerate() {
                let t = ci * chunk + k;
                let v = tri.map(|i| Vertex::new(Vec3::from_array(mesh.positions[i as usize]), color_of(key(t, i))));
                list.triangle(v, Blend::Opaque);
            }
            list
        })
        .collect()
}

/// The mesh as a holdout: opaque triangles of transparent black, which hide what is behind them
/// (depth-tested) without adding colour: the emission pass's stand-in for the burning object.
pub fn holdout_mesh(view: &View, mesh: &Mesh) -> DrawList {
    let mut list = DrawList::new(view);
    for tri in &mesh.triangles {
        list.triangle(tri.map(|i| Vertex::new(Vec3::from_array(mesh.positions[i as usize]), [0.0; 4])), Blend::Opaque);
    }
    list
}
