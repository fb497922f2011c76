//! Animated parameters in the evaluator: per-frame nodes sample at the frame they cook, moving a
//! key re-cooks only the frames it moved (recompute log), chunks equal a full cook, and
//! parameters nothing samples over time are refused when the graph loads.

mod common;

use common::Ramp;
use pyrograph_core::document::ParamValue;
use pyrograph_core::{BuildOptions, Cook, CookCtx, DiagnosticKind, Graph, GraphDoc, NodeError, PortType, Registry, Value};

pyrograph_core::node! {
    /// value × gain + offset
    #[node("test.gain", "Test", PerFrame)]
    pub struct Gain {
        /// input
        value: f64,
        /// gain
        #[range(-100.0, 100.0)]
        gain: f64 = 1.0,
        /// offset
        #[range(-1000.0, 1000.0)]
        offset: f64 = 0.0,
    }
    /// result
    -> value: f64
}

impl Cook for Gain {
    fn cook(self, _: &CookCtx) -> Result<f64, NodeError> {
        Ok(self.value * self.gain + self.offset)
    }
}

fn registry() -> Registry {
    let mut r = Registry::new();
    r.add(Ramp::node());
    r.add(Gain::node());
    r
}

fn doc(gain: &str, offset: &str) -> GraphDoc {
    let text = format!(
        r#"(version: 4, nodes: {{
            "ramp": (type: "test.ramp", params: {{"frames": 60}}),
            "a": (type: "test.gain", params: {{"gain": {gain}}}),
            "b": (type: "test.gain", params: {{"offset": {offset}}}),
        }}, edges: [("ramp.clip", "a.value"), ("a.value", "b.value")])"#
    );
    GraphDoc::from_ron(&text).unwrap()
}

fn build(d: &GraphDoc) -> Result<Graph, pyrograph_core::Diagnostics> {
    Graph::build(d, &registry(), std::path::Path::new("."), &BuildOptions::default())
}

fn values(ev: &mut pyrograph_core::Evaluator, g: &Graph, ctx: &CookCtx, frames: std::ops::Range<usize>) -> Vec<f64> {
    let Value::Clip(c) = ev.output(g, "b.value", ctx).unwrap() else { panic!("b.value is a clip") };
    c.materialize_range(frames, ctx).unwrap().iter().map(|v| if let Value::Float(x) = v { *x } else { f64::NAN }).collect()
}

const GAIN: &str = "keys([(0, 1.0, linear), (20, 1.0, linear), (40, 2.0)])";

#[test]
fn a_per_frame_node_cooks_each_frame_with_its_keys_sampled_there() {
    let g = build(&doc(GAIN, "expr(\"frame * 0.5\")")).unwrap();
    let ctx = CookCtx::new();
    let v = values(&mut pyrograph_core::Evaluator::new(), &g, &ctx, 0..60);
    // Frame 30: gain 1.5 (halfway from 1 at 20 to 2 at 40), offset 15.
    assert_eq!(v[30], 30.0 * 1.5 + 15.0);
    assert_eq!(v[10], 10.0 + 5.0);
    assert_eq!(v[50], 50.0 * 2.0 + 25.0, "held after the last key");
}

#[test]
fn moving_one_key_recooks_only_that_node_downstream_and_the_frames_it_moved() {
    let mut ev = pyrograph_core::Evaluator::new();
    let ctx = CookCtx::new().with_frame_log();
    let g = build(&doc(GAIN, "3.0")).unwrap();
    let before = values(&mut ev, &g, &ctx, 0..60);
    ev.take_log();
    ctx.take_frame_log();

    // The last key moves from 2.0 to 3.0: frames 21..=59 change, frames 0..=20 do not.
    let moved = GAIN.replace("(40, 2.0)", "(40, 3.0)");
    let g = build(&doc(&moved, "3.0")).unwrap();
    let after = values(&mut ev, &g, &ctx, 0..60);
    assert_eq!(ev.take_log(), ["a", "b"], "the ramp is not re-cooked");
    let log = ctx.take_frame_log();
    for node in ["a", "b"] {
        let mut frames: Vec<usize> = log.iter().filter(|(n, _)| n == node).map(|(_, f)| *f).collect();
        frames.sort_unstable();
        assert_eq!(frames, (21..60).collect::<Vec<_>>(), "{node} re-cooks only the frames the key moved");
    }
    assert_eq!(before[..21], after[..21]);
    assert_ne!(before[30], after[30]);

    // A key of b's own channel: a's frames are all served from the cache.
    let g = build(&doc(&moved, "keys([(0, 3.0), (50, 3.0, linear), (59, 4.0)])")).unwrap();
    values(&mut ev, &g, &ctx, 0..60);
    let log = ctx.take_frame_log();
    assert!(log.iter().all(|(n, _)| n == "b"), "{log:?}");
    let mut frames: Vec<usize> = log.iter().map(|(_, f)| *f).collect();
    frames.sort_unstable();
    assert_eq!(frames, (51..60).collect::<Vec<_>>());
}

#[test]
fn chunks_cooked_alone_in_any_order_equal_the_curves_sampled_on_their_own() {
    let gain = "expr(\"1 + 0.5 * sin(time * 4) + noise(frame * 0.1)\")";
    let offset = "keys([(0, 0.0), (33, 7.5, ease), (59, -2.0)])";
    let d = doc(gain, offset);
    let sample = |text: &str, f: usize| {
        let a = pyrograph_core::value::animated_param(&ron::from_str(text).unwrap(), &PortType::Float).unwrap().unwrap();
        let Value::Float(x) = a.sample(f as f64, 24.0).unwrap() else { panic!() };
        x
    };
    // Chunks of 8, last first, each in an evaluator of its own, as farm tasks cook them.
    for start in (0..60).step_by(8).rev() {
        let end = (start + 8).min(60);
        let chunk = values(&mut pyrograph_core::Evaluator::new(), &build(&d).unwrap(), &CookCtx::new(), start..end);
        for (f, got) in (start..end).zip(chunk) {
            let want = f as f64 * sample(gain, f) + sample(offset, f);
            assert_eq!(got.to_bits(), want.to_bits(), "frame {f}");
        }
    }
}

#[test]
fn an_animated_parameter_nothing_samples_is_refused_at_load() {
    let mut d = doc("1.0", "0.0");
    d.set_param("ramp", "frames", ParamValue::parse_cli("keys([(0, 10), (10, 20)])")).unwrap();
    let err = build(&d).err().expect("refused");
    let diag = &err.0[0];
    assert_eq!(diag.kind, DiagnosticKind::Animation);
    assert!(diag.to_string().contains("ramp") && diag.message.contains("'frames' is animated"), "{diag}");
}

#[test]
fn a_sampled_value_outside_the_range_fails_the_frame_naming_it() {
    let g = build(&doc("expr(\"frame * 3\")", "0.0")).unwrap();
    let ctx = CookCtx::new();
    let Value::Clip(c) = pyrograph_core::Evaluator::new().output(&g, "b.value", &ctx).unwrap() else { panic!() };
    assert!(c.get(33, &ctx).is_ok());
    let e = c.get(34, &ctx).unwrap_err().to_string();
    assert!(e.contains("gain") && e.contains("frame 34") && e.contains("102"), "{e}");
}

#[test]
fn keys_out_of_order_and_bad_expressions_are_load_errors_naming_node_and_port() {
    let err = build(&doc("keys([(0, 1.0), (20, 2.0), (10, 3.0)])", "expr(\"sin(\")")).err().unwrap();
    let text: Vec<String> = err.0.iter().map(ToString::to_string).collect();
    assert!(text.iter().any(|t| t.contains("'a'") && t.contains("gain") && t.contains("key 3")), "{text:?}");
    assert!(text.iter().any(|t| t.contains("'b'") && t.contains("offset") && t.contains("column")), "{text:?}");
    let err = build(&doc("keys([(0, 1.0), (20, 200.0)])", "0.0")).err().unwrap();
    assert!(err.0[0].message.contains("key 2") && err.0[0].message.contains("200"), "{}", err.0[0]);
    // Keys in range whose tangents carry the curve out of it between them.
    let err = build(&doc("keys([(0, 90.0, tangent(40)), (10, 95.0)])", "0.0")).err().unwrap();
    assert!(err.0[0].message.contains("overshoot") && err.0[0].message.contains("-100..=100"), "{}", err.0[0]);
}

#[test]
fn documents_with_animation_are_written_as_version_4_and_read_back() {
    let d = doc(GAIN, "expr(\"frame * 0.5\")");
    let text = d.to_ron();
    assert!(text.contains("version: 4,") && text.contains("keys([(0, 1.0, linear)"), "{text}");
    assert_eq!(GraphDoc::from_ron(&text).unwrap(), d);
    assert!(doc("1.0", "0.0").to_ron().contains("version: 1,"));
}
