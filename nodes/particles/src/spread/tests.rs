use std::sync::Arc;

use glam::Vec3;
use pyrograph_core::NodeError;
use pyrograph_core::declare::Declared;
use pyrograph_core::value::Points;

use super::*;
use crate::mesh::{build_mesh, cube, cylinder, plane};
use crate::types::{LargeWind, Mesh, WindField};

/// Frames per second the tests' flame lifetimes are counted in (the node's default).
const FPS: f32 = 24.0;

fn still() -> impl Fn(Vec3) -> Vec3 + Sync {
    |_| Vec3::ZERO
}

fn surface(soup: &crate::mesh::PolygonSoup) -> Arc<Surface> {
    Arc::new(Surface::new(&build_mesh(soup, 0, true).unwrap()).unwrap())
}

fn at(s: &Surface, p: Vec3) -> Ignition {
    let (face, bary, d) = s.nearest(p);
    assert!(d < 1e-5);
    Ignition { face, bary, time: 0.0 }
}

fn run(s: &mut Spread, seconds: f32, dt: f32, wind: &(dyn Fn(Vec3) -> Vec3 + Sync)) {
    let steps = (seconds / dt).round() as usize;
    for _ in 0..steps {
        s.step(dt, wind);
    }
}

#[test]
fn on_a_flat_plane_without_wind_the_boundary_is_a_circle_growing_linearly() {
    let surf = surface(&plane(4.0, 16));
    let p = SpreadParams { d_s: 0.05, double_burn: false, ..SpreadParams::default() };
    let v = p.q_o / p.K.value();
    let mut s = Spread::new(surf.clone(), vec![at(&surf, Vec3::new(0.1, 0.0, -0.07))], p, FPS).unwrap();
    let centre = Vec3::new(0.1, 0.0, -0.07);
    let mut radii = Vec::new();
    for t in [2.0f32, 4.0, 6.0] {
        run(&mut s, 2.0, 0.05, &still());
        let r: Vec<f32> = s.loops()[0].iter().map(|c| (c.position - centre).length()).collect();
        let mean = r.iter().sum::<f32>() / r.len() as f32;
        let dev = r.iter().map(|x| (x - mean).abs()).fold(0.0, f32::max) / mean;
        println!(
            "t = {t}: {} points, mean radius {mean:.4} (v·t = {:.4}), max radial deviation {:.2} %",
            r.len(),
            v * t,
            dev * 100.0
        );
        assert!(dev < 0.05, "t = {t}: radial deviation {dev}");
        assert!((mean - v * t).abs() / (v * t) < 0.05, "t = {t}: radius {mean} vs {}", v * t);
        assert!(s.loops()[0].iter().all(|c| c.alive && c.position.y.abs() < 1e-5));
        radii.push(mean);
    }
    // Linear growth: equal increments.
    let (d1, d2) = (radii[1] - radii[0], radii[2] - radii[1]);
    assert!((d1 - d2).abs() / d1 < 0.03, "increments {d1} and {d2}");
    // Every gap at most d_s (after the insertion pass).
    let ring = &s.loops()[0];
    let max_gap = (0..ring.len()).map(|j| (ring[j].position - ring[(j + 1) % ring.len()].position).length()).fold(0.0, f32::max);
    assert!(max_gap <= 0.05 + 1e-4, "gap {max_gap}");
}

#[test]
fn with_wind_the_concurrent_side_outruns_the_opposed_side_by_the_flux_ratio() {
    let surf = surface(&plane(6.0, 12));
    let p = SpreadParams { double_burn: false, ..SpreadParams::default() };
    let mut s = Spread::new(surf.clone(), vec![at(&surf, Vec3::ZERO)], p.clone(), FPS).unwrap();
    let wind = |_: Vec3| Vec3::new(2.0, 0.3, 0.0); // the vertical part is normal to the plane
    run(&mut s, 5.0, 0.05, &wind);
    let xs: Vec<f32> = s.loops()[0].iter().map(|c| c.position.x).collect();
    let (lo, hi) = xs.iter().fold((f32::MAX, f32::MIN), |(a, b), x| (a.min(*x), b.max(*x)));
    let ratio = hi / -lo;
    let expected = (p.q_o + p.q_c) / p.q_o;
    println!("downwind {hi:.4}, upwind {:.4}: ratio {ratio:.4}, model (q_o + q_c)/q_o = {expected:.4}", -lo);
    assert!((ratio - expected).abs() / expected < 0.03, "ratio {ratio} vs {expected}");
}

#[test]
fn after_crossing_cube_edges_every_control_point_lies_on_the_surface() {
    let surf = surface(&cube(1.0, 3));
    let p = SpreadParams { d_s: 0.04, ..SpreadParams::default() };
    let mut s = Spread::new(surf.clone(), vec![at(&surf, Vec3::new(0.5, 0.1, -0.05))], p, FPS).unwrap();
    let wind = spread_wind(&WindField { large: LargeWind::Constant([0.5, 0.0, 0.2]), ..WindField::default() });
    let mut faces_seen = std::collections::HashSet::new();
    let mut worst = 0.0f32;
    for _ in 0..160 {
        s.step(1.0 / 24.0, &wind);
        for c in s.loops().iter().flatten() {
            let m = c.position.abs().max_element();
            let d = (m - 0.5).abs().max(c.position.abs().max_element() - 0.5);
            worst = worst.max(d);
            let n = surf.normal(c.face);
            faces_seen.insert((n * 2.0).round().to_array().map(|x| x as i32));
            assert!((c.heading.dot(n)).abs() < 1e-4, "heading in the face plane");
        }
    }
    println!("{} points on {} cube sides, worst distance to the surface {worst:e}", s.point_count(), faces_seen.len());
    assert!(worst < 1e-5, "{worst}");
    assert!(faces_seen.len() >= 5, "the fire crossed onto {} sides", faces_seen.len());
}

/// Points on an open tube around +Y ignited at angle 0: a point moving strongly around the tube
/// (|ĥ·θ̂| > 0.5) must stay on its own half; past the far side means it is burning burnt ground.
fn trespassers(s: &Spread) -> usize {
    let tol = 0.15;
    s.loops()
        .iter()
        .flatten()
        .filter(|c| {
            let th = (-c.position.z).atan2(c.position.x).rem_euclid(std::f32::consts::TAU);
            let e_th = Vec3::new(-th.sin(), 0.0, -th.cos());
            let around = c.heading.dot(e_th);
            let pi = std::f32::consts::PI;
            (around > 0.5 && th > pi + tol && th < 2.0 * pi - tol) || (around < -0.5 && th > tol && th < pi - tol)
        })
        .count()
}

#[test]
fn with_double_burn_prevention_no_point_enters_the_burnt_region_of_a_cylinder() {
    let surf = surface(&cylinder(0.5, 0.6, 48, 3));
    let (face, bary, _) = surf.nearest(Vec3::new(0.5, 0.3, -0.02));
    let ig = Ignition { face, bary, time: 0.0 };
    let params = SpreadParams { d_t: 0.0, d_s: 0.03, ..SpreadParams::default() };
    let mut on = Spread::new(surf.clone(), vec![ig], params.clone(), FPS).unwrap();
    let mut off = Spread::new(surf.clone(), vec![ig], SpreadParams { double_burn: false, ..params }, FPS).unwrap();
    // Half the circumference is π·0.5 ≈ 1.57 at 0.225/s ≈ 7 s; run well past the meeting.
    let (mut worst_on, mut worst_off) = (0, 0);
    for _ in 0..(11.0f32 / 0.05) as usize {
        on.step(0.05, &still());
        off.step(0.05, &still());
        worst_on = worst_on.max(trespassers(&on));
        worst_off = worst_off.max(trespassers(&off));
    }
    println!("points in the burnt region: {worst_on} with prevention, {worst_off} without");
    assert_eq!(worst_on, 0);
    assert!(worst_off > 0, "the test has teeth: without prevention the fronts pass through each other");
    assert!(on.loops()[0].iter().all(|c| !c.alive), "with prevention the fire goes out");
}

fn dead_points(s: &Spread) -> usize {
    s.loops().iter().flatten().filter(|c| !c.alive).count()
}

/// Perimeter of the convex hull of the control points seen from above (the XZ plane).
fn hull_perimeter_xz(s: &Spread) -> f32 {
    let mut p: Vec<(f32, f32)> = s.loops().iter().flatten().map(|c| (c.position.x, c.position.z)).collect();
    p.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    p.dedup();
    let turns_left = |o: (f32, f32), a: (f32, f32), b: (f32, f32)| (a.0 - o.0) * (b.1 - o.1) - (a.1 - o.1) * (b.0 - o.0) > 0.0;
    let half = |points: &mut dyn Iterator<Item = (f32, f32)>| {
        let mut h: Vec<(f32, f32)> = Vec::new();
        for q in points {
            while h.len() >= 2 && !turns_left(h[h.len() - 2], h[h.len() - 1], q) {
                h.pop();
            }
            h.push(q);
        }
        h.pop();
        h
    };
    let mut hull = half(&mut p.iter().copied());
    hull.extend(half(&mut p.iter().rev().copied()));
    (0..hull.len())
        .map(|k| {
            let (a, b) = (hull[k], hull[(k + 1) % hull.len()]);
            (a.0 - b.0).hypot(a.1 - b.1)
        })
        .sum()
}

/// Fraction of a grid of points on the sides of the unit cube within `r` of a flame root or
/// char mark: how much of it has burnt.
fn burnt_fraction_of_unit_cube(s: &Spread, r: f32) -> f32 {
    let st = s.state();
    let marks: Vec<Vec3> =
        st.roots.iter().map(|m| m.position).chain(st.char_marks.iter().map(|m| m.position)).map(Vec3::from_array).collect();
    let n = 20;
    let mut burnt = 0;
    for axis in 0..3 {
        for side in [-0.5f32, 0.5] {
            for (i, j) in (0..n).flat_map(|i| (0..n).map(move |j| (i, j))) {
                let mut p = Vec3::ZERO;
                p[axis] = side;
                p[(axis + 1) % 3] = (i as f32 + 0.5) / n as f32 - 0.5;
                p[(axis + 2) % 3] = (j as f32 + 0.5) / n as f32 - 0.5;
                burnt += usize::from(marks.iter().any(|m| (*m - p).length() < r));
            }
        }
    }
    burnt as f32 / (6 * n * n) as f32
}

#[test]
fn in_wind_the_point_count_stays_within_three_per_d_s_of_the_burnt_perimeter() {
    let surf = surface(&plane(4.0, 16));
    let p = SpreadParams { d_s: 0.05, ..SpreadParams::default() };
    let mut s = Spread::new(surf.clone(), vec![at(&surf, Vec3::ZERO)], p.clone(), FPS).unwrap();
    let wind = |_: Vec3| Vec3::new(2.0, 0.3, 0.5);
    let rim = 16.0;
    let mut most = 0;
    for step in 1..=360 {
        s.step(1.0 / 24.0, &wind);
        let (n, dead) = (s.point_count(), dead_points(&s));
        let bound = 3.0 * hull_perimeter_xz(&s) / p.d_s + p.points as f32;
        assert!(n as f32 <= bound, "step {step}: {n} points, more than {bound:.0}");
        // Points only stop on the rim here (one ignition, no fronts meet).
        assert!(dead as f32 <= 3.0 * rim / p.d_s, "step {step}: {dead} stopped points along a rim of {rim}");
        most = most.max(n);
    }
    // After 15 s even the upwind front (0.225/s) has reached the farthest corner (≈ 2.8 away).
    assert!(s.loops().iter().flatten().all(|c| !c.alive), "the fire is out");
    let out = s.point_count();
    run(&mut s, 2.0, 1.0 / 24.0, &wind);
    println!("at most {most} points; {out} when the fire is out, on a rim of {rim} (d_s = {})", p.d_s);
    assert_eq!(s.point_count(), out, "a fire that is out keeps its points");
}

#[test]
fn the_burning_cube_needs_a_few_hundred_points_and_still_burns_all_over() {
    // graphs/burning-cube.ron without its translation.
    let surf = surface(&cube(1.0, 8));
    let p = SpreadParams { d_t: 0.1, d_s: 0.05, ..SpreadParams::default() };
    let mut s = Spread::new(surf.clone(), vec![at(&surf, Vec3::new(0.5, -0.3, -0.15))], p.clone(), FPS).unwrap();
    let wind = spread_wind(&WindField { k_g: 2.0, large: LargeWind::Constant([-0.15, 0.0, 0.35]), ..WindField::default() });
    // Generous: three points per d_s along fronts as long as the cube's twelve edges together.
    let bound = 3.0 * 12.0 / p.d_s + p.points as f32;
    let mut counts = Vec::new();
    for frame in 1..=240 {
        s.step(1.0 / 24.0, &wind);
        assert!(s.point_count() as f32 <= bound, "frame {frame}: {} points, more than {bound}", s.point_count());
        if frame % 48 == 0 {
            counts.push((s.point_count(), dead_points(&s)));
        }
    }
    let burnt = burnt_fraction_of_unit_cube(&s, 0.06);
    println!("(points, stopped) every 2 s: {counts:?}; {:.1} % of the cube burnt", burnt * 100.0);
    assert!(burnt > 0.99, "only {:.1} % of the cube burnt", burnt * 100.0);
    assert!(s.loops().iter().flatten().all(|c| !c.alive), "the fire is out after 10 s");
    let out = s.point_count();
    run(&mut s, 2.0, 1.0 / 24.0, &wind);
    assert_eq!(s.point_count(), out, "a fire that is out keeps its points");
}

#[test]
fn more_flames_drop_as_d_d_shrinks_and_roots_face_outwards() {
    let surf = surface(&cube(1.0, 2));
    let counts: Vec<u64> = [0.4f32, 0.2, 0.1, 0.05]
        .iter()
        .map(|&d_d| {
            // l_f = 100 frames at 1 fps: 100 s.
            let p = SpreadParams { d_d, lifetime: 100, ..SpreadParams::default() };
            let mut s = Spread::new(surf.clone(), vec![at(&surf, Vec3::new(0.0, 0.5, 0.0))], p, 1.0).unwrap();
            run(&mut s, 2.0, 1.0 / 24.0, &still());
            assert!(
                s.state().roots.iter().all(|r| (Vec3::from_array(r.direction) - Vec3::Y).length() < 1e-5 || r.position[1] < 0.5)
            );
            s.flames_dropped()
        })
        .collect();
    println!("flames dropped for d_d = 0.4, 0.2, 0.1, 0.05: {counts:?}");
    assert!(counts.windows(2).all(|w| w[1] > w[0]), "{counts:?}");
}

#[test]
fn dead_flames_leave_char_and_the_state_is_deterministic() {
    let surf = surface(&cube(1.0, 2));
    // l_f = 12 frames at 24 fps: 0.5 s.
    let p = SpreadParams { lifetime: 12, seed: 3, ..SpreadParams::default() };
    let mut a = Spread::new(surf.clone(), vec![at(&surf, Vec3::new(0.0, 0.5, 0.0))], p.clone(), FPS).unwrap();
    let mut b = a.clone();
    run(&mut a, 2.0, 1.0 / 24.0, &still());
    run(&mut b, 2.0, 1.0 / 24.0, &still());
    assert_eq!(a.state(), b.state());
    let st = a.state();
    assert!(!st.char_marks.is_empty() && !st.roots.is_empty());
    assert_eq!(st.flames_dropped as usize, st.roots.len() + st.char_marks.len());
    assert!(st.roots.iter().all(|r| r.age < r.lifetime));
}

#[test]
fn ignitions_parse_snap_and_report_errors_naming_the_port() {
    let surf = surface(&cube(1.0, 1));
    let points = |text: &str| Points::from_param(&pyrograph_core::ParamValue::parse_cli(text)).unwrap();
    let ig = parse_ignitions(&points("[(0.5, 0, 0), (1.5, face(3, (0.2, 0.3, 0.5)))]"), &surf, 0.01).unwrap();
    assert_eq!(ig.len(), 2);
    assert!((surf.point(ig[0].face, ig[0].bary) - Vec3::new(0.5, 0.0, 0.0)).length() < 1e-5);
    assert_eq!((ig[1].face, ig[1].time, ig[1].bary), (3, 1.5, [0.2, 0.3, 0.5]));
    let e = FireSpread::error(parse_ignitions(&points("[(0.5, 0, 0), (3, 0, 0)]"), &surf, 0.05).unwrap_err());
    assert!(
        matches!(&e, NodeError::Port { port, message } if port == "ignite" && message.contains("point 2 at (3, 0, 0) is off the mesh")),
        "{e}"
    );
    let e = parse_ignitions(&points("[face(99)]"), &surf, 0.05).unwrap_err();
    assert!(e.to_string().contains("point 1: face 99 is past the mesh's 12 faces"), "{e}");
    // The centre of a face, when no coordinates are given.
    let centre = parse_ignitions(&Points::face(2), &surf, 0.05).unwrap();
    assert_eq!(centre[0].bary, [1.0 / 3.0; 3]);
    // A delayed ignition starts its own ring when its time comes.
    let mut s = Spread::new(surf, ig, SpreadParams::default(), FPS).unwrap();
    assert_eq!(s.loops().len(), 1);
    run(&mut s, 1.6, 0.1, &still());
    assert_eq!(s.loops().len(), 2);
}

#[test]
fn a_boundary_edge_stops_every_point_on_the_edge() {
    let surf = surface(&plane(1.0, 2));
    let p = SpreadParams { double_burn: false, ..SpreadParams::default() };
    let mut s = Spread::new(surf.clone(), vec![at(&surf, Vec3::new(0.05, 0.0, -0.1))], p, FPS).unwrap();
    // The farthest corner is ≈ 0.78 away; at q_o/K = 0.225 per second that is ≈ 3.5 s.
    run(&mut s, 5.0, 1.0 / 24.0, &still());
    let ring = &s.loops()[0];
    assert!(ring.len() > 16, "points were inserted as the ring grew");
    for c in ring {
        assert!(!c.alive, "point at {} still moving", c.position);
        let off = (c.position.x.abs().max(c.position.z.abs()) - 0.5).abs();
        assert!(off < 1e-4 && c.position.y.abs() < 1e-6, "stopped at {}, {off} from the rim", c.position);
    }
    assert!(s.state().extinguished.len() >= ring.len());
    // A stopped fire stays stopped.
    let before = s.state().boundaries;
    run(&mut s, 0.5, 1.0 / 24.0, &still());
    assert_eq!(s.state().boundaries, before);
}

#[test]
fn curvature_speeds_the_spread_towards_convex_edges_and_slows_it_towards_concave_ones() {
    let outside = surface(&cube(1.0, 1));
    let mut inverted = cube(1.0, 1);
    inverted.polygons.iter_mut().for_each(|p| p.reverse());
    let inside = surface(&inverted);
    let d_t = 0.2;
    // Points on the y = +0.5 face, at distances from its edge x = +0.5.
    for (surf, sign) in [(&outside, 1.0f32), (&inside, -1.0)] {
        for (d, want) in [(0.0f32, 0.5f32), (0.05, 0.375), (0.1, 0.25), (0.3, 0.0)] {
            let p = Vec3::new(0.5 - d, 0.5, 0.03);
            let (face, _, dist) = surf.nearest(p);
            assert!(dist < 1e-6);
            let got = surf.curvature(face, p, d_t);
            assert!((got - (1.0 + sign * want)).abs() < 1e-4, "sign {sign}, d = {d}: factor {got}");
            assert_eq!(surf.curvature(face, p, 0.0), 1.0, "d_t = 0 turns curvature off");
        }
    }
    // A spreading fire reaches a convex edge sooner with the curvature term than without.
    let reach = |d_t: f32| {
        let p = SpreadParams { d_t, double_burn: false, ..SpreadParams::default() };
        let mut s = Spread::new(outside.clone(), vec![at(&outside, Vec3::new(0.2, 0.5, 0.0))], p, FPS).unwrap();
        let mut steps = 0;
        while s.loops()[0].iter().all(|c| c.position.y > 0.5 - 1e-6) {
            s.step(0.01, &still());
            steps += 1;
            assert!(steps < 1000, "never left the top face");
        }
        steps
    };
    let (with, without) = (reach(0.2), reach(0.0));
    println!("steps to the first edge: {with} with curvature, {without} without");
    assert!(with < without, "{with} vs {without}");
}

#[test]
fn a_mesh_without_faces_cannot_burn() {
    let e = Surface::new(&Mesh::default()).unwrap_err();
    assert!(e.contains("no faces"), "{e}");
    let mesh = build_mesh(&cube(1.0, 1), 0, true).unwrap();
    let broken = Mesh { neighbors: Vec::new(), ..mesh };
    let e = Surface::new(&broken).unwrap_err();
    assert!(e.contains("inconsistent"), "{e}");
}

#[test]
fn table_3_1_ranges_are_the_port_ranges() {
    let d = FireSpread::desc();
    let range = |n: &str| d.inputs[d.input_index(n).unwrap()].range;
    assert_eq!(range("K"), Some((0.004, 0.4)));
    assert_eq!(range("d_d"), Some((0.01, 1.0)));
    assert_eq!(range("d_s"), Some((0.01, 0.2)));
    assert_eq!(range("d_t"), Some((0.01, 0.5)));
    assert_eq!(range("lifetime"), Some((1.0, 1000.0)));
    assert_eq!(range("points").map(|r| r.0), Some(8.0));
}

/// The spread states of frames `0..frames` of a cube ignited on its side, with `k` as K and
/// `wind` as the wind field's parameters.
fn spread_clip(k: &str, wind: &str, frames: usize) -> Vec<Arc<crate::types::SpreadState>> {
    use pyrograph_core::{BuildOptions, CookCtx, Evaluator, Graph, GraphDoc, Registry, Value};
    let mut registry = Registry::with_builtins();
    crate::register(&mut registry);
    let doc = GraphDoc::from_ron(&format!(
        r#"(version: 4, nodes: {{
            "cube": (type: "particles.mesh_load", params: {{"source": "cube"}}),
            "wind": (type: "particles.wind_field", params: {{{wind}}}),
            "spread": (type: "particles.fire_spread", params: {{"ignite": [(0.5, 0.1, 0.0)], "frames": {frames}, "K": {k}, "d_s": 0.05}}),
        }}, edges: [("cube.mesh", "spread.mesh"), ("wind.wind", "spread.wind")])"#
    ))
    .unwrap();
    let graph =
        Graph::build(&doc, &registry, std::path::Path::new("."), &BuildOptions::default()).unwrap_or_else(|d| panic!("{d}"));
    let ctx = CookCtx::new();
    let Value::Clip(clip) = Evaluator::new().output(&graph, "spread.spread", &ctx).unwrap() else { panic!("a clip") };
    (0..frames).map(|i| clip.get(i, &ctx).unwrap().downcast::<crate::types::SpreadState>().unwrap()).collect()
}

#[test]
fn an_animated_k_and_wind_reach_the_front_at_the_step_they_change() {
    let wind = r#""large_scale": "constant", "wind": (0.0, 0.0, 0.0)"#;
    let steady = spread_clip("0.4", wind, 30);
    // K drops to a quarter (four times the speed) from frame 12 on.
    let faster = spread_clip("keys([(0, 0.4, constant), (12, 0.1)])", wind, 30);
    // Stepping to frame f samples at f − 1: frames up to 12 are the steady spread's, bit for bit.
    for f in 0..=12 {
        assert!(steady[f] == faster[f], "frame {f}, before K changes");
    }
    assert!(steady[13] != faster[13], "frame 13 follows the new K");
    let burnt = |s: &crate::types::SpreadState| s.flames_dropped;
    println!("flames dropped by frame 29: {} steady, {} with K keyed down", burnt(&steady[29]), burnt(&faster[29]));
    assert!(burnt(&faster[29]) > burnt(&steady[29]) * 3 / 2, "{} vs {}", burnt(&faster[29]), burnt(&steady[29]));
    // A wind keyed to blow from frame 12 changes nothing before it blows.
    let gust = spread_clip("0.4", r#""large_scale": "constant", "wind": (0, 0, keys([(0, 0.0, constant), (12, 3.0)]))"#, 16);
    for f in 0..=12 {
        assert!(steady[f] == gust[f], "frame {f}, before the gust");
    }
    assert!(steady[14] != gust[14], "the gust moves the front");
}
