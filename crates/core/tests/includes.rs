//! Includes are flattened into the including graph: their nodes cook, cache and fail under
//! `include/inner` ids in the one evaluator, and problems at an include's ports are reported
//! at those ports.

use pyrograph_core::{
    BuildOptions, ClipOf, Cook, CookCtx, DiagnosticKind, Evaluator, Graph, Location, NodeError, Registry, Value,
};

/// `y = factor · x + offset`, shared with evaluator.rs.
const PRESET: &str = include_str!("fixtures/affine.ron");

/// A preset that includes PRESET and adds one to its result.
const NESTED: &str = r#"(
    version: 1,
    interface: Some((inputs: {"x": "inner.x"}, outputs: {"y": "plus.value"}, params: {"factor": "inner.factor"})),
    nodes: {
        "inner": (type: "graph.include", params: {"path": "affine.ron"}),
        "plus": (type: "math.add", params: {"b": 1.0}),
    },
    edges: [("inner.y", "plus.a")],
)"#;

/// A preset whose input must be connected (a data port has no default).
const NEEDS: &str = r#"(
    version: 1,
    interface: Some((inputs: {"clip": "len.clip"}, outputs: {"n": "len.n"})),
    nodes: {"len": (type: "test.len")},
)"#;

pyrograph_core::node! {
    /// The length of a clip.
    #[node("test.len", "Test", WholeClip)]
    pub struct Len {
        /// input
        clip: ClipOf<f64>,
    }
    /// its length
    -> n: i64
}

impl Cook for Len {
    fn cook(self, _: &CookCtx) -> Result<i64, NodeError> {
        Ok(self.clip.len() as i64)
    }
}

fn registry() -> Registry {
    let mut r = Registry::with_builtins();
    r.declare::<Len>();
    r
}

fn setup(main: &str) -> (tempfile::TempDir, std::path::PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("affine.ron"), PRESET).unwrap();
    std::fs::write(dir.path().join("nested.ron"), NESTED).unwrap();
    std::fs::write(dir.path().join("needs.ron"), NEEDS).unwrap();
    let path = dir.path().join("main.ron");
    std::fs::write(&path, main).unwrap();
    (dir, path)
}

fn load(path: &std::path::Path) -> Result<Graph, pyrograph_core::Diagnostics> {
    Graph::load(path, &registry(), &BuildOptions::default()).map(|(_, g)| g)
}

fn float(v: &Value) -> f64 {
    match v {
        Value::Float(x) => *x,
        other => panic!("not a float: {other:?}"),
    }
}

const TWO_INCLUDES: &str = r#"(
    version: 1,
    nodes: {
        "x": (type: "value.float", params: {"value": 3.0}),
        "p1": (type: "graph.include", params: {"path": "affine.ron", "factor": 10.0}),
        "p2": (type: "graph.include", params: {"path": "nested.ron"}),
        "sum": (type: "math.add"),
    },
    edges: [("x.value", "p1.x"), ("x.value", "p2.x"), ("p1.y", "sum.a"), ("p2.y", "sum.b")],
)"#;

#[test]
fn included_nodes_join_the_graph_under_prefixed_ids() {
    let (_dir, path) = setup(TWO_INCLUDES);
    let g = load(&path).unwrap_or_else(|d| panic!("{d}"));
    let mut ids: Vec<String> = g.topo_order().iter().map(|i| g.node(*i).id.to_string()).collect();
    ids.sort();
    assert_eq!(ids, ["p1/offset", "p1/scale", "p2/inner/offset", "p2/inner/scale", "p2/plus", "sum", "x"]);
    assert!(g.index("p1").is_none(), "an include is not a node of its own");
    assert_eq!(g.desc("p1").map(|d| d.outputs[0].name.as_str()), Some("y"));

    let mut ev = Evaluator::new();
    let res = ev.cook(&g, &["sum"], &CookCtx::new()).unwrap();
    // p1: 3·10 + 0 = 30; p2: (3·2 + 0) + 1 = 7.
    assert_eq!(float(&res.output(&g, "p1", "y").unwrap()), 30.0);
    assert_eq!(float(&res.output(&g, "p2", "y").unwrap()), 7.0);
    assert_eq!(float(&res.output(&g, "sum", "value").unwrap()), 37.0);
}

#[test]
fn editing_one_includes_parameter_recooks_only_its_nodes_and_downstream() {
    let (dir, path) = setup(TWO_INCLUDES);
    let mut ev = Evaluator::new();
    let g = load(&path).unwrap();
    ev.cook(&g, &["sum"], &CookCtx::new()).unwrap();
    assert_eq!(ev.take_log().len(), 7, "a cold cook cooks every node once");

    std::fs::write(dir.path().join("main.ron"), TWO_INCLUDES.replace("\"factor\": 10.0", "\"factor\": 4.0")).unwrap();
    let g = load(&path).unwrap();
    let res = ev.cook(&g, &["sum"], &CookCtx::new()).unwrap();
    let mut log = ev.take_log();
    log.sort();
    assert_eq!(log, ["p1/offset", "p1/scale", "sum"]);
    assert_eq!(float(&res.output(&g, "sum", "value").unwrap()), 19.0);

    // Nothing changed: everything, the nested include's nodes too, comes from the cache.
    ev.cook(&g, &["p2"], &CookCtx::new()).unwrap();
    assert!(ev.take_log().is_empty());
}

#[test]
fn an_include_can_be_cooked_as_a_target() {
    let (_dir, path) = setup(TWO_INCLUDES);
    let g = load(&path).unwrap();
    let y = Evaluator::new().output(&g, "p2.y", &CookCtx::new()).unwrap();
    assert_eq!(float(&y), 7.0);
}

#[test]
fn a_wrong_type_into_an_include_port_is_reported_at_that_port() {
    let (_dir, path) = setup(
        r#"(version: 1,
            nodes: {"s": (type: "value.int"), "p": (type: "graph.include", params: {"path": "affine.ron"})},
            edges: [("s.value", "p.x")])"#,
    );
    let d = load(&path).err().expect("Int into Float must fail");
    let mismatch = d.0.iter().find(|d| d.kind == DiagnosticKind::TypeMismatch).expect("a type mismatch");
    assert_eq!(mismatch.location, Location::Port { node: "p".into(), port: "x".into() }, "{d}");
}

#[test]
fn an_unfed_include_input_is_reported_at_the_include() {
    let (_dir, path) = setup(r#"(version: 1, nodes: {"p": (type: "graph.include", params: {"path": "needs.ron"})})"#);
    let d = load(&path).err().expect("clip is required");
    assert_eq!(d.0.len(), 1, "{d}");
    assert_eq!(d.0[0].kind, DiagnosticKind::MissingInput);
    assert_eq!(d.0[0].location, Location::Port { node: "p".into(), port: "clip".into() });
}

#[test]
fn an_unknown_include_port_names_the_include() {
    let (_dir, path) = setup(
        r#"(version: 1,
            nodes: {"s": (type: "value.float"), "p": (type: "graph.include", params: {"path": "affine.ron"})},
            edges: [("s.value", "p.nope")])"#,
    );
    let text = load(&path).err().expect("no such port").to_string();
    assert!(text.contains("has no input 'nope'") && text.contains("x, factor, offset"), "{text}");
}

#[test]
fn ids_with_the_include_separator_are_refused() {
    let (_dir, path) = setup(r#"(version: 1, nodes: {"a/b": (type: "value.float")})"#);
    let d = load(&path).err().expect("'/' is reserved");
    assert_eq!(d.0[0].kind, DiagnosticKind::BadId);
    assert!(d.to_string().contains("a/b"), "{d}");
}
