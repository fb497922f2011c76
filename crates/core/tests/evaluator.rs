//! Recompute-log tests of the evaluator: what re-cooks after an edit, backdating, per-node errors,
//! lifting over clips, cancellation, and sub-graph includes.

use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};

mod common;

use common::Ramp;
use pyrograph_core::{
    BuildOptions, CancelToken, ClipOf, Cook, CookCtx, Graph, GraphDoc, InputPath, NodeDoc, NodeError, ParamValue, PortType,
    Progress, Registry, Value, port,
};

pyrograph_core::node! {
    /// Fails when `fail` is set.
    #[node("test.fail", "Test", PerFrame)]
    pub struct Fail {
        /// passed through
        #[range(-1e9, 1e9)]
        a: f64 = 0.0,
        /// whether to fail
        fail: bool = false,
        /// whether to panic, as a node with a bug would
        panic: bool = false,
    }
    /// a
    -> value: f64
}

impl Cook for Fail {
    fn cook(self, _: &CookCtx) -> Result<f64, NodeError> {
        if self.fail {
            return Err(NodeError::port(port!(Fail, fail), "asked to fail"));
        }
        assert!(!self.panic, "asked to panic");
        Ok(self.a)
    }
}

pyrograph_core::node! {
    /// Sums a float clip, pulling frames in parallel.
    #[node("test.sum", "Test", WholeClip)]
    pub struct Sum {
        /// input
        clip: ClipOf<f64>,
    }
    /// sum
    -> value: f64
}

impl Cook for Sum {
    fn cook(self, ctx: &CookCtx) -> Result<f64, NodeError> {
        let frames = self.clip.materialize(ctx)?;
        let value = frames.iter().map(|v| if let Value::Float(f) = v { *f } else { 0.0 }).sum();
        Ok(value)
    }
}

pyrograph_core::node! {
    /// The size in bytes of the file it reads.
    #[node("test.file_size", "Test", PerFrame)]
    pub struct FileSize {
        /// file to read
        path: InputPath,
    }
    /// its size
    -> value: f64
}

impl Cook for FileSize {
    fn cook(self, _: &CookCtx) -> Result<f64, NodeError> {
        let bytes = std::fs::read(&*self.path).map_err(|e| NodeError::port(port!(FileSize, path), e.to_string()))?;
        Ok(bytes.len() as f64)
    }
}

pyrograph_core::node! {
    /// Sleeps 5 ms, then passes `a` through.
    #[node("test.slow", "Test", PerFrame)]
    pub struct Slow {
        /// passed through
        #[range(-1e9, 1e9)]
        a: f64 = 0.0,
    }
    /// a
    -> value: f64
}

impl Cook for Slow {
    fn cook(self, _: &CookCtx) -> Result<f64, NodeError> {
        std::thread::sleep(std::time::Duration::from_millis(5));
        Ok(self.a)
    }
}

fn registry() -> Registry {
    let mut r = Registry::with_builtins();
    r.declare::<Fail>();
    r.declare::<Ramp>();
    r.declare::<Sum>();
    r.declare::<FileSize>();
    r.declare::<Slow>();
    r
}

fn f(v: f64) -> ParamValue {
    ParamValue::Float(v)
}

fn build(doc: &GraphDoc) -> Graph {
    Graph::build(doc, &registry(), std::path::Path::new("."), &BuildOptions::default()).unwrap_or_else(|d| panic!("{d}"))
}

fn float(v: &Value) -> f64 {
    match v {
        Value::Float(x) => *x,
        other => panic!("expected Float, got {other:?}"),
    }
}

/// x → add → mul, and an independent y → add2.
fn two_branches() -> GraphDoc {
    let mut doc = GraphDoc::new();
    doc.add_node("x", NodeDoc::new("value.float").param("value", f(1.0)));
    doc.add_node("add", NodeDoc::new("math.add").param("b", f(2.0)));
    doc.add_node("mul", NodeDoc::new("math.multiply").param("b", f(10.0)));
    doc.add_node("y", NodeDoc::new("value.float").param("value", f(5.0)));
    doc.add_node("add2", NodeDoc::new("math.add").param("b", f(1.0)));
    doc.connect("x.value", "add.a").connect("add.value", "mul.a").connect("y.value", "add2.a");
    doc
}

#[test]
fn cold_cook_cooks_the_cone_once() {
    let g = build(&two_branches());
    let mut ev = pyrograph_core::Evaluator::new();
    let out = ev.output(&g, "mul.value", &CookCtx::new()).unwrap();
    assert_eq!(float(&out), 30.0);
    let mut log = ev.take_log();
    log.sort();
    assert_eq!(log, ["add", "mul", "x"], "only the upstream cone of 'mul' cooks");
}

#[test]
fn rewriting_a_file_a_node_reads_recooks_the_reader_and_its_downstream() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("data.bin");
    std::fs::write(&file, [0u8; 3]).unwrap();
    let mut doc = GraphDoc::new();
    doc.add_node("read", NodeDoc::new("test.file_size").param("path", ParamValue::String(file.display().to_string())));
    doc.add_node("add", NodeDoc::new("math.add").param("b", f(1.0)));
    doc.connect("read.value", "add.a");
    let g = build(&doc);
    let mut ev = pyrograph_core::Evaluator::new();
    assert_eq!(float(&ev.output(&g, "add.value", &CookCtx::new()).unwrap()), 4.0);
    ev.take_log();

    assert_eq!(float(&ev.output(&g, "add.value", &CookCtx::new()).unwrap()), 4.0);
    assert!(ev.take_log().is_empty(), "an untouched file is served from the cache");

    std::fs::write(&file, [0u8; 5]).unwrap();
    assert_eq!(float(&ev.output(&g, "add.value", &CookCtx::new()).unwrap()), 6.0, "not the stale size");
    assert_eq!(ev.take_log(), ["read", "add"]);
}

#[test]
fn warm_cook_serves_everything_from_the_cache() {
    let g = build(&two_branches());
    let mut ev = pyrograph_core::Evaluator::new();
    ev.cook(&g, &["mul", "add2"], &CookCtx::new()).unwrap();
    ev.take_log();
    let res = ev.cook(&g, &["mul", "add2"], &CookCtx::new()).unwrap();
    assert!(res.is_ok());
    assert!(ev.take_log().is_empty());
}

#[test]
fn one_parameter_change_recooks_that_node_and_its_downstream_only() {
    let mut doc = two_branches();
    let mut ev = pyrograph_core::Evaluator::new();
    ev.cook(&build(&doc), &["mul", "add2"], &CookCtx::new()).unwrap();
    ev.take_log();

    doc.set_param("add", "b", f(3.0)).unwrap();
    let g = build(&doc);
    let res = ev.cook(&g, &["mul", "add2"], &CookCtx::new()).unwrap();
    assert_eq!(ev.take_log(), ["add", "mul"]);
    assert_eq!(float(&res.output(&g, "mul", "value").unwrap()), 40.0);
}

#[test]
fn an_unchanged_output_stops_propagation() {
    let mut doc = two_branches();
    doc.set_param("x", "value", f(1.0)).unwrap();
    doc.set_param("add", "b", f(2.0)).unwrap();
    let mut ev = pyrograph_core::Evaluator::new();
    ev.cook(&build(&doc), &["mul"], &CookCtx::new()).unwrap();
    ev.take_log();

    // 2 + 1 == 1 + 2: 'x' and 'add' re-cook, 'mul' sees the same input and stays cached.
    doc.set_param("x", "value", f(2.0)).unwrap();
    doc.set_param("add", "b", f(1.0)).unwrap();
    ev.cook(&build(&doc), &["mul"], &CookCtx::new()).unwrap();
    assert_eq!(ev.take_log(), ["x", "add"]);
}

#[test]
fn a_failing_node_marks_its_downstream_and_other_branches_still_cook() {
    let mut doc = two_branches();
    doc.add_node("bad", NodeDoc::new("test.fail").param("fail", ParamValue::Bool(true)));
    doc.add_node("after", NodeDoc::new("math.add"));
    doc.connect("add.value", "bad.a").connect("bad.value", "after.a");
    let g = build(&doc);
    let mut ev = pyrograph_core::Evaluator::new();
    let res = ev.cook(&g, &["after", "add2"], &CookCtx::new()).unwrap();
    assert_eq!(float(&res.output(&g, "add2", "value").unwrap()), 6.0);
    let bad = res.node("bad").unwrap().as_ref().unwrap_err().to_string();
    assert_eq!(bad, "node 'bad' (test.fail): port 'fail': asked to fail");
    let after = res.node("after").unwrap().as_ref().unwrap_err();
    assert_eq!(after, &NodeError::Upstream("bad".into()));
    assert_eq!(res.root_errors().len(), 1);
}

#[test]
fn a_panicking_node_is_an_error_of_that_node_and_other_branches_still_cook() {
    let mut doc = two_branches();
    doc.add_node("bad", NodeDoc::new("test.fail").param("panic", ParamValue::Bool(true)));
    doc.add_node("after", NodeDoc::new("math.add"));
    doc.connect("add.value", "bad.a").connect("bad.value", "after.a");
    let g = build(&doc);
    let res = pyrograph_core::Evaluator::new().cook(&g, &["after", "add2"], &CookCtx::new()).unwrap();
    assert_eq!(float(&res.output(&g, "add2", "value").unwrap()), 6.0);
    let bad = res.node("bad").unwrap().as_ref().unwrap_err().to_string();
    assert!(
        bad.starts_with("node 'bad' (test.fail): internal error, a bug in pyrograph") && bad.ends_with("asked to panic"),
        "{bad}"
    );
    assert_eq!(res.node("after").unwrap().as_ref().unwrap_err(), &NodeError::Upstream("bad".into()));
}

#[test]
fn asking_for_a_downstream_output_reports_the_failing_nodes_own_error() {
    let mut doc = two_branches();
    doc.add_node("bad", NodeDoc::new("test.fail").param("fail", ParamValue::Bool(true)));
    doc.add_node("after", NodeDoc::new("math.add"));
    doc.add_node("last", NodeDoc::new("math.add"));
    doc.connect("add.value", "bad.a").connect("bad.value", "after.a").connect("after.value", "last.a");
    let g = build(&doc);
    let mut ev = pyrograph_core::Evaluator::new();
    // Two nodes below the failure: the echo is followed up to 'bad' and its port.
    let err = ev.output(&g, "last.value", &CookCtx::new()).unwrap_err();
    assert_eq!(err.to_string(), "node 'bad' (test.fail): port 'fail': asked to fail");
}

#[test]
fn a_clip_into_a_per_frame_input_lifts_the_node() {
    let mut doc = GraphDoc::new();
    doc.add_node("ramp", NodeDoc::new("test.ramp").param("frames", ParamValue::Int(4)));
    doc.add_node("add", NodeDoc::new("math.add").param("b", f(0.5)));
    doc.add_node("sum", NodeDoc::new("test.sum"));
    doc.connect("ramp.clip", "add.a").connect("add.value", "sum.clip");
    let g = build(&doc);
    let add = g.node(g.index("add").unwrap());
    assert!(add.lifted);
    assert_eq!(add.out_types, vec![PortType::clip_of(PortType::Float)]);
    let mut ev = pyrograph_core::Evaluator::new();
    let sum = ev.output(&g, "sum.value", &CookCtx::new()).unwrap();
    assert_eq!(float(&sum), 0.5 + 1.5 + 2.5 + 3.5);
}

#[test]
fn a_cancelled_cook_stops_and_a_second_cook_completes() {
    let mut doc = GraphDoc::new();
    doc.add_node("ramp", NodeDoc::new("test.ramp").param("frames", ParamValue::Int(400)));
    doc.add_node("slow", NodeDoc::new("test.slow"));
    doc.add_node("sum", NodeDoc::new("test.sum"));
    doc.connect("ramp.clip", "slow.a").connect("slow.value", "sum.clip");
    let g = build(&doc);

    let token = CancelToken::new();
    let frames_seen = Arc::new(AtomicUsize::new(0));
    let (t, seen) = (token.clone(), frames_seen.clone());
    let progress = Arc::new(move |p: &Progress| {
        if let Progress::Frame { .. } = p
            && seen.fetch_add(1, Ordering::SeqCst) == 10
        {
            t.cancel();
        }
    });
    let ctx = CookCtx::new().with_cancel(token.clone()).with_progress(progress);
    let mut ev = pyrograph_core::Evaluator::new();
    let started = std::time::Instant::now();
    let res = ev.cook(&g, &["sum"], &ctx).unwrap();
    let err = res.node("sum").unwrap().as_ref().unwrap_err();
    assert!(err.is_cancelled(), "got {err}");
    assert!(frames_seen.load(Ordering::SeqCst) < 400, "cancel stopped the frame loop early");
    assert!(started.elapsed() < std::time::Duration::from_secs(2));

    token.reset();
    let sum = ev.output(&g, "sum.value", &CookCtx::new().with_cancel(token)).unwrap();
    assert_eq!(float(&sum), (0..400).sum::<i32>() as f64);
}

fn write(dir: &std::path::Path, name: &str, text: &str) -> std::path::PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// `y = factor · x + offset`, shared with includes.rs.
const PRESET: &str = include_str!("fixtures/affine.ron");

#[test]
fn a_preset_included_twice_cooks_with_its_own_parameters() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir(dir.path().join("presets")).unwrap();
    write(&dir.path().join("presets"), "affine.ron", PRESET);
    let main = write(
        dir.path(),
        "main.ron",
        r#"(
        version: 1,
        nodes: {
            "x": (type: "value.float", params: {"value": 3.0}),
            "p1": (type: "graph.include", params: {"path": "presets/affine.ron", "factor": 10.0}),
            "p2": (type: "graph.include", params: {"path": "presets/affine.ron", "offset": 1.0}),
        },
        edges: [("x.value", "p1.x"), ("x.value", "p2.x")],
    )"#,
    );
    let (_, g) = Graph::load(&main, &registry(), &BuildOptions::default()).unwrap_or_else(|d| panic!("{d}"));
    let mut ev = pyrograph_core::Evaluator::new();
    let res = ev.cook(&g, &["p1", "p2"], &CookCtx::new()).unwrap();
    assert_eq!(float(&res.output(&g, "p1", "y").unwrap()), 30.0);
    assert_eq!(float(&res.output(&g, "p2", "y").unwrap()), 7.0);
}

#[test]
fn include_cycles_between_files_are_reported() {
    let dir = tempfile::tempdir().unwrap();
    let body = |other: &str| {
        format!(
            r#"(version: 1, interface: Some((outputs: {{"y": "inc.y"}})),
               nodes: {{"inc": (type: "graph.include", params: {{"path": "{other}"}})}})"#
        )
    };
    write(dir.path(), "a.ron", &body("b.ron"));
    write(dir.path(), "b.ron", &body("a.ron"));
    let err = Graph::load(&dir.path().join("a.ron"), &registry(), &BuildOptions::default()).err().expect("cycle must fail");
    let text = err.to_string();
    assert!(text.contains("include cycle: a.ron -> b.ron -> a.ron"), "{text}");
}
