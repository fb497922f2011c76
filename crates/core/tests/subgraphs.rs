//! Local subgraphs (document version 6): an include node whose graph is kept in the including
//! file cooks that graph instead of its `path`, nests, is described like a file include, counts
//! towards the node limit, and is refused by name when it belongs to no include.

use pyrograph_core::{BuildOptions, CookCtx, Evaluator, Graph, GraphDoc, NodeDoc, ParamValue, Registry, Value};

/// `y = factor · x + offset`, shared with includes.rs.
const PRESET: &str = include_str!("fixtures/affine.ron");

/// The preset included twice; `p1` keeps its own copy, whose offset is 0.5 and not 0.
const LOCAL: &str = r#"(
    version: 6,
    nodes: {
        "x": (type: "value.float", params: {"value": 3.0}),
        "p1": (type: "graph.include", params: {"path": "affine.ron", "factor": 10.0}),
        "p2": (type: "graph.include", params: {"path": "affine.ron", "factor": 10.0}),
    },
    edges: [("x.value", "p1.x"), ("x.value", "p2.x")],
    subgraphs: {
        "p1": (
            version: 1,
            interface: Some((
                inputs: {"x": "scale.a"},
                outputs: {"y": "offset.value"},
                params: {"factor": "scale.b", "offset": "offset.b"},
            )),
            nodes: {
                "scale": (type: "math.multiply", params: {"b": 2.0}),
                "offset": (type: "math.add", params: {"b": 0.5}),
            },
            edges: [("scale.value", "offset.a")],
        ),
    },
)"#;

fn setup(main: &str) -> (tempfile::TempDir, std::path::PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("affine.ron"), PRESET).unwrap();
    std::fs::write(dir.path().join("nested.ron"), NESTED).unwrap();
    let path = dir.path().join("main.ron");
    std::fs::write(&path, main).unwrap();
    (dir, path)
}

/// A preset that includes affine.ron and adds one.
const NESTED: &str = r#"(
    version: 1,
    interface: Some((inputs: {"x": "inner.x"}, outputs: {"y": "plus.value"})),
    nodes: {
        "inner": (type: "graph.include", params: {"path": "affine.ron"}),
        "plus": (type: "math.add", params: {"b": 1.0}),
    },
    edges: [("inner.y", "plus.a")],
)"#;

fn load(path: &std::path::Path) -> Result<Graph, pyrograph_core::Diagnostics> {
    Graph::load(path, &Registry::with_builtins(), &BuildOptions::default()).map(|(_, g)| g)
}

fn y(g: &Graph, target: &str) -> f64 {
    match Evaluator::new().output(g, target, &CookCtx::new()) {
        Ok(Value::Float(v)) => v,
        other => panic!("{target}: {other:?}"),
    }
}

#[test]
fn a_local_subgraph_is_cooked_instead_of_the_file_it_was_copied_from() {
    let (dir, path) = setup(LOCAL);
    let g = load(&path).unwrap_or_else(|d| panic!("{d}"));
    assert_eq!(y(&g, "p1.y"), 30.5, "p1 cooks its own copy (offset 0.5)");
    assert_eq!(y(&g, "p2.y"), 30.0, "p2 still reads the file");
    assert_eq!(std::fs::read_to_string(dir.path().join("affine.ron")).unwrap(), PRESET);
    // The exposed parameters of the copy are those of the include's ports.
    let ports: Vec<&str> = g.desc("p1").unwrap().inputs.iter().map(|p| p.name.as_str()).collect();
    assert_eq!(ports, ["path", "x", "factor", "offset"]);
}

#[test]
fn a_local_subgraph_needs_no_file_and_survives_its_files_removal() {
    let text = LOCAL.replace(
        r#""path": "affine.ron", "factor": 10.0}),
        "p2""#,
        r#""factor": 10.0}),
        "p2""#,
    );
    assert!(!text.contains(r#""p1": (type: "graph.include", params: {"path""#));
    let (dir, path) = setup(&text);
    std::fs::remove_file(dir.path().join("affine.ron")).unwrap();
    let err = load(&path).err().expect("p2 reads the removed file").to_string();
    assert!(err.contains("p2") && !err.contains("p1"), "{err}");
    let g = load(
        &setup(
            &text
                .replace("\"p2\": (type: \"graph.include\", params: {\"path\": \"affine.ron\", \"factor\": 10.0}),", "")
                .replace(", (\"x.value\", \"p2.x\")", ""),
        )
        .1,
    )
    .unwrap_or_else(|d| panic!("{d}"));
    assert_eq!(y(&g, "p1.y"), 30.5);
}

#[test]
fn a_local_subgraph_of_no_include_is_refused_by_name() {
    let text = LOCAL.replace("subgraphs: {\n        \"p1\"", "subgraphs: {\n        \"p9\"");
    let (_dir, path) = setup(&text);
    let err = load(&path).err().expect("p9 is no node").to_string();
    assert!(err.contains("local subgraph 'p9' belongs to no included graph (there is no node with that id)"), "{err}");
    let text = LOCAL.replace("subgraphs: {\n        \"p1\"", "subgraphs: {\n        \"x\"");
    let err = load(&setup(&text).1).err().expect("x is no include").to_string();
    assert!(err.contains("that node is not a graph.include"), "{err}");
}

#[test]
fn problems_inside_a_local_subgraph_are_reported_at_its_include() {
    let text = LOCAL.replace("\"b\": 0.5", "\"b\": \"half\"");
    let err = load(&setup(&text).1).err().expect("a string is no float").to_string();
    assert!(err.contains("p1") && err.contains("in its local subgraph") && err.contains("offset"), "{err}");
}

#[test]
fn includes_inside_includes_are_described_and_cooked_by_their_path() {
    let main = r#"(
        version: 1,
        nodes: {"x": (type: "value.float", params: {"value": 3.0}), "n": (type: "graph.include", params: {"path": "nested.ron"})},
        edges: [("x.value", "n.x")],
    )"#;
    let g = load(&setup(main).1).unwrap_or_else(|d| panic!("{d}"));
    assert_eq!(g.desc("n/inner").map(|d| d.outputs[0].name.as_str()), Some("y"));
    assert_eq!(y(&g, "n/inner.y"), 6.0, "3 · 2 + 0 inside, before the + 1");
    assert_eq!(y(&g, "n.y"), 7.0);
}

/// A chain of `depth` include nodes, each with a local subgraph holding the next.
fn nested_locals(depth: usize) -> GraphDoc {
    let mut inner = GraphDoc::new();
    inner.add_node("v", NodeDoc::new("value.float").param("value", ParamValue::Float(4.0)));
    inner.interface =
        Some(pyrograph_core::document::InterfaceDoc { outputs: [("y".into(), "v.value".into())].into(), ..Default::default() });
    for _ in 0..depth {
        let mut outer = GraphDoc::new();
        outer.add_node("s", NodeDoc::new("graph.include"));
        outer.subgraphs.insert("s".into(), inner);
        outer.interface =
            Some(pyrograph_core::document::InterfaceDoc { outputs: [("y".into(), "s.y".into())].into(), ..Default::default() });
        inner = outer;
    }
    inner
}

fn build(doc: &GraphDoc) -> Result<Graph, pyrograph_core::Diagnostics> {
    Graph::build(doc, &Registry::with_builtins(), std::path::Path::new("."), &BuildOptions::default())
}

#[test]
fn local_subgraphs_nest_and_too_deep_a_nest_is_refused_not_overflowed() {
    let g = build(&nested_locals(5)).unwrap_or_else(|d| panic!("{d}"));
    assert_eq!(y(&g, "s.y"), 4.0);
    assert_eq!(y(&g, "s/s/s/s/s/v.value"), 4.0);
    let text = nested_locals(5).to_ron();
    assert_eq!(GraphDoc::from_ron(&text).unwrap(), nested_locals(5), "{text}");
    // On a thread with a small stack, so a build that recursed without a limit would crash.
    let err = std::thread::Builder::new()
        .stack_size(8 << 20)
        .spawn(|| build(&nested_locals(200)).err().map(|d| d.to_string()))
        .unwrap()
        .join()
        .unwrap()
        .expect("200 levels are refused");
    assert!(err.contains("nest more than 32 deep"), "{}", &err[..err.len().min(400)]);
}

#[test]
fn the_node_limit_counts_the_nodes_of_local_subgraphs() {
    let mut doc = GraphDoc::new();
    let mut inner = GraphDoc::new();
    for i in 0..50 {
        inner.add_node(&format!("v{i}"), NodeDoc::new("value.float"));
    }
    inner.interface =
        Some(pyrograph_core::document::InterfaceDoc { outputs: [("y".into(), "v0.value".into())].into(), ..Default::default() });
    doc.add_node("big", NodeDoc::new("graph.include"));
    doc.subgraphs.insert("big".into(), inner);
    pyrograph_core::limits::set_max_nodes(Some(40));
    let err = build(&doc).err().map(|d| d.to_string());
    pyrograph_core::limits::set_max_nodes(None);
    let err = err.expect("50 nodes are over 40");
    assert!(err.contains("50 nodes") && err.contains("the local subgraph of 'big'"), "{err}");
}
