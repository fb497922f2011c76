//! Validation reports every problem of a document at once, each with its location.

use pyrograph_core::{BuildOptions, DiagnosticKind, Graph, GraphDoc, Location, Registry};

fn problems(text: &str) -> Vec<(DiagnosticKind, Location, String)> {
    let doc = GraphDoc::from_ron(text).unwrap_or_else(|d| panic!("{d}"));
    match Graph::build(&doc, &Registry::with_builtins(), std::path::Path::new("."), &BuildOptions::default()) {
        Ok(_) => Vec::new(),
        Err(d) => d.0.into_iter().map(|d| (d.kind, d.location, d.message)).collect(),
    }
}

#[test]
fn every_problem_is_reported_together() {
    let found = problems(
        r#"(version: 1,
        nodes: {
            "a": (type: "math.add", params: {"a": "text", "zz": 1.0}),
            "b": (type: "math.nope"),
            "c": (type: "math.add"),
            "c": (type: "math.add"),
            "i": (type: "value.int", params: {"value": 1.5}),
        },
        edges: [("a.value", "ghost.a"), ("a.nothing", "c.a"), ("i.value", "c.b"), ("c.value", "a.b"), ("broken", "c.a")],
    )"#,
    );
    let kinds: Vec<DiagnosticKind> = found.iter().map(|f| f.0).collect();
    for k in [
        DiagnosticKind::WrongKind,
        DiagnosticKind::UnknownPort,
        DiagnosticKind::UnknownNodeType,
        DiagnosticKind::DuplicateNode,
        DiagnosticKind::MissingNode,
        DiagnosticKind::TypeMismatch,
        DiagnosticKind::MalformedEdge,
    ] {
        assert!(kinds.contains(&k), "{k:?} missing from {found:#?}");
    }
    let mismatch = found.iter().find(|f| f.0 == DiagnosticKind::TypeMismatch).unwrap();
    assert_eq!(mismatch.1, Location::Port { node: "c".into(), port: "b".into() });
    assert!(mismatch.2.contains("needs Float, got Int from 'i.value'"), "{}", mismatch.2);
}

#[test]
fn cycles_name_their_nodes() {
    let found = problems(
        r#"(version: 1, nodes: {"p": (type: "math.add"), "q": (type: "math.add"), "r": (type: "math.add")},
            edges: [("p.value", "q.a"), ("q.value", "r.a"), ("r.value", "p.a")])"#,
    );
    assert_eq!(found.len(), 1, "{found:?}");
    assert_eq!(found[0].0, DiagnosticKind::Cycle);
    assert!(found[0].2.contains("'p', 'q', 'r'"), "{}", found[0].2);
}

#[test]
fn ranges_and_options_are_checked() {
    let found = problems(r#"(version: 1, nodes: {"v": (type: "value.float", params: {"value": 1e20})})"#);
    assert_eq!(found[0].0, DiagnosticKind::OutOfRange);
    assert_eq!(found[0].1, Location::Port { node: "v".into(), port: "value".into() });
}

#[test]
fn an_input_takes_one_edge() {
    let found = problems(
        r#"(version: 1, nodes: {"x": (type: "value.float"), "y": (type: "value.float"), "s": (type: "math.add")},
            edges: [("x.value", "s.a"), ("y.value", "s.a")])"#,
    );
    assert_eq!(found.len(), 1);
    assert_eq!(found[0].0, DiagnosticKind::DuplicateEdge);
}

#[test]
fn unset_environment_variables_are_named() {
    let found = problems(
        r#"(version: 1, nodes: {"g": (type: "graph.include", params: {"path": "${PYROGRAPH_SURELY_UNSET_VAR}/x.ron"})})"#,
    );
    assert!(found[0].2.contains("PYROGRAPH_SURELY_UNSET_VAR is not set"), "{found:?}");
}

#[test]
fn a_rejected_parameter_is_reported_once_not_also_as_missing() {
    let found = problems(r#"(version: 1, nodes: {"v": (type: "value.int", params: {"value": "x"})})"#);
    assert_eq!(found.len(), 1, "{found:?}");
}

#[test]
fn groups_name_existing_nodes_once_with_colours_that_parse() {
    let found = problems(
        r##"(version: 2,
        nodes: {"a": (type: "value.float"), "b": (type: "value.float")},
        groups: [
            (title: "one", color: "#112233", nodes: ["a", "ghost"]),
            (title: "two", color: "blue", nodes: ["a", "b"]),
        ],
        comments: [(text: "x", pos: (0, 0), color: "#12")],
    )"##,
    );
    let at = |i: usize, t: &str| Location::Group { index: i, title: t.into() };
    assert!(
        found.iter().any(|f| f.0 == DiagnosticKind::MissingNode && f.1 == at(0, "one") && f.2.contains("ghost")),
        "{found:#?}"
    );
    assert!(
        found.iter().any(|f| f.0 == DiagnosticKind::DuplicateNode && f.1 == at(1, "two") && f.2.contains("'a'")),
        "{found:#?}"
    );
    assert!(found.iter().any(|f| f.0 == DiagnosticKind::WrongKind && f.1 == at(1, "two")), "{found:#?}");
    assert!(found.iter().any(|f| f.0 == DiagnosticKind::WrongKind && f.2.contains("comment #0")), "{found:#?}");
    assert_eq!(found.len(), 4, "{found:#?}");
}
