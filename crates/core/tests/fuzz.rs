//! Bounded fuzzing on stable, in `cargo test`: every parser a user's text reaches — the graph
//! document loader, the `--set` value parser, the frame grammar, the old text forms of ramps and
//! point lists, the expression parser — is fed inputs made by mutating valid examples (bytes
//! inserted, removed, replaced, runs duplicated or cut) and by drawing from the characters its
//! grammar uses. Each must return (a value or an error), never panic, within a second an input.
//! `PYROGRAPH_FUZZ_CASES` sets the cases per target (default 100,000; TESTING.md records longer
//! runs).

use std::str::FromStr;
use std::time::{Duration, Instant};

use proptest::prelude::*;
use proptest::test_runner::{Config, TestRunner};
use pyrograph_core::anim::Expr;
use pyrograph_core::frames::FrameSet;
use pyrograph_core::value::{Points, RampKeys};
use pyrograph_core::{BuildOptions, CookCtx, Evaluator, Graph, GraphDoc, ParamValue};

fn cases() -> u32 {
    std::env::var("PYROGRAPH_FUZZ_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(100_000)
}

/// One edit of a text: where, what, and the bytes it brings.
#[derive(Clone, Debug)]
enum Edit {
    Insert(usize, String),
    Remove(usize, usize),
    Replace(usize, char),
    Duplicate(usize, usize),
    Cut(usize),
}

fn edit(alphabet: &'static str) -> impl Strategy<Value = Edit> {
    let chars: Vec<char> = alphabet.chars().collect();
    let ch = proptest::sample::select(chars);
    prop_oneof![
        (any::<usize>(), proptest::collection::vec(ch.clone(), 1..8))
            .prop_map(|(at, s)| Edit::Insert(at, s.into_iter().collect())),
        (any::<usize>(), 1usize..12).prop_map(|(at, n)| Edit::Remove(at, n)),
        (any::<usize>(), ch).prop_map(|(at, c)| Edit::Replace(at, c)),
        (any::<usize>(), 1usize..40).prop_map(|(at, n)| Edit::Duplicate(at, n)),
        any::<usize>().prop_map(Edit::Cut),
    ]
}

fn apply(text: &str, edits: &[Edit]) -> String {
    let mut t: Vec<char> = text.chars().collect();
    for e in edits {
        let at = |i: usize| if t.is_empty() { 0 } else { i % (t.len() + 1) };
        match e {
            Edit::Insert(i, s) => {
                let i = at(*i);
                t.splice(i..i, s.chars());
            }
            Edit::Remove(i, n) => {
                let i = at(*i);
                let end = (i + n).min(t.len());
                t.drain(i..end);
            }
            Edit::Replace(i, c) if !t.is_empty() => {
                let i = *i % t.len();
                t[i] = *c;
            }
            Edit::Duplicate(i, n) => {
                let i = at(*i);
                let run: Vec<char> = t[i..(i + n).min(t.len())].to_vec();
                t.splice(i..i, run);
            }
            Edit::Cut(i) => t.truncate(at(*i)),
            Edit::Replace(..) => {}
        }
    }
    t.into_iter().collect()
}

/// Runs `parse` on `cases()` mutations of `seeds`, failing on a panic or an input over a second.
fn fuzz(name: &str, seeds: &'static [&'static str], alphabet: &'static str, parse: impl Fn(&str)) {
    let strategy = (proptest::sample::select(seeds), proptest::collection::vec(edit(alphabet), 0..6));
    let mut runner = TestRunner::new(Config { cases: cases(), failure_persistence: None, ..Config::default() });
    let started = Instant::now();
    runner
        .run(&strategy, |(seed, edits)| {
            let text = apply(seed, &edits);
            let t = Instant::now();
            parse(&text);
            prop_assert!(t.elapsed() < Duration::from_secs(1), "{name}: {:?} for {text:?}", t.elapsed());
            Ok(())
        })
        .unwrap_or_else(|e| panic!("{name}: {e}"));
    println!("{name}: {} inputs in {:.1} s", cases(), started.elapsed().as_secs_f64());
}

const RON: &str = "()[]{},:\"'\\ .-+0123456789eE_abcxyzkeysexprfacetypeparamsversionnodesedges#/*\n\t";

#[test]
fn the_document_loader_never_panics() {
    const SEEDS: &[&str] = &[
        r#"(version: 4, nodes: {"a": (type: "math.add", params: {"a": keys([(0, 1.0), (24, 2.0, ease)], cycle), "b": expr("sin(time)")}, pos: (1, 2))}, edges: [("a.value", "b.a")])"#,
        r#"(version: 3, preset: (name: "x", tags: ["a"]), interface: (outputs: {"v": "a.value"}, params: {"p": "a.b"}), nodes: {}, edges: [], groups: [(title: "g", nodes: ["a"])], comments: [(text: "c", pos: (0, 0))])"#,
        r#"(nodes: [(id: "a", kind: "math.add", settings: {"a": 1})], links: [(from: "a.value", to: "b.a")])"#,
        r#"(version: 1, nodes: {"s": (type: "particles.fire_spread", params: {"ignite": [(0.5, 0.2, -0.15), (2, face(3, (0.2, 0.3, 0.5)))], "center_ramp": [(0, (1, 0, 0, 1))]})}, edges: [])"#,
    ];
    fuzz("GraphDoc::from_ron", SEEDS, RON, |t| {
        let _ = GraphDoc::from_ron(t);
    });
}

#[test]
fn the_set_value_parser_and_the_typed_forms_never_panic() {
    const SEEDS: &[&str] = &[
        "keys([(0, 0.2), (40, 1.5, ease), (72, 0.4, tangent(0.1, -0.2))], hold, linear)",
        "expr(0.5 + 0.2 * sin(time))",
        "[(0.5, 0.2, -0.15), (2.0, (1.85, 0.1, 0.6)), face(3), (1, face(0, (0.2, 0.3, 0.5)))]",
        "[(0, (0.3, 0.4, 1, 0.5)), (0.15, (1, 0.85, 0.5, 0.6))]",
        "(keys([(0, 1.0)]), 0, \"#ff8000\")",
    ];
    fuzz("ParamValue::parse_cli + Points + RampKeys + animation", SEEDS, RON, |t| {
        let v = ParamValue::parse_cli(t);
        let _ = Points::from_param(&v);
        let _ = RampKeys::from_param(&v, 4);
        let _ = pyrograph_core::anim::from_param(&v, pyrograph_core::anim::Shape::Float);
        let _ = pyrograph_core::anim::from_param(&v, pyrograph_core::anim::Shape::Vec3);
    });
}

#[test]
fn the_old_text_forms_and_the_frame_grammar_never_panic() {
    const SEEDS: &[&str] = &[
        "-0.45 0.12 0.75; 1.85 0.1 0.6 @ 0.5; face 3 0.2 0.3 0.5 @ 1.5; face 2",
        "0: 1 0.5 0 1; 0.15: 1 0.85 0.5 0.6; 1: 0.9 0.2 0.02 0",
        "0-99:2,120,130-140x3",
        "1,5,9-12",
    ];
    fuzz("Points/RampKeys::parse_legacy + FrameSet", SEEDS, "0123456789.-+eE:;,@ facex\t", |t| {
        let _ = Points::parse_legacy(t);
        let _ = RampKeys::parse_legacy(t, 4);
        let _ = RampKeys::parse_legacy(t, 1);
        let _ = FrameSet::from_str(t);
    });
}

#[test]
fn the_expression_parser_never_panics() {
    const SEEDS: &[&str] = &[
        "0.5 + 0.2 * sin(time * 3)",
        "fit(frame, 0, 40, 0.2, 1.5) ^ 2",
        "if frame < 40 { 0 } else { clamp(noise(time, 3), -1, 1) }",
        "smoothstep(0, 1, frac(time / 2)) * max(rand(frame), 0.1)",
    ];
    fuzz("Expr::parse + eval", SEEDS, "0123456789.+-*/^%()<>=!&|{}, framtiesnoculpdxhgfk_", |t| {
        if let Ok(e) = Expr::parse(t) {
            let _ = e.eval(12.5, 24.0);
        }
    });
}

#[test]
fn includes_never_panic() {
    // The included file is what changes: an outer graph includes it twice and sums its output.
    const SEEDS: &[&str] = &[
        r#"(version: 4, interface: (outputs: {"value": "x.value"}, params: {"b": "x.b"}), nodes: {"x": (type: "math.add", params: {"a": 1.0, "b": keys([(0, 1), (10, 2)])})}, edges: [])"#,
        r#"(version: 4, interface: (outputs: {"value": "i.value"}), nodes: {"i": (type: "graph.include", params: {"path": "leaf.ron"})}, edges: [])"#,
        r#"(version: 4, interface: (outputs: {"value": "i.value"}), nodes: {"i": (type: "graph.include", params: {"path": "inc.ron"})}, edges: [])"#,
    ];
    let dir = tempfile::tempdir().unwrap();
    let outer = dir.path().join("outer.ron");
    std::fs::write(
        &outer,
        r#"(version: 4, nodes: {"a": (type: "graph.include", params: {"path": "inc.ron"}), "b": (type: "graph.include", params: {"path": "inc.ron", "b": 3.0}), "s": (type: "math.add")}, edges: [("a.value", "s.a"), ("b.value", "s.b")])"#,
    )
    .unwrap();
    std::fs::write(dir.path().join("leaf.ron"), SEEDS[0]).unwrap();
    let inc = dir.path().join("inc.ron");
    let registry = pyrograph_core::Registry::with_builtins();
    fuzz("graph.include (files on disk)", SEEDS, RON, |t| {
        std::fs::write(&inc, t).unwrap();
        if let Ok((_, g)) = Graph::load(&outer, &registry, &BuildOptions::default()) {
            let _ = Evaluator::new().output(&g, "s.value", &CookCtx::new());
        }
    });
}
