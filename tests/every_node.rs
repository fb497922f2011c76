//! Cooks every registered node type with its defaults and the smallest real inputs it needs,
//! so a port read that its declaration does not have ("no such input"), a wrong type or a
//! default a node cannot cook shows up here rather than in an artist's graph.

#[path = "support/nodes.rs"]
mod nodes;

use nodes::{cook, data_refusal, graph_for, make_files};

#[test]
fn every_registered_node_cooks_with_its_defaults() {
    let registry = pyrograph_frontend::registry();
    let files = make_files(&registry, (48, 64));
    let mut failures = Vec::new();
    let mut cooked = 0;
    let mut refused = 0;
    let descs: Vec<_> = registry.descs().cloned().collect();
    for desc in descs {
        let name = desc.type_name.as_str();
        let doc = graph_for(&desc, &files);
        let out = tempfile::tempdir().unwrap();
        match cook(&registry, &doc, out.path(), "n") {
            Ok(()) => cooked += 1,
            Err(e) if data_refusal(name, &e) => refused += 1,
            Err(e) => failures.push(format!("{name}: {e}")),
        }
    }
    assert!(failures.is_empty(), "{} of {} node types failed:\n{}", failures.len(), cooked + failures.len(), failures.join("\n"));
    assert!(cooked + refused >= 76, "only {} node types registered", cooked + refused);
    assert!(refused <= 2, "{refused} data refusals");
}
