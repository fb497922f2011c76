//! The six-way maps against direct renders: Unity's decode of the maps, lit from a direction,
//! must reproduce `volume.render`'s single scattering lit from that direction.

use std::f32::consts::PI;
use std::sync::Arc;

use glam::{IVec3, Vec3, Vec4};
use pyrograph_render::{Camera, View};

use super::*;
use crate::grid::{Field, FieldData, SimStats, Topology, Transform, VOXELS};
use crate::render::march::Octaves;

/// A dense puff on a thinner column, with a flame at the puff's foot, over 4 × 4 × 4 bricks.
fn smoke() -> Volume {
    let top = Topology::new((0..64).map(|k| IVec3::new(k & 3, (k >> 2) & 3, k >> 4)).collect());
    let (mut density, mut flame) = (vec![0.0; top.voxels()], vec![0.0; top.voxels()]);
    for (b, c) in top.coords().iter().enumerate() {
        for i in 0..VOXELS {
            let p = (*c * 8 + IVec3::new((i & 7) as i32, ((i >> 3) & 7) as i32, (i >> 6) as i32)).as_vec3();
            let puff = (1.0 - (p - Vec3::new(14.0, 18.0, 16.0)).length() / 9.0).clamp(0.0, 1.0);
            let column = (1.0 - Vec3::new(p.x - 18.0, 0.0, p.z - 16.0).length() / 4.0).clamp(0.0, 1.0) * 0.3;
            density[b * VOXELS + i] = 1.5 * puff + column;
            flame[b * VOXELS + i] = if p.y < 8.0 { column } else { 0.0 };
        }
    }
    Volume {
        transform: Transform { voxel_size: 0.05, origin: [0.0; 3] },
        topology: Arc::new(top),
        fields: vec![
            Field { name: "density".into(), data: FieldData::Scalar(density) },
            Field { name: "flame".into(), data: FieldData::Scalar(flame) },
        ],
        time: 0.0,
        stats: SimStats::default(),
    }
}

fn view(size: u32) -> View {
    let centre = Vec3::splat(16.0 * 0.05);
    let camera = Camera::new(centre + Vec3::new(0.6, 0.3, 4.0), centre, Vec3::Y, 24.0, 0.1, 100.0).unwrap();
    View::new(camera, size, size).unwrap()
}

fn look() -> Look {
    Look {
        extinction: 8.0,
        albedo: Vec3::splat(0.9),
        anisotropy: 0.0,
        ambient: Vec3::ZERO,
        exposure: 2.0,
        glow: 0.0,
        kelvin: [1000.0, 2600.0],
        step: 0.5,
        background: Vec4::ZERO,
        seed: 3,
        octaves: Octaves::SINGLE,
    }
}

/// π × the light scattered toward the camera from unit irradiance along world direction `l`.
fn direct(v: &Volume, view: &View, l: Vec3) -> Vec<f32> {
    let light = [Light { kind: LightKind::Directional(l), color: Vec3::ONE }];
    let scene = Scene { lights: &light, groups: &[], surfaces: None, motion: false };
    gather(v, view, &scene, &look(), |g, _, _| [PI * g.scattered[0].x]).into_iter().map(|[x]| x).collect()
}

/// Between axes the engines' blend of six lights stands in for the light itself, and on a dense
/// puff the lit side's edge (the shadow's terminator) falls where no blend of axis-lit images puts
/// it: the mean absolute difference per pixel is within this fraction of the direct render's mean
/// (along an axis the decode is the map itself)...
const LIMIT: f64 = 0.32;
/// ... and the smoke's total light within this fraction.
const LIGHT_LIMIT: f64 = 0.15;

#[test]
fn relit_six_way_maps_reproduce_direct_renders_from_fourteen_directions() {
    let (v, view) = (smoke(), view(48));
    let (pos, neg) = sixway_maps(&v, &view, &look(), 1.0);
    let frame = camera_frame(&view);
    let rgb = |img: &Image, k: usize| Vec3::from_slice(&img.data()[k * 4..k * 4 + 3]);
    let covered: Vec<usize> = (0..48 * 48).filter(|k| pos.data()[k * 4 + 3] > 0.05).collect();
    assert!(covered.len() > 300, "the smoke covers {} pixels", covered.len());
    let mut directions: Vec<(&str, Vec3)> =
        ["+x", "+y", "+z", "-x", "-y", "-z"].into_iter().zip([Vec3::X, Vec3::Y, Vec3::Z, -Vec3::X, -Vec3::Y, -Vec3::Z]).collect();
    for (name, l) in [
        ("upper right front", Vec3::new(1.0, 1.0, -1.0)),
        ("upper left back", Vec3::new(-1.0, 1.0, 1.0)),
        ("lower right back", Vec3::new(1.0, -1.0, 1.0)),
        ("lower left front", Vec3::new(-1.0, -1.0, -1.0)),
        ("key light", Vec3::new(0.6, 0.7, -0.4)),
        ("rim light", Vec3::new(-0.3, 0.4, 0.87)),
        ("low sun", Vec3::new(0.9, 0.2, 0.3)),
        ("overhead", Vec3::new(0.1, 0.95, -0.2)),
    ] {
        directions.push((name, l.normalize()));
    }
    println!("| light (camera frame) | mean direct | mean |decoded − direct| | relative | total light |");
    let mut worst = Vec::new();
    for (name, l) in directions {
        let world = frame[0] * l.x + frame[1] * l.y + frame[2] * l.z;
        let truth = direct(&v, &view, world);
        let (mut err, mut total, mut sum) = (0.0f64, 0.0f64, 0.0f64);
        for &k in &covered {
            let decoded = relight(rgb(&pos, k), rgb(&neg, k), l);
            err += f64::from((decoded - truth[k]).abs());
            total += f64::from(truth[k]);
            sum += f64::from(decoded);
        }
        let (relative, light) = (err / total, sum / total - 1.0);
        let n = covered.len() as f64;
        println!("| {name} | {:.4} | {:.4} | {:.1} % | {:+.1} % |", total / n, err / n, 100.0 * relative, 100.0 * light);
        if light.abs() > LIGHT_LIMIT {
            worst.push(format!("{name}: the decoded smoke's total light is off by {light:.3}"));
        }
        let limit = if l.abs().max_element() > 0.999 { 1e-5 } else { LIMIT };
        if relative > limit {
            worst.push(format!("{name}: decoded off by {relative:.3} of the direct render"));
        }
    }
    assert!(worst.is_empty(), "{worst:?}");
}

#[test]
fn the_maps_follow_unitys_channels() {
    let (v, view) = (smoke(), view(32));
    let (pos, neg) = sixway_maps(&v, &view, &look(), 1.0);
    let px = |img: &Image, x: usize, y: usize, c: usize| img.data()[(y * 32 + x) * 4 + c];
    // The dense puff is lit on the side facing its light: "right" brighter on the image's right
    // half, "top" on its upper half (rows run down the image).
    let half = |img: &Image, c: usize, right: bool, rows: bool| -> f32 {
        (0..32)
            .flat_map(|y| (0..32).map(move |x| (x, y)))
            .filter(|&(x, y)| (if rows { y < 16 } else { x >= 16 }) == right)
            .map(|(x, y)| px(img, x, y, c))
            .sum()
    };
    assert!(half(&pos, 0, true, false) > 1.3 * half(&pos, 0, false, false), "right lights the right side");
    assert!(half(&neg, 0, false, false) > 1.3 * half(&neg, 0, true, false), "left lights the left side");
    assert!(half(&pos, 1, true, true) > 1.3 * half(&pos, 1, false, true), "top lights the upper side");
    // Opacity in the positive map's alpha; the flame's glow in the negative map's alpha.
    assert!(pos.data().chunks(4).any(|p| p[3] > 0.9) && pos.data()[3] == 0.0);
    assert!(neg.data().chunks(4).any(|p| p[3] > 0.05), "the flame shows in the emission mask");
}
