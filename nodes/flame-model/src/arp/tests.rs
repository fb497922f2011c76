use proptest::prelude::*;

use pyrograph_core::Value;
use pyrograph_core::testing::cook;

use super::rng::Rng;
use super::*;

/// `frames` rows of x_t = A_1 x_{t−1} + A_2 x_{t−2} + d + B w_t (+ observation noise of standard
/// deviation `obs`), after a burn-in, with `offset` added to column i (different units per column).
pub(crate) fn ar2_series(a1: &[f64], a2: &[f64], d: &[f64], b: &[f64], frames: usize, obs: f64, seed: u64) -> ParamSeries {
    let dim = d.len();
    let mut rng = Rng::new(seed);
    let (mut x1, mut x2) = (vec![0.0; dim], vec![0.0; dim]);
    let mut data = Vec::with_capacity(frames * dim);
    let mut w = vec![0.0; dim];
    for t in 0..frames + 500 {
        rng.fill_normal(&mut w);
        let x: Vec<f64> = (0..dim)
            .map(|i| {
                d[i] + (0..dim).map(|j| a1[i * dim + j] * x1[j] + a2[i * dim + j] * x2[j] + b[i * dim + j] * w[j]).sum::<f64>()
            })
            .collect();
        if t >= 500 {
            for (i, v) in x.iter().enumerate() {
                data.push(v * (1.0 + i as f64) + 10.0 * i as f64 + obs * rng.normal());
            }
        }
        x2 = std::mem::replace(&mut x1, x);
    }
    let names = (0..dim).map(|i| format!("p{i}")).collect();
    ParamSeries { names, frames, data, fps: 25.0 }
}

/// A damped oscillating, coupled AR(2) (companion spectral radius 0.927), like a flickering flame.
const A1: [f64; 9] = [1.3, 0.2, 0.0, -0.1, 1.1, 0.15, 0.05, 0.0, 1.2];
const A2: [f64; 9] = [-0.7, 0.0, 0.05, 0.0, -0.5, 0.0, 0.1, 0.05, -0.6];
const D: [f64; 3] = [0.5, -0.3, 0.2];
const B: [f64; 9] = [0.3, 0.0, 0.0, 0.1, 0.25, 0.0, -0.05, 0.05, 0.2];

fn known() -> ParamSeries {
    ar2_series(&A1, &A2, &D, &B, 4000, 0.0, 11)
}

/// A_k in the units of the series (column i was scaled by 1 + i): S A_k S⁻¹ of the model's A_k.
fn a_original(m: &ArModel, k: usize) -> Vec<f64> {
    let dim = m.dim();
    (0..dim * dim)
        .map(|e| {
            let (i, j) = (e / dim, e % dim);
            m.a[k * dim * dim + e] * m.scale[i] / m.scale[j] * (1.0 + j as f64) / (1.0 + i as f64)
        })
        .collect()
}

fn rel_err(got: &[f64], want: &[f64]) -> f64 {
    let num: f64 = got.iter().zip(want).map(|(g, w)| (g - w).powi(2)).sum();
    let den: f64 = want.iter().map(|w| w * w).sum();
    (num / den).sqrt()
}

#[test]
fn em_recovers_a_known_ar2_and_its_likelihood_never_decreases() {
    let series = known();
    let m = learn(&series, &LearnOptions::default(), &CookCtx::new()).unwrap();
    let (e1, e2) = (rel_err(&a_original(&m, 0), &A1), rel_err(&a_original(&m, 1), &A2));
    println!(
        "EM (Kalman) on AR(2), D = 3, T = 4000: {} iterations, |ΔA_1|/|A_1| = {e1:.4}, |ΔA_2|/|A_2| = {e2:.4}",
        m.log_likelihood.len()
    );
    println!("log-likelihood: first {:.3}, last {:.3}", m.log_likelihood[0], m.log_likelihood.last().unwrap());
    assert!(e1 < 0.05 && e2 < 0.05, "A_1 {:?}\nA_2 {:?}", a_original(&m, 0), a_original(&m, 1));
    for w in m.log_likelihood.windows(2) {
        assert!(w[1] >= w[0] - 1e-9 * w[0].abs(), "likelihood decreased: {} → {}", w[0], w[1]);
    }
    assert!(m.log_likelihood.len() >= 4 && m.log_likelihood.last().unwrap() > &m.log_likelihood[0]);
    assert!(spectral_radius(&m).unwrap() < 1.0);
    assert_eq!(m.initial, series.data[(series.frames - 2) * 3..]);
}

#[test]
fn condensation_e_step_learns_the_same_process_roughly() {
    let series = ar2_series(&A1, &A2, &D, &B, 800, 0.0, 5);
    let opts =
        LearnOptions { e_step: EStep::Condensation { particles: 100, seed: 3 }, max_iterations: 40, ..LearnOptions::default() };
    let m = learn(&series, &opts, &CookCtx::new()).unwrap();
    let (e1, e2) = (rel_err(&a_original(&m, 0), &A1), rel_err(&a_original(&m, 1), &A2));
    println!("EM (condensation, N_c = 100) on AR(2), T = 800: {} iterations, errors {e1:.3} {e2:.3}", m.log_likelihood.len());
    assert!(e1 < 0.25 && e2 < 0.5, "{e1} {e2}");
}

#[test]
fn samples_of_a_learned_model_stay_bounded_over_100000_steps() {
    let m = learn(&known(), &LearnOptions::default(), &CookCtx::new()).unwrap();
    let mut s = ArSampler::new(&m, 1).unwrap();
    let mut worst: f64 = 0.0;
    let mut sum_sq = [0.0; 3];
    for _ in 0..100_000 {
        let x = s.step_scaled();
        for i in 0..3 {
            worst = worst.max(x[i].abs());
            sum_sq[i] += x[i] * x[i] / 1e5;
        }
    }
    println!("100000 steps: max |x| = {worst:.2} (unit-variance units), E[x²] = {sum_sq:?}");
    assert!(worst < 10.0, "{worst}");
    assert!(sum_sq.iter().all(|v| (0.5..2.0).contains(v)), "{sum_sq:?}");
}

#[test]
fn the_same_seed_gives_the_same_sequence() {
    let m = learn(&ar2_series(&A1, &A2, &D, &B, 300, 0.0, 2), &LearnOptions::default(), &CookCtx::new()).unwrap();
    let c = Controls::default();
    let a = sample(&m, 500, 0, 9, &c).unwrap();
    assert_eq!(a, sample(&m, 500, 0, 9, &c).unwrap());
    assert_ne!(a.data, sample(&m, 500, 0, 10, &c).unwrap().data);
    assert_eq!((a.frames, a.names.clone()), (500, m.names.clone()));
}

fn diagonal_model(coef: &[f64]) -> ArModel {
    let dim = coef.len();
    let mut a = vec![0.0; dim * dim];
    let mut b = vec![0.0; dim * dim];
    for (i, c) in coef.iter().enumerate() {
        a[i * dim + i] = *c;
        b[i * dim + i] = 1.0;
    }
    ArModel {
        names: (0..dim).map(|i| format!("p{i}")).collect(),
        order: 1,
        a,
        d: vec![0.0; dim],
        b,
        observation_noise: vec![0.0; dim],
        offset: vec![0.0; dim],
        scale: vec![1.0; dim],
        initial: vec![0.0; dim],
        log_likelihood: Vec::new(),
        fps: 25.0,
    }
}

#[test]
fn an_unstable_model_is_an_error_not_a_diverging_sampler() {
    let m = diagonal_model(&[0.5, 1.01]);
    assert!((spectral_radius(&m).unwrap() - 1.01).abs() < 1e-12);
    let e = sample(&m, 10, 0, 0, &Controls::default()).map_err(ArpSample::sample_error).unwrap_err();
    assert!(matches!(&e, NodeError::Port { port, message } if port == "model" && message.contains("unstable")), "{e}");
    // An explosive series learns an unstable process: learn says so.
    let mut data = Vec::new();
    let mut rng = Rng::new(4);
    let (mut x, mut y) = (1.0, 0.5);
    for _ in 0..200 {
        x = 1.04 * x + 0.1 * rng.normal();
        y = 0.5 * y + rng.normal();
        data.extend([x, y]);
    }
    let s = ParamSeries::new(vec!["grow".into(), "noise".into()], 200, data, 25.0).unwrap();
    let e = learn(&s, &LearnOptions::default(), &CookCtx::new()).unwrap_err();
    assert!(e.to_string().contains("unstable"), "{e}");
}

#[test]
fn bad_series_are_clear_errors_naming_the_port_and_parameter() {
    let s = ar2_series(&A1, &A2, &D, &B, 8, 0.0, 1);
    let e = learn(&s, &LearnOptions::default(), &CookCtx::new()).map_err(ArpLearn::learn_error).unwrap_err();
    assert!(matches!(&e, NodeError::Port { port, message } if port == "params" && message.contains("too few frames")), "{e}");
    assert_eq!(min_frames(3, 2), 9);

    let mut s = ar2_series(&A1, &A2, &D, &B, 100, 0.0, 1);
    for t in 0..100 {
        s.data[t * 3 + 1] = 4.25;
    }
    let e = learn(&s, &LearnOptions::default(), &CookCtx::new()).map_err(ArpLearn::learn_error).unwrap_err();
    assert!(
        matches!(&e, NodeError::Port { port, message } if port == "params" && message.contains("'p1'") && message.contains("does not vary")),
        "{e}"
    );

    let mut s = ar2_series(&A1, &A2, &D, &B, 100, 0.0, 1);
    s.data[37 * 3 + 2] = f64::NAN;
    let e = learn(&s, &LearnOptions::default(), &CookCtx::new()).map_err(ArpLearn::learn_error).unwrap_err();
    assert!(matches!(&e, NodeError::Port { message, .. } if message.contains("'p2'") && message.contains("frame 37")), "{e}");

    let s = ar2_series(&A1, &A2, &D, &B, 100, 0.0, 1);
    let e = learn(&s, &LearnOptions { order: 0, ..LearnOptions::default() }, &CookCtx::new())
        .map_err(ArpLearn::learn_error)
        .unwrap_err();
    assert!(matches!(&e, NodeError::Port { port, .. } if port == "order"), "{e}");
}

#[test]
fn controls_bend_the_path_and_scale_height_and_width() {
    let mut m = diagonal_model(&[0.5, 0.5, 0.5, 0.5, 0.5]);
    m.names = ["path_0", "path_1", "path_2", "width_0", "height"].iter().map(|s| s.to_string()).collect();
    m.offset = vec![0.0, 0.0, 0.0, 2.0, 10.0];
    m.b = vec![0.0; 25];
    m.initial = vec![0.0, 0.0, 0.0, 2.0, 10.0];
    let plain = sample(&m, 5, 0, 1, &Controls::default()).unwrap();
    assert!(plain.data.chunks(5).all(|r| r == [0.0, 0.0, 0.0, 2.0, 10.0]), "{:?}", plain.data);
    let c = Controls {
        bend: Ramp::linear(0.0, 4.0),
        height: Ramp::constant(2.0),
        width: Ramp::linear(1.0, 3.0),
        ..Controls::default()
    };
    let out = sample(&m, 5, 0, 1, &c).unwrap();
    let last = out.row(4).unwrap();
    assert_eq!(last, [0.0, 1.0, 4.0, 6.0, 20.0]);
    assert_eq!(out.row(0).unwrap(), [0.0, 0.0, 0.0, 2.0, 20.0]);
    let c =
        Controls { scale: Ramp::constant(0.5), bend: Ramp::constant(2.0), bend_shape: BendShape::Uniform, ..Controls::default() };
    assert_eq!(sample(&m, 1, 0, 1, &c).unwrap().data, [1.0, 1.0, 1.0, 1.0, 5.0]);
}

#[test]
fn a_keyed_bend_follows_its_keys_frame_by_frame() {
    use pyrograph_core::declare::{Anim, Port};
    let mut m = diagonal_model(&[0.5, 0.5, 0.5, 0.5, 0.5]);
    m.names = ["path_0", "path_1", "path_2", "width_0", "height"].iter().map(|s| s.to_string()).collect();
    m.b = vec![0.0; 25];
    let keys = pyrograph_core::ParamValue::parse_cli("keys([(0, 0.0, constant), (3, 4.0, constant)])");
    let animated = pyrograph_core::anim::from_param(&keys, pyrograph_core::anim::Shape::Float).unwrap().unwrap();
    let bend = Anim::<f64>::from_value(&Value::Anim(Arc::new(animated))).unwrap();
    let keyed = Controls {
        bend: Ramp { keyed: Some((bend.clone(), 24.0)), ..Ramp::constant(0.0) },
        bend_shape: BendShape::Uniform,
        ..Controls::default()
    };
    let (plain, out) = (sample(&m, 6, 0, 1, &Controls::default()).unwrap(), sample(&m, 6, 0, 1, &keyed).unwrap());
    for f in 0..6 {
        let (a, b) = (plain.row(f).unwrap(), out.row(f).unwrap());
        let want = if f < 3 { 0.0 } else { 4.0 };
        for c in 0..3 {
            assert_eq!(b[c] - a[c], want, "frame {f}, path_{c}");
        }
        assert_eq!(a[3..], b[3..], "frame {f}: width and height are not bent");
    }
    // Keys and the linear ramp both move the control: asking for both is an error naming it.
    let ports = ControlPorts { bend, ramp: true, ..ControlPorts::default() };
    let e = ports.controls(24.0).unwrap_err().to_string();
    assert!(e.contains("'bend'") && e.contains("ramp is on"), "{e}");
}

#[test]
fn the_nodes_learn_and_sample_through_their_ports() {
    let series = Arc::new(ar2_series(&A1, &A2, &D, &B, 400, 0.01, 8));
    let out = cook::<ArpLearn>(&[("params", Value::custom(series.clone()))]).unwrap();
    let (Some(model), Some(ll), Value::Float(rho)) = (out[0].downcast::<ArModel>(), out[1].downcast::<ParamSeries>(), &out[2])
    else {
        panic!("outputs {out:?}")
    };
    assert_eq!((ll.frames, ll.data.as_slice()), (model.log_likelihood.len(), model.log_likelihood.as_slice()));
    assert!(*rho < 1.0);
    let out = cook::<ArpSample>(&[
        ("model", Value::custom(model.clone())),
        ("frames", Value::Int(50)),
        ("ramp", Value::Bool(true)),
        ("height_end", Value::Float(2.0)),
    ])
    .unwrap();
    let Some(p) = out[0].downcast::<ParamSeries>() else { panic!("{out:?}") };
    assert_eq!((p.frames, p.dim()), (50, 3));
    let e = cook::<ArpSample>(&[("model", Value::custom(model.clone())), ("bend", Value::Float(f64::NAN))]).unwrap_err();
    assert!(matches!(&e, NodeError::Port { port, .. } if port == "bend"), "{e}");
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(32))]

    #[test]
    fn spectral_radius_of_a_diagonal_process_is_its_largest_coefficient(coef in prop::collection::vec(-0.99f64..0.99, 1..6)) {
        let m = diagonal_model(&coef);
        let want = coef.iter().fold(0.0f64, |a, c| a.max(c.abs()));
        prop_assert!((spectral_radius(&m).unwrap() - want).abs() < 1e-9);
    }

    #[test]
    fn ramps_hit_their_ends(start in -10.0f64..10.0, end in -10.0f64..10.0, frames in 2usize..500) {
        let r = Ramp::linear(start, end);
        prop_assert_eq!(r.at(0, frames).unwrap(), start);
        prop_assert!((r.at(frames - 1, frames).unwrap() - end).abs() < 1e-12);
    }
}
