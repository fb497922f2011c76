use glam::Vec3;
use pyrograph_core::declare::{Anim, Cook, Declared};
use pyrograph_core::{CookCtx, NodeError, Value};

use super::*;

fn calm() -> ClothParams {
    ClothParams { buoyancy: Anim::constant(0.0), wind: Anim::constant([0.0; 3]), ..ClothParams::default() }
}

#[test]
fn one_spring_oscillates_at_its_analytic_frequency() {
    let (k, m, amp) = (40.0f32, 0.1f32, 0.05f32);
    let topo = Topology::single_spring(1.0, k, 0.0);
    let mut f = FlameState::at_rest(&topo, 0.0, 1.0, 0);
    f.pos[0][1] += amp;
    let h = 1e-4f32;
    let mut crossings = Vec::new();
    let mut prev = f.pos[0][1] - 1.0;
    for s in 1..200_000 {
        f.advance(&topo, m, 0.0, h, 1, 0.0, |_| Vec3::ZERO);
        let x = f.pos[0][1] - 1.0;
        if prev > 0.0 && x <= 0.0 {
            // Linear interpolation of the downward zero crossing.
            crossings.push((s as f64 - 1.0 + prev as f64 / (prev - x) as f64) * h as f64);
        }
        prev = x;
    }
    assert!(crossings.len() > 10, "{crossings:?}");
    let measured = (crossings[crossings.len() - 1] - crossings[0]) / (crossings.len() - 1) as f64;
    let analytic = std::f64::consts::TAU * (m as f64 / k as f64).sqrt();
    assert!((measured / analytic - 1.0).abs() < 0.01, "period {measured} vs analytic {analytic}");
}

#[test]
fn a_two_by_two_stencil_grid_bobs_at_its_analytic_frequency() {
    // Both top masses hang on one vertical spring each; moved up together, the horizontal
    // spring between them stays at rest, so each bobs at ω = √(k/m).
    let p = ClothParams {
        grid_width: 2,
        grid_height: 2,
        shear: false,
        bend: false,
        stiffness: 40.0,
        mass: 0.1,
        damping: 0.0,
        ..calm()
    };
    let topo = Topology::grid(&p);
    assert!(topo.stencil.is_some(), "the grid runs the stencil kernel");
    let mut f = FlameState::at_rest(&topo, 0.0, 1.0, 0);
    let rest_y = f.pos[1][2];
    f.pos[1][2] += 0.05;
    f.pos[1][3] += 0.05;
    let h = 1e-4f32;
    let (mut crossings, mut prev) = (Vec::new(), 0.05f32);
    for s in 1..100_000 {
        f.advance(&topo, p.mass, 0.0, h, 1, 0.0, |_| Vec3::ZERO);
        let y = f.pos[1][2] - rest_y;
        if prev > 0.0 && y <= 0.0 {
            crossings.push((s as f64 - 1.0 + prev as f64 / (prev - y) as f64) * h as f64);
        }
        prev = y;
    }
    assert!(crossings.len() > 10, "{crossings:?}");
    let measured = (crossings[crossings.len() - 1] - crossings[0]) / (crossings.len() - 1) as f64;
    let analytic = std::f64::consts::TAU * (p.mass as f64 / p.stiffness as f64).sqrt();
    assert!((measured / analytic - 1.0).abs() < 0.01, "period {measured} vs analytic {analytic}");
    assert_eq!(f.pos[1][2].to_bits(), f.pos[1][3].to_bits(), "the two top masses move together");
}

#[test]
fn the_stencil_kernel_matches_the_spring_list() {
    for (shear, bend) in [(false, false), (true, false), (true, true)] {
        let p = ClothParams { grid_width: 7, grid_height: 9, shear, bend, wind_jitter: 0.0, ..ClothParams::default() };
        let topo = Topology::grid(&p);
        let st = topo.stencil.as_ref().unwrap();
        let counted: usize = st.families.iter().map(|f| f.rest.len() - f.cut.len()).sum();
        assert_eq!(counted, topo.springs(), "shear {shear} bend {bend}: the families hold every spring");
        let (mut a, mut b) = (FlameState::at_rest(&topo, 0.0, 1.0, 0), FlameState::at_rest(&topo, 0.0, 1.0, 0));
        let ext = |t: f64| Vec3::new(0.05 * (3.0 * t).sin() as f32, *p.buoyancy.value(), 0.02);
        let h = 1.0 / 600.0;
        for k in 0..60 {
            a.advance(&topo, p.mass, p.drag, h, 10, k as f64 / 60.0, ext);
            b.advance_springs(&topo, p.mass, p.drag, h, 10, k as f64 / 60.0, ext);
        }
        let mut worst = 0.0f32;
        for axis in 0..3 {
            for i in 0..topo.masses() {
                worst = worst.max((a.pos[axis][i] - b.pos[axis][i]).abs());
            }
        }
        let moved = (a.pos[0][topo.masses() - 1] - topo.rest[0][topo.masses() - 1]).abs();
        assert!(moved > 0.01, "the cloth moved: {moved}");
        assert!(worst < 1e-4, "shear {shear} bend {bend}: stencil and spring list differ by {worst}");
    }
}

#[test]
fn a_diverging_step_is_reported_not_returned_as_nan() {
    // Past the stability limit (bypassing the check) the stepper reports the flame.
    let p = ClothParams::default();
    let mut sim = Simulation::new(&p, &grid_roots(2, 1.5)).unwrap();
    sim.params.dt = 0.05;
    let err = (0..50).find_map(|_| sim.step_frame().err());
    assert!(matches!(err, Some(ClothError { ref param, .. }) if param == "dt"), "{err:?}");
}

#[test]
fn without_wind_and_buoyancy_the_grid_stays_at_rest() {
    let mut sim = Simulation::new(&calm(), &grid_roots(4, 1.5)).unwrap();
    let start = sim.snapshot();
    for _ in 0..48 {
        sim.step_frame().unwrap();
    }
    assert_eq!(sim.snapshot().positions, start.positions);
}

#[test]
fn the_pinned_row_never_moves_and_the_cloth_rises_and_sways() {
    let p = ClothParams { wind_jitter: 0.0, ..ClothParams::default() };
    let mut sim = Simulation::new(&p, &grid_roots(3, 1.5)).unwrap();
    let rest = sim.snapshot();
    let w = p.grid_width;
    let n = p.grid_width * p.grid_height;
    let mut moved = 0.0f32;
    for _ in 0..150 {
        sim.step_frame().unwrap();
        let s = sim.snapshot();
        for f in 0..3 {
            assert_eq!(s.positions[f * n..f * n + w], rest.positions[f * n..f * n + w], "flame {f}");
            let top = s.positions[f * n + n - 1];
            moved = moved.max((top[0] - rest.positions[f * n + n - 1][0]).abs());
        }
    }
    assert!(moved > 0.05, "the wind impulses move the tips: {moved}");
}

#[test]
fn with_damping_energy_never_grows_after_the_impulse() {
    let p = ClothParams { wind_jitter: 0.0, damping: 0.05, drag: 0.01, ..ClothParams::default() };
    let topo = Topology::grid(&p);
    let mut f = FlameState::at_rest(&topo, 0.0, 1.0, 0);
    let up = Vec3::Y * *p.buoyancy.value();
    let h = 1.0 / 600.0;
    // The impulse is on for the first second (phase 0), then off for five.
    let wind = Vec3::from_array(*p.wind.value());
    let ext = |t: f64| if wind_active(t, 0.0, p.wind_on, p.wind_off) { up + wind } else { up };
    f.advance(&topo, p.mass, p.drag, h, 600, 0.0, ext);
    let mut e = f.energy(&topo, p.mass, up);
    for k in 0..240 {
        f.advance(&topo, p.mass, p.drag, h, 10, 1.0 + k as f64 / 60.0, ext);
        let next = f.energy(&topo, p.mass, up);
        assert!(next <= e + 1e-6 * e.abs().max(1e-3), "step {k}: energy grew from {e} to {next}");
        e = next;
    }
}

#[test]
fn the_same_seed_gives_the_same_frames_and_random_access_matches_stepping() {
    let p = ClothParams { seed: 7, ..ClothParams::default() };
    let roots = grid_roots(5, 1.5);
    let ctx = CookCtx::default();
    let a = ClothSource::new(Simulation::new(&p, &roots).unwrap(), 60);
    let b = ClothSource::new(Simulation::new(&p, &roots).unwrap(), 60);
    let forward: Vec<_> = (0..60).map(|k| a.state(k, &ctx).unwrap()).collect();
    for k in [59, 3, 30, 0, 31] {
        assert_eq!(*b.state(k, &ctx).unwrap(), *forward[k], "frame {k}");
    }
    assert_eq!(a.frames_stepped(), 59, "sequential access steps one frame per frame");
    let other = ClothSource::new(Simulation::new(&ClothParams { seed: 8, ..p }, &roots).unwrap(), 60);
    assert_ne!(other.state(40, &ctx).unwrap().positions, forward[40].positions);
}

#[test]
fn bad_inputs_are_errors_naming_the_port() {
    let port = |p: ClothParams| match Simulation::new(&p, &[Vec3::ZERO]) {
        Err(ClothError { param, .. }) => param,
        other => panic!("expected a port error, got {other:?}"),
    };
    assert_eq!(port(ClothParams { grid_width: 1, ..ClothParams::default() }), "grid_width");
    assert_eq!(port(ClothParams { grid_height: 1, ..ClothParams::default() }), "grid_height");
    assert_eq!(port(ClothParams { mass: -1.0, ..ClothParams::default() }), "mass");
    assert_eq!(port(ClothParams { dt: 0.05, ..ClothParams::default() }), "dt");
    assert_eq!(port(ClothParams { stiffness: f32::NAN, ..ClothParams::default() }), "stiffness");
    // Just under the limit is accepted and stays finite.
    let p = ClothParams::default();
    let limit = Topology::grid(&p).stable_step(p.mass, p.drag);
    let mut sim = Simulation::new(&ClothParams { dt: limit * 0.95, ..p.clone() }, &[Vec3::ZERO]).unwrap();
    for _ in 0..100 {
        sim.step_frame().unwrap();
    }
    assert!(sim.snapshot().positions.iter().all(|q| q.iter().all(|x| x.is_finite())));
}

#[test]
fn the_node_refuses_a_small_grid_and_a_negative_mass() {
    let desc = MassSpringFlame::desc();
    let values: Vec<Value> = desc.inputs.iter().map(|p| p.default.clone().unwrap_or(Value::Int(0))).collect();
    let cook = |values: &[Value]| pyrograph_core::testing::read::<MassSpringFlame>(values)?.cook(&CookCtx::default());
    let port_of = |values: &[Value]| match cook(values) {
        Err(NodeError::Port { port, .. }) => port,
        other => panic!("expected a port error, got {:?}", other.err()),
    };
    let mut v = values.clone();
    v[desc.input_index("grid_width").unwrap()] = Value::Int(1);
    assert_eq!(port_of(&v), "grid_width");
    let mut v = values.clone();
    v[desc.input_index("mass").unwrap()] = Value::Float(-0.5);
    assert_eq!(port_of(&v), "mass");
    let mut v = values;
    v[desc.input_index("dt").unwrap()] = Value::Float(1.0);
    assert_eq!(port_of(&v), "dt");
}

/// An animated parameter from its file form, as a port would hold it.
fn animated<T: pyrograph_core::declare::Port + Clone>(text: &str, shape: pyrograph_core::anim::Shape) -> Anim<T> {
    use pyrograph_core::declare::Port;
    let a = pyrograph_core::anim::from_param(&pyrograph_core::ParamValue::parse_cli(text), shape).unwrap().unwrap();
    Anim::<T>::from_value(&Value::Anim(std::sync::Arc::new(a))).unwrap()
}

#[test]
fn a_keyed_buoyancy_and_wind_act_from_the_sub_step_of_their_key() {
    use pyrograph_core::anim::Shape;
    let p = ClothParams { wind_jitter: 0.0, wind_off: 0.0, ..ClothParams::default() };
    let keyed = ClothParams {
        buoyancy: animated("keys([(0, 0.05, constant), (10, 0.5)])", Shape::Float),
        wind: animated("(keys([(0, 0.03, constant), (10, 0.3)]), 0, 0.01)", Shape::Vec3),
        ..p.clone()
    };
    let roots = grid_roots(2, 1.5);
    let (mut a, mut b) = (Simulation::new(&p, &roots).unwrap(), Simulation::new(&keyed, &roots).unwrap());
    for frame in 1..=14 {
        a.step_frame().unwrap();
        b.step_frame().unwrap();
        let same = a.snapshot().positions == b.snapshot().positions;
        // Frames up to 10 are stepped before the keys' change: the same masses, bit for bit.
        assert_eq!(same, frame <= 10, "frame {frame}");
    }
    let top = |s: &Simulation| s.snapshot().positions.iter().map(|q| q[1]).fold(f32::MIN, f32::max);
    assert!(top(&b) > top(&a), "a stronger buoyancy lifts the cloth: {} vs {}", top(&b), top(&a));
}
