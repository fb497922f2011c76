//! `volume.render` against a reference renderer: Mitsuba 3's volumetric path tracer (`volpath`,
//! the `scalar_rgb` variant of the `mitsuba` wheel from PyPI, `tests/mitsuba_check.py`) renders
//! the same density grid through the same camera, lit by the same sun (and, in one scene, a point
//! light), with the same extinction, albedo and Henyey–Greenstein anisotropy. Single scattering
//! (Mitsuba's `max_depth` 2) must agree with pyrograph's march; the full path tracer's multiple
//! scattering is reported beside it, for what single scattering misses.
//!
//! CI renders small grids. `PYROGRAPH_MITSUBA_FULL=1` renders the full-size comparison and
//! `PYROGRAPH_MITSUBA_PICTURES=<dir>` writes the side-by-side pictures BENCHMARKS.md shows.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::Arc;

use glam::{IVec3, Vec3, Vec4};
use pyrograph_nodes_volume::grid::{Field, FieldData, SimStats, Topology, Transform, VOXELS, Volume};
use pyrograph_nodes_volume::render::light::{Light, LightKind};
use pyrograph_nodes_volume::render::march::{Look, Octaves, render};
use pyrograph_render::{Camera, View};
use serde_json::{Value as Json, json};

const MARKER: &str = "== mitsuba_check json";
const EXTINCTION: f32 = 8.0;
const ALBEDO: f32 = 0.85;
const ANISOTROPY: f32 = 0.3;
/// Toward the sun: from the upper left, in front.
const SUN: Vec3 = Vec3::new(-0.8, 0.5, 0.35);
const SUN_IRRADIANCE: f32 = 9.0;
/// The multiple-scattering approximation compared with the path tracer's every order: volume.render's
/// octave ports at their defaults, with 4 octaves.
const OCTAVES: Octaves = Octaves { count: 4, ..Octaves::SINGLE };

/// The Python with `mitsuba`: `PYROGRAPH_MITSUBA_PYTHON`, else the venv `.ci/run` fills.
fn mitsuba_python() -> PathBuf {
    match std::env::var_os("PYROGRAPH_MITSUBA_PYTHON") {
        Some(p) => PathBuf::from(p),
        None => Path::new(env!("CARGO_MANIFEST_DIR")).join("../../target/mitsuba-venv/bin/python"),
    }
}

/// A scene: its density (world point in the unit box around the origin → density) and its lights.
struct Scene {
    name: &'static str,
    density: fn(Vec3) -> f32,
    point: Option<(Vec3, f32)>,
}

fn smooth(edge0: f32, edge1: f32, x: f32) -> f32 {
    let t = ((x - edge0) / (edge1 - edge0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// A thin column: a Gaussian across (σ 0.07), fading in and out along its height.
fn plume(p: Vec3, x: f32) -> f32 {
    let r2 = (p.x - x).powi(2) + (p.z * 0.8).powi(2);
    0.35 * (-r2 / (2.0 * 0.07 * 0.07)).exp() * smooth(-0.45, -0.2, p.y) * smooth(0.45, 0.2, p.y)
}

/// A dense ball of radius 0.26 with a soft edge.
fn puff(p: Vec3, at: Vec3) -> f32 {
    4.0 * smooth(0.26, 0.14, (p - at).length())
}

fn scenes() -> [Scene; 3] {
    [
        Scene { name: "thin plume", density: |p| plume(p, 0.0), point: Some((Vec3::new(0.3, -0.15, 0.3), 0.6)) },
        Scene { name: "dense puff", density: |p| puff(p, Vec3::ZERO), point: None },
        // The puff sits between the sun and the plume's lower half.
        Scene { name: "puff in shadow", density: |p| plume(p, 0.18) + puff(p, Vec3::new(-0.2, -0.06, -0.05)), point: None },
    ]
}

/// The scene's density on `n`³ voxels filling the box [−0.5, 0.5]³, the outer layer empty (so
/// both renderers see the density fall to 0 at the box's faces).
fn volume(scene: &Scene, n: i32) -> (Volume, Vec<f32>) {
    let h = 1.0 / n as f64;
    let origin = -0.5 + 0.5 * h;
    let bricks = (n + 7) / 8;
    let mut coords = Vec::new();
    for z in 0..bricks {
        for y in 0..bricks {
            for x in 0..bricks {
                coords.push(IVec3::new(x, y, z));
            }
        }
    }
    let top = Topology::new(coords);
    let at = |v: IVec3| -> f32 {
        if v.min_element() <= 0 || v.max_element() >= n - 1 {
            return 0.0;
        }
        (scene.density)(Vec3::splat(origin as f32) + v.as_vec3() * h as f32)
    };
    let mut d = vec![0.0; top.voxels()];
    for (b, c) in top.coords().iter().enumerate() {
        for (i, slot) in d[b * VOXELS..(b + 1) * VOXELS].iter_mut().enumerate() {
            *slot = at(*c * 8 + IVec3::new((i & 7) as i32, ((i >> 3) & 7) as i32, (i >> 6) as i32));
        }
    }
    let mut dense = Vec::with_capacity((n * n * n) as usize);
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                dense.push(at(IVec3::new(x, y, z)));
            }
        }
    }
    let v = Volume {
        transform: Transform { voxel_size: h, origin: [origin; 3] },
        topology: Arc::new(top),
        fields: vec![Field { name: "density".into(), data: FieldData::Scalar(d) }],
        time: 0.0,
        stats: SimStats::default(),
    };
    (v, dense)
}

fn write_f32(path: &Path, data: &[f32]) {
    let bytes: Vec<u8> = data.iter().flat_map(|x| x.to_le_bytes()).collect();
    std::fs::write(path, bytes).unwrap();
}

/// Renders every scene with pyrograph into `dir` (the density, the image and a JSON description
/// per scene) and returns the descriptions.
fn prepare(dir: &Path, n: i32, (w, h): (u32, u32)) -> Vec<Json> {
    let (eye, fov) = (Vec3::new(0.0, 0.1, 2.6), 28.0);
    let camera = Camera::new(eye, Vec3::ZERO, Vec3::Y, fov, 0.1, 100.0).unwrap();
    let view = View::new(camera, w, h).unwrap();
    let look = Look {
        extinction: EXTINCTION,
        albedo: Vec3::splat(ALBEDO),
        anisotropy: ANISOTROPY,
        ambient: Vec3::ZERO,
        exposure: 0.0,
        glow: 0.0,
        kelvin: [1000.0, 2600.0],
        step: 0.5,
        background: Vec4::ZERO,
        seed: 11,
        octaves: Octaves::SINGLE,
    };
    let mut out = Vec::new();
    for (k, scene) in scenes().iter().enumerate() {
        let (v, dense) = volume(scene, n);
        let mut lights = vec![Light { kind: LightKind::Directional(SUN.normalize()), color: Vec3::splat(SUN_IRRADIANCE) }];
        if let Some((at, intensity)) = scene.point {
            lights.push(Light { kind: LightKind::Point(at), color: Vec3::splat(intensity) });
        }
        let started = std::time::Instant::now();
        let img = render(&v, &view, &lights, &look);
        let seconds = started.elapsed().as_secs_f64();
        // Premultiplied RGB (what the path tracer sees over black) and alpha.
        let premultiplied = |img: &pyrograph_core::Image| -> Vec<f32> {
            img.data().chunks(4).flat_map(|p| [p[0] * p[3], p[1] * p[3], p[2] * p[3], p[3]]).collect()
        };
        write_f32(&dir.join(format!("{k}.density.f32")), &dense);
        write_f32(&dir.join(format!("{k}.pyrograph.f32")), &premultiplied(&img));
        // The multiple-scattering approximation, set against the path tracer's every order.
        let octaves = render(&v, &view, &lights, &Look { octaves: OCTAVES, ..look.clone() });
        write_f32(&dir.join(format!("{k}.octaves.f32")), &premultiplied(&octaves));
        out.push(json!({
            "name": scene.name, "index": k, "n": n, "width": w, "height": h,
            "eye": eye.to_array(), "target": [0.0, 0.0, 0.0], "up": [0.0, 1.0, 0.0], "fov": fov,
            "box": [[-0.5, -0.5, -0.5], [0.5, 0.5, 0.5]],
            "extinction": EXTINCTION, "albedo": ALBEDO, "anisotropy": ANISOTROPY,
            "sun": SUN.normalize().to_array(), "sun_irradiance": SUN_IRRADIANCE,
            "point": scene.point.map(|(at, i)| json!({"at": at.to_array(), "intensity": i})),
            "pyrograph_seconds": seconds,
        }));
    }
    out
}

fn mitsuba(dir: &Path, scenes: &[Json], spp: u32, pictures: Option<&Path>) -> Vec<Json> {
    std::fs::write(dir.join("scenes.json"), serde_json::to_vec_pretty(scenes).unwrap()).unwrap();
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/mitsuba_check.py");
    let python = mitsuba_python();
    let mut cmd = Command::new(&python);
    cmd.arg(&script).arg(dir).arg("--spp").arg(spp.to_string());
    if let Some(p) = pictures {
        cmd.arg("--pictures").arg(p);
    }
    let out = cmd
        .output()
        .unwrap_or_else(|e| panic!("{} runs ({e}); .ci/run installs mitsuba into target/mitsuba-venv", python.display()));
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "mitsuba_check.py failed:\n{stdout}\n{}", String::from_utf8_lossy(&out.stderr));
    let json = stdout.split(MARKER).nth(1).unwrap_or_else(|| panic!("no result from Mitsuba:\n{stdout}"));
    serde_json::from_str(json.trim()).expect("the script prints JSON")
}

#[test]
#[ignore = "needs Mitsuba 3 (PYROGRAPH_MITSUBA_PYTHON; .ci/run installs it into target/mitsuba-venv)"]
fn single_scattering_agrees_with_mitsubas_path_tracer_on_three_smoke_scenes() {
    let full = std::env::var_os("PYROGRAPH_MITSUBA_FULL").is_some();
    let (n, size, spp) = if full { (64, (320, 240), 512) } else { (32, (96, 72), 512) };
    let dir = tempfile::tempdir().unwrap();
    let scenes = prepare(dir.path(), n, size);
    let pictures = std::env::var_os("PYROGRAPH_MITSUBA_PICTURES").map(PathBuf::from);
    let results = mitsuba(dir.path(), &scenes, spp, pictures.as_deref());
    println!(
        "| scene | grid | image | smoke pixels | mean (pyrograph) | MAE (single) | MAE / mean | SSIM (single) | MAE (all orders) | SSIM (all orders) | multiple scattering adds | MAE (octaves, all orders) | SSIM (octaves, all orders) | octaves add |"
    );
    for r in &results {
        let f = |k: &str| r[k].as_f64().unwrap_or(f64::NAN);
        println!(
            "| {} | {n}³ | {}×{} | {} | {:.3} | {:.4} | {:.1} % | {:.3} | {:.4} | {:.3} | {:+.0} % | {:.4} | {:.3} | {:+.0} % |",
            r["name"].as_str().unwrap_or("?"),
            size.0,
            size.1,
            r["mask_pixels"],
            f("mean_pyrograph"),
            f("mae_single"),
            100.0 * f("mae_single") / f("mean_single"),
            f("ssim_single"),
            f("mae_full"),
            f("ssim_full"),
            100.0 * f("multiple_gain"),
            f("mae_octaves"),
            f("ssim_octaves"),
            100.0 * (f("mean_octaves") / f("mean_pyrograph") - 1.0),
        );
    }
    for r in &results {
        let name = r["name"].as_str().unwrap_or("?");
        let f = |k: &str| r[k].as_f64().unwrap_or(f64::NAN);
        // The octaves come closer to every order than single scattering where multiple scattering
        // matters (the dense scenes), and lose little where it does not (the thin plume, where they
        // add more light than the path tracer finds).
        assert!(f("ssim_octaves") >= f("ssim_full"), "{name}: octaves SSIM {} vs single {}", f("ssim_octaves"), f("ssim_full"));
        assert!(f("mae_octaves") <= 1.1 * f("mae_full"), "{name}: octaves MAE {} vs single {}", f("mae_octaves"), f("mae_full"));
        if f("multiple_gain") > 0.5 {
            assert!(
                f("mae_octaves") <= 0.7 * f("mae_full"),
                "{name}: octaves MAE {} vs single {}",
                f("mae_octaves"),
                f("mae_full")
            );
        }
        assert!(r["mask_pixels"].as_u64().unwrap_or(0) > 100, "{name}: too little smoke in view: {r}");
        assert!(r["mae_single"].as_f64().is_some_and(|m| m <= 0.03), "{name}: mean absolute error {}", r["mae_single"]);
        let relative = r["mae_single"].as_f64().unwrap_or(f64::NAN) / r["mean_single"].as_f64().unwrap_or(f64::NAN);
        assert!(relative <= 0.12, "{name}: mean absolute error {relative} of the mean");
        assert!(r["ssim_single"].as_f64().is_some_and(|s| s >= 0.9), "{name}: SSIM {}", r["ssim_single"]);
    }
}
