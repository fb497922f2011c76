//! Tests of the graph document: parsing, migrations, versions, saving.
use super::*;

const SAMPLE: &str = r#"(
    version: 1,
    nodes: {
        "frames": (type: "imaging.load_sequence", params: {"path": "frames", "fps": 30.0}),
        "gray": (type: "imaging.to_gray", pos: (420, 80)),
    },
    edges: [("frames.clip", "gray.image")],
)"#;

#[test]
fn parses_the_design_shape() {
    let doc = GraphDoc::from_ron(SAMPLE).unwrap();
    assert_eq!(doc.nodes.0.len(), 2);
    assert_eq!(doc.nodes.0[0].0, "frames");
    assert_eq!(doc.node("frames").unwrap().params["fps"], ParamValue::Float(30.0));
    assert_eq!(doc.node("gray").unwrap().pos, Some((420.0, 80.0)));
    assert_eq!(doc.edges, vec![("frames.clip".to_string(), "gray.image".to_string())]);
}

#[test]
fn round_trips_through_text() {
    let doc = GraphDoc::from_ron(SAMPLE).unwrap();
    let again = GraphDoc::from_ron(&doc.to_ron()).unwrap();
    assert_eq!(doc, again);
}

#[test]
fn keeps_duplicate_ids_for_validation() {
    let text = r#"(version: 1, nodes: {"a": (type: "x"), "a": (type: "y")})"#;
    let doc = GraphDoc::from_ron(text).unwrap();
    assert_eq!(doc.nodes.0.len(), 2);
}

#[test]
fn syntax_errors_carry_line_and_column() {
    let err = GraphDoc::from_ron("(version: 1,\n nodes: {\"a\": (type: }\n)").unwrap_err();
    match &err.0[0].location {
        Location::Text { line, .. } => assert_eq!(*line, 2),
        other => panic!("expected a text location, got {other:?}"),
    }
}

#[test]
fn a_malformed_graph_is_described_in_the_files_terms_not_the_readers() {
    let deep =
        format!("(version: 1, nodes: {{\"a\": (type: \"x\", params: {{\"b\": {}1{}}})}})", "[".repeat(500), "]".repeat(500));
    for text in [
        "42",
        "[]",
        "Graph(version: 1)",
        "",
        "(version: 1, nodes: {\"a\": 3})",
        "(version: 1, nodes: {\"a\": (kind: 1)})",
        deep.as_str(),
    ] {
        let message = GraphDoc::from_ron(text).unwrap_err().0[0].message.clone();
        let internal = ["VersionProbe", "GraphDoc", "NodeDoc", "NodeV0", "struct", "ron::", "serde_stacker"];
        assert!(!internal.iter().any(|n| message.contains(n)), "{text:?}: {message}");
        let says = ["a graph, (version", "a node, (type", "nested too deep"];
        assert!(says.iter().any(|s| message.contains(s)), "{text:?}: {message}");
    }
}

#[test]
fn newer_versions_are_refused_with_advice() {
    let err = GraphDoc::from_ron("(version: 7, nodes: {})").unwrap_err();
    assert_eq!(err.0[0].kind, DiagnosticKind::Version);
    assert!(err.0[0].message.contains("upgrade"));
}

#[test]
fn migrates_the_unversioned_shape() {
    let old = r#"(
        nodes: [(id: "c", kind: "imaging.constant_color", settings: {"width": 4}, x: 1.0, y: 2.0)],
        links: [(from: "c.image", to: "w.clip")],
    )"#;
    let doc = GraphDoc::from_ron(old).unwrap();
    assert_eq!(doc.version, CURRENT_VERSION);
    assert_eq!(doc.node("c").unwrap().type_name, "imaging.constant_color");
    assert_eq!(doc.node("c").unwrap().params["width"], ParamValue::Int(4));
    assert_eq!(doc.node("c").unwrap().pos, Some((1.0, 2.0)));
    assert_eq!(doc.edges[0], ("c.image".to_string(), "w.clip".to_string()));
}

#[test]
fn cli_values_parse_as_ron_or_fall_back_to_text() {
    assert_eq!(ParamValue::parse_cli("0.5"), ParamValue::Float(0.5));
    assert_eq!(ParamValue::parse_cli("7"), ParamValue::Int(7));
    assert_eq!(ParamValue::parse_cli("frames/a.png"), ParamValue::String("frames/a.png".into()));
    assert_eq!(
        ParamValue::parse_cli("(1, 0.5, 0)"),
        ParamValue::List(vec![ParamValue::Int(1), ParamValue::Float(0.5), ParamValue::Int(0)])
    );
}

#[test]
fn atomic_write_refuses_to_overwrite_unless_asked() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("g.ron");
    write_atomic(&p, b"one", false).unwrap();
    assert!(write_atomic(&p, b"two", false).is_err());
    assert_eq!(std::fs::read(&p).unwrap(), b"one");
    write_atomic(&p, b"two", true).unwrap();
    assert_eq!(std::fs::read(&p).unwrap(), b"two");
    let leftovers = std::fs::read_dir(dir.path()).unwrap().count();
    assert_eq!(leftovers, 1, "no temp files left behind");
}

#[test]
fn endpoints_split_at_the_last_dot() {
    assert_eq!(split_endpoint("a.b.port"), Some(("a.b", "port")));
    assert_eq!(split_endpoint("nodot"), None);
    assert_eq!(split_endpoint(".x"), None);
}

const ANNOTATED: &str = r##"(
    version: 2,
    nodes: {
        "a": (type: "value.float", pos: (0, 0)),
        "b": (type: "value.float", pos: (0, 120)),
    },
    groups: [(title: "inputs", color: "#3366aa", nodes: ["a", "b"])],
    comments: [(text: "tune these\nfirst", pos: (-40, -80))],
)"##;

#[test]
fn groups_and_comments_round_trip_as_version_2() {
    let doc = GraphDoc::from_ron(ANNOTATED).unwrap();
    assert_eq!(doc.groups.len(), 1);
    assert_eq!(doc.groups[0].nodes, vec!["a".to_string(), "b".to_string()]);
    assert_eq!(doc.groups[0].color.as_deref(), Some("#3366aa"));
    assert_eq!(doc.comments[0].text, "tune these\nfirst");
    let text = doc.to_ron();
    assert!(text.contains("version: 2"), "{text}");
    assert_eq!(GraphDoc::from_ron(&text).unwrap(), doc);
}

#[test]
fn preset_metadata_round_trips_as_version_3_and_newer_is_refused() {
    let text = r#"(version: 3, preset: (name: "candle row", description: "Five candles", tags: ["fire", "candle"],
        revision: 2, author: "pyrograph", licence: "MIT", thumbnail: "thumbs/candle-row.png", requires: ["footage"],
        samples: {"footage": "clips/candle.mp4"}, preview: "gray", thumbnail_frame: 30),
        nodes: {"a": (type: "value.float")})"#;
    let doc = GraphDoc::from_ron(text).unwrap();
    let p = doc.preset.as_ref().unwrap();
    assert_eq!((p.name.as_str(), p.revision, p.tags.len(), p.requires.len()), ("candle row", 2, 2, 1));
    assert_eq!(p.thumbnail.as_deref(), Some("thumbs/candle-row.png"));
    assert_eq!(p.samples["footage"], "clips/candle.mp4");
    assert_eq!((p.preview.as_deref(), p.thumbnail_frame), (Some("gray"), Some(30)));
    let out = doc.to_ron();
    assert!(out.contains("version: 3,") && out.contains("preset: (") && !out.contains("Some("), "{out}");
    assert_eq!(GraphDoc::from_ron(&out).unwrap(), doc);
    let err = GraphDoc::from_ron(&out.replace("version: 3", "version: 7")).unwrap_err();
    assert_eq!(err.0[0].kind, DiagnosticKind::Version);
    // Without metadata the same graph is written for older readers again.
    let mut plain = doc.clone();
    plain.preset = None;
    assert!(plain.to_ron().contains("version: 1,"));
}

#[test]
fn documents_without_annotations_are_written_as_version_1_and_v1_files_migrate() {
    let doc = GraphDoc::from_ron(SAMPLE).unwrap();
    assert_eq!(doc.version, CURRENT_VERSION, "a version 1 file migrates on load");
    let text = doc.to_ron();
    assert!(text.contains("version: 1,"), "older readers can still open it: {text}");
    assert!(!text.contains("groups") && !text.contains("comments"), "{text}");
    let mut annotated = doc.clone();
    annotated.comments.push(CommentDoc { text: "x".into(), pos: (1.0, 2.0), color: None });
    assert!(annotated.to_ron().contains("version: 2,"));
    annotated.comments.clear();
    assert!(annotated.to_ron().contains("version: 1,"));
}

#[test]
fn ungrouping_a_deleted_node_keeps_the_group() {
    let mut doc = GraphDoc::from_ron(ANNOTATED).unwrap();
    doc.ungroup_node("a");
    assert_eq!(doc.groups[0].nodes, vec!["b".to_string()]);
}

#[test]
fn a_bypassed_node_is_written_as_version_5_and_only_then() {
    let mut doc = GraphDoc::from_ron(SAMPLE).unwrap();
    doc.node_mut("gray").unwrap().bypass = true;
    let text = doc.to_ron();
    assert!(text.contains("version: 5,") && text.contains("bypass: true"), "{text}");
    assert_eq!(text.matches("bypass").count(), 1, "only the bypassed node says so: {text}");
    let back = GraphDoc::from_ron(&text).unwrap();
    assert!(back.node("gray").unwrap().bypass && !back.node("frames").unwrap().bypass);
    assert_eq!(back, doc);
    doc.node_mut("gray").unwrap().bypass = false;
    assert!(doc.to_ron().contains("version: 1,"), "bypass off: readable by older releases again");
    // A version 4 file (animated, no bypass) migrates to 5 in memory and is written as 4.
    let v4 = GraphDoc::from_ron(r#"(version: 4, nodes: {"a": (type: "value.float", params: {"value": expr("time")})})"#).unwrap();
    assert_eq!(v4.version, CURRENT_VERSION);
    assert!(v4.to_ron().contains("version: 4,"));
}

#[test]
fn a_local_subgraph_is_written_as_version_6_each_node_on_its_line_and_only_then() {
    let mut doc = GraphDoc::from_ron(SAMPLE).unwrap();
    let inner = GraphDoc::from_ron(SAMPLE).unwrap();
    doc.add_node("fire", NodeDoc::new("graph.include"));
    doc.subgraphs.insert("fire".into(), inner);
    let text = doc.to_ron();
    assert!(text.starts_with("(\n    version: 6,"), "{text}");
    assert!(text.contains("    subgraphs: {\n        \"fire\": (\n            version: 1,\n"), "{text}");
    assert!(text.contains("\n                \"gray\": (type: \"imaging.to_gray\""), "one line per inner node: {text}");
    let back = GraphDoc::from_ron(&text).unwrap();
    assert_eq!(back, doc);
    assert_eq!(back.subgraphs["fire"].version, CURRENT_VERSION, "in memory, every level is current");
    doc.subgraphs.clear();
    assert!(!doc.to_ron().contains("version: 6"));
    let future = text.replace("            version: 1,", "            version: 99,");
    let err = GraphDoc::from_ron(&future).unwrap_err().to_string();
    assert!(err.contains("local subgraph 'fire': version 99 is newer"), "{err}");
}
