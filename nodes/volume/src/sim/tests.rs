//! Whole-simulation tests: a plume rises and spreads, the projection meets its tolerance, a keyed
//! wind leans the plume only after its key, runs are deterministic, and budgets are refused.

use std::sync::Arc;

use pyrograph_core::CookCtx;
use pyrograph_core::declare::Anim;

use super::cache::{Simulation, VolumeFrames};
use super::collide::Solids;
use super::forces::Turbulence;
use super::params::SimParams;
use super::step::{Setup, brick_bounds};
use crate::grid::Volume;
use crate::source::{Emitter, Geometry, Rates, VolumeSource};

fn sphere_source(centre: [f32; 3], radius: f32) -> Arc<VolumeSource> {
    let rates = Rates {
        fuel: Anim::constant(6.0),
        smoke: Anim::constant(1.0),
        temperature: Anim::constant(1.0),
        velocity: Anim::constant([0.0, 0.5, 0.0]),
        radius: Anim::constant(radius),
        inherit: 0.0,
    };
    Arc::new(VolumeSource {
        emitters: vec![Emitter { label: "sphere".into(), geometry: Geometry::Sphere(Anim::constant(centre)), rates }],
    })
}

pub(crate) fn small_params() -> SimParams {
    SimParams { voxel_size: 0.1, turbulence: Anim::constant(0.0), ..SimParams::default() }
}

pub(crate) fn frames(p: SimParams, wind: Option<pyrograph_nodes_particles::types::WindField>, n: usize) -> VolumeFrames {
    limited(p, wind, n, pyrograph_core::limits::DEFAULT_MAX_VOXELS)
}

fn limited(p: SimParams, wind: Option<pyrograph_nodes_particles::types::WindField>, n: usize, max_voxels: u64) -> VolumeFrames {
    let setup = Setup {
        solids: Solids::default(),
        turbulence: Turbulence::new(p.seed, p.turbulence_scale, p.turbulence_speed),
        bounds: brick_bounds(p.bounds_min, p.bounds_max, p.voxel_size),
        cutoff: p.cutoff,
        tolerance: p.tolerance,
        max_iterations: p.max_iterations,
        max_voxels,
    };
    let h = p.voxel_size;
    let sim = Simulation { params: p, fps: 24.0, sources: vec![sphere_source([0.0, 0.0, 0.0], 0.25)], wind, setup };
    VolumeFrames::new(sim, n, h)
}

fn width(v: &Volume) -> f32 {
    // The density-weighted spread around the centroid across x and z.
    let c = v.centroid("density").unwrap();
    let d = v.scalar("density").unwrap();
    let (mut sum, mut w) = (0.0f64, 0.0f64);
    for (b, coord) in v.topology.coords().iter().enumerate() {
        for i in 0..crate::grid::VOXELS {
            let x = d[b * crate::grid::VOXELS + i];
            if x > 0.0 {
                let p = v.transform.to_world((*coord * 8).as_vec3() + super::advect::local(i));
                sum += f64::from(x) * f64::from((p.x - c.x).powi(2) + (p.z - c.z).powi(2));
                w += f64::from(x);
            }
        }
    }
    (sum / w).sqrt() as f32
}

#[test]
fn a_plume_rises_and_spreads_and_every_projection_meets_its_tolerance() {
    let p = small_params();
    let tolerance = p.tolerance;
    let sim = frames(p, None, 24);
    let ctx = CookCtx::new();
    let mut last: Option<(f32, f32)> = None;
    for f in (0..24).step_by(3) {
        let v = sim.volume(f, &ctx).unwrap();
        let c = v.centroid("density").unwrap();
        let w = width(&v);
        println!(
            "frame {f}: centroid y {:.3}, width {w:.3}, {} voxels, {} sub-steps, {} CG iterations, divergence {:.2e}",
            c.y,
            v.topology.voxels(),
            v.stats.substeps,
            v.stats.pressure_iterations,
            v.stats.max_divergence
        );
        assert!(v.stats.max_divergence <= tolerance, "divergence {} above {tolerance}", v.stats.max_divergence);
        if let Some((y, w0)) = last {
            assert!(c.y > y, "the plume rises: {} after {y}", c.y);
            assert!(w > w0 * 0.98, "the plume spreads: {w} after {w0}");
        }
        last = Some((c.y, w));
    }
}

#[test]
fn a_simulation_is_deterministic_and_frames_pulled_out_of_order_agree() {
    let ctx = CookCtx::new();
    let a = frames(small_params(), None, 10);
    let b = frames(small_params(), None, 10);
    let a9 = a.volume(9, &ctx).unwrap();
    let b5 = b.volume(5, &ctx).unwrap();
    let b9 = b.volume(9, &ctx).unwrap();
    assert!(a9 == b9, "the same frame from a straight run and after an earlier pull");
    assert!(b5 == a.volume(5, &ctx).unwrap(), "an earlier frame after a later one");
}

#[test]
fn a_keyed_wind_leans_the_plume_after_its_key_and_not_before() {
    use pyrograph_core::declare::Port;
    use pyrograph_nodes_particles::types::{LargeWind, WindAnimation, WindField};
    let keyed = pyrograph_core::ParamValue::parse_cli("(keys([(0, 0.0, constant), (8, 3.0, constant)]), 0.0, 0.0)");
    let animated = pyrograph_core::anim::from_param(&keyed, pyrograph_core::anim::Shape::Vec3).unwrap().unwrap();
    let wind_anim = Anim::<[f32; 3]>::from_value(&pyrograph_core::Value::Anim(Arc::new(animated))).unwrap();
    let wind = WindField {
        large: LargeWind::Constant([0.0; 3]),
        animation: Some(Arc::new(WindAnimation { wind: Some(wind_anim), ..WindAnimation::default() })),
        ..WindField::default()
    };
    let p = SimParams { wind_drag: Anim::constant(2.0), ..small_params() };
    // Still air with the same drag: the keyed wind's value before its key.
    let still = WindField { large: LargeWind::Constant([0.0; 3]), ..WindField::default() };
    let (calm, windy) = (frames(p.clone(), Some(still), 16), frames(p, Some(wind), 16));
    let ctx = CookCtx::new();
    for f in [3, 6] {
        assert!(calm.volume(f, &ctx).unwrap() == windy.volume(f, &ctx).unwrap(), "frame {f}, before the key");
    }
    let (c, w) = (
        calm.volume(15, &ctx).unwrap().centroid("density").unwrap(),
        windy.volume(15, &ctx).unwrap().centroid("density").unwrap(),
    );
    println!("centroid at frame 15: calm {c}, windy {w}");
    assert!(w.x > c.x + 0.05, "the wind blows toward +x after frame 8: {w} vs {c}");
}

#[test]
fn a_region_over_the_voxel_budget_is_refused_naming_the_limit() {
    let p = SimParams { voxel_size: 0.01, ..small_params() };
    // A sphere of radius 0.25 at voxel size 0.01 needs hundreds of bricks: far over 10,000 voxels.
    let sim = limited(p, None, 4, 10_000);
    let e = sim.volume(0, &CookCtx::new()).unwrap_err().to_string();
    assert!(e.contains("over the limit of 10000 active voxels") && e.contains("--max-voxels"), "{e}");
}
