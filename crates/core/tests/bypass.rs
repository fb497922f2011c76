//! Bypassed nodes: outputs pass the first input of their type through, over clips too; turning
//! bypass on or off re-cooks the node and its downstream only; a node with nothing to pass is
//! refused by name; an include cannot be bypassed.

mod common;

use common::Ramp;
use pyrograph_core::{
    BuildOptions, Cook, CookCtx, DiagnosticKind, Evaluator, Graph, GraphDoc, NodeDoc, NodeError, ParamValue, Registry, Value,
};

pyrograph_core::node! {
    /// Rounds a float to a whole number (no input of its output's type).
    #[node("test.round", "Test", PerFrame)]
    pub struct Round {
        /// rounded
        #[range(-1e9, 1e9)]
        a: f64 = 0.0,
    }
    /// round(a)
    -> value: i64
}

impl Cook for Round {
    fn cook(self, _: &CookCtx) -> Result<i64, NodeError> {
        Ok(self.a.round() as i64)
    }
}

fn registry() -> Registry {
    let mut r = Registry::with_builtins();
    r.declare::<Round>();
    r.declare::<Ramp>();
    r
}

fn build(doc: &GraphDoc) -> Result<Graph, pyrograph_core::Diagnostics> {
    Graph::build(doc, &registry(), std::path::Path::new("."), &BuildOptions::default())
}

fn float(v: &Value) -> f64 {
    match v {
        Value::Float(x) => *x,
        other => panic!("expected Float, got {other:?}"),
    }
}

/// x (1) → add (+2) → mul (×10).
fn chain() -> GraphDoc {
    let mut doc = GraphDoc::new();
    doc.add_node("x", NodeDoc::new("value.float").param("value", ParamValue::Float(1.0)));
    doc.add_node("add", NodeDoc::new("math.add").param("b", ParamValue::Float(2.0)));
    doc.add_node("mul", NodeDoc::new("math.multiply").param("b", ParamValue::Float(10.0)));
    doc.connect("x.value", "add.a").connect("add.value", "mul.a");
    doc
}

#[test]
fn a_bypassed_node_passes_its_first_input_of_the_type_and_toggling_recooks_downstream_only() {
    let mut doc = chain();
    let mut ev = Evaluator::new();
    let ctx = CookCtx::new();
    assert_eq!(float(&ev.output(&build(&doc).unwrap(), "mul.value", &ctx).unwrap()), 30.0);
    ev.take_log();

    doc.node_mut("add").unwrap().bypass = true;
    let g = build(&doc).unwrap();
    assert_eq!(float(&ev.output(&g, "mul.value", &ctx).unwrap()), 10.0, "add passes a (1) through");
    assert_eq!(ev.take_log(), ["add", "mul"], "x is not cooked again");

    doc.node_mut("add").unwrap().bypass = false;
    assert_eq!(float(&ev.output(&build(&doc).unwrap(), "mul.value", &ctx).unwrap()), 30.0);
    let log = ev.take_log();
    assert!(!log.contains(&"x".to_string()), "{log:?}");
}

#[test]
fn bypass_passes_clips_frame_by_frame() {
    let mut doc = GraphDoc::new();
    doc.add_node("ramp", NodeDoc::new("test.ramp").param("frames", ParamValue::Int(5)));
    doc.add_node("add", NodeDoc::new("math.add").param("b", ParamValue::Float(100.0)));
    doc.connect("ramp.clip", "add.a");
    doc.node_mut("add").unwrap().bypass = true;
    let g = build(&doc).unwrap();
    let ctx = CookCtx::new();
    let Value::Clip(clip) = Evaluator::new().output(&g, "add.value", &ctx).unwrap() else { panic!("a clip") };
    let frames: Vec<f64> = (0..clip.len()).map(|i| float(&clip.get(i, &ctx).unwrap())).collect();
    assert_eq!(frames, [0.0, 1.0, 2.0, 3.0, 4.0]);
}

#[test]
fn a_node_with_nothing_to_pass_is_refused_by_name_and_port() {
    let mut doc = GraphDoc::new();
    doc.add_node("r", NodeDoc::new("test.round").param("a", ParamValue::Float(2.4)));
    assert!(build(&doc).is_ok());
    doc.node_mut("r").unwrap().bypass = true;
    let Err(err) = build(&doc) else { panic!("a node with nothing to pass was bypassed") };
    let d = &err.0[0];
    assert_eq!(d.kind, DiagnosticKind::Bypass);
    let text = err.to_string();
    assert!(text.contains("'r'") || text.contains("r:") || text.contains("node r"), "names the node: {text}");
    assert!(d.message.contains("output 'value'") && d.message.contains("a (Float)"), "{}", d.message);
}

#[test]
fn an_include_cannot_be_bypassed() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("inner.ron"), chain().to_ron()).unwrap();
    let mut doc = GraphDoc::new();
    let mut inc = NodeDoc::new("graph.include").param("path", ParamValue::String("inner.ron".into()));
    inc.bypass = true;
    doc.add_node("sub", inc);
    let Err(err) = Graph::build(&doc, &registry(), dir.path(), &BuildOptions::default()) else {
        panic!("an include was bypassed")
    };
    assert_eq!(err.0[0].kind, DiagnosticKind::Bypass, "{err}");
    assert!(err.0[0].message.contains("included graph"), "{err}");
}
