//! Hostile sizes: nothing in loading, checking or cooking recurses once per node, so a chain of
//! 20,000 nodes checks and cooks on a thread with a 512 KiB stack (the main thread has 8 MiB,
//! rayon's workers 2): recursion of even 27 bytes a node would overflow it (petgraph's Tarjan,
//! which this replaced, took about 120). The CLI checks a 1,000,000-node chain (TESTING.md), and
//! a cycle through all of a chain is one error that names a few of its nodes.

use pyrograph_core::{BuildOptions, CookCtx, DiagnosticKind, Evaluator, Graph, GraphDoc, NodeDoc, ParamValue, Registry, Value};
use pyrograph_testing::include_bomb;

const CHAIN: usize = 20_000;

/// `math.add` nodes n0 → n1 → … → n{len − 1}, each adding 1; `close` feeds the last back into the first.
fn chain(len: usize, close: bool) -> GraphDoc {
    let mut doc = GraphDoc::new();
    for i in 0..len {
        let mut node = NodeDoc::new("math.add");
        node.params.insert("b".into(), ParamValue::Float(1.0));
        doc.add_node(&format!("n{i}"), node);
    }
    for i in 1..len {
        doc.connect(&format!("n{}.value", i - 1), &format!("n{i}.a"));
    }
    if close {
        doc.connect(&format!("n{}.value", len - 1), "n0.a");
    }
    doc
}

/// Runs `f` on a thread with a 512 KiB stack.
fn on_small_stack<T: Send + 'static>(f: impl FnOnce() -> T + Send + 'static) -> T {
    let worker = std::thread::Builder::new().stack_size(512 << 10).spawn(f).expect("spawn");
    worker.join().expect("no stack overflow or panic")
}

#[test]
fn a_long_chain_checks_and_cooks_without_recursing_per_node() {
    let value = on_small_stack(|| {
        let doc = chain(CHAIN, false);
        let graph = Graph::build(&doc, &Registry::with_builtins(), std::path::Path::new("."), &BuildOptions::default())
            .unwrap_or_else(|d| panic!("{d}"));
        let v = Evaluator::new().output(&graph, &format!("n{}.value", CHAIN - 1), &CookCtx::new()).unwrap();
        // The graph, its caches and the values drop here too, on the small stack.
        drop(graph);
        v
    });
    assert!(matches!(value, Value::Float(v) if v == CHAIN as f64), "{value:?}");
}

#[test]
fn a_cycle_through_a_long_chain_is_one_error_naming_a_few_of_its_nodes() {
    let diagnostics = on_small_stack(|| {
        let doc = chain(CHAIN, true);
        match Graph::build(&doc, &Registry::with_builtins(), std::path::Path::new("."), &BuildOptions::default()) {
            Ok(_) => panic!("a cycle built"),
            Err(d) => d.0,
        }
    });
    let cycles: Vec<_> = diagnostics.iter().filter(|d| d.kind == DiagnosticKind::Cycle).collect();
    assert_eq!(cycles.len(), 1, "{:?}", cycles.iter().map(|d| &d.message).collect::<Vec<_>>());
    let message = &cycles[0].message;
    assert!(message.contains("20000 nodes") && message.contains("'n0'") && message.len() < 400, "{message}");
}

fn load(path: &std::path::Path) -> Result<Graph, pyrograph_core::Diagnostics> {
    let doc = GraphDoc::load(path)?;
    Graph::build_file(&doc, path, &Registry::with_builtins(), &BuildOptions::default())
}

#[test]
fn an_include_bomb_is_refused_before_it_is_built_naming_the_chain() {
    let dir = tempfile::tempdir().unwrap();
    // 31 files: 2^31 − 1 nodes flattened. Refused at once, from the files' sizes alone.
    let start = std::time::Instant::now();
    let e = load(&include_bomb(dir.path(), 30, false)).err().expect("refused").to_string();
    assert!(start.elapsed().as_secs() < 10, "{:?}", start.elapsed());
    assert!(e.contains("would have 2147483647 nodes, more than the 1000000"), "{e}");
    assert!(e.contains("f1.ron (1073741823 nodes each, included 2×) → f2.ron"), "{e}");
    assert!(e.contains("PYROGRAPH_MAX_NODES"), "{e}");
    // Listed as a preset, the same file is refused the same way.
    let Err(e) = pyrograph_core::graph::preset_desc(&dir.path().join("f0.ron"), &Registry::with_builtins()) else {
        panic!("a preset listing built the bomb")
    };
    assert!(e.to_string().contains("would have 2147483647 nodes"), "{e}");
}

#[test]
fn a_file_included_many_times_is_built_once_and_its_problem_reported_once() {
    let dir = tempfile::tempdir().unwrap();
    // 12 levels: 8191 nodes, every file built once; it cooks to 2^12.
    let graph = load(&include_bomb(dir.path(), 12, false)).unwrap_or_else(|d| panic!("{d}"));
    assert_eq!(graph.node_count(), 8191);
    let v = Evaluator::new().output(&graph, "s.value", &CookCtx::new()).unwrap();
    assert!(matches!(v, Value::Float(x) if x == 4096.0), "{v:?}");
    // A broken leaf under 2^12 instances: its problem is told once in full, each other
    // include of a broken file says where to look in one line.
    let dir = tempfile::tempdir().unwrap();
    let e = load(&include_bomb(dir.path(), 12, true)).err().expect("the leaf is broken");
    let full = e.0.iter().filter(|d| d.message.contains("math.nope")).count();
    assert_eq!(full, 1, "{e}");
    assert!(e.0.len() <= 2 * 13, "{} diagnostics:\n{e}", e.0.len());
}
