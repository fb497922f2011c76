//! The time and math nodes: `time.channel` and `time.frame` drive per-frame nodes frame by frame,
//! the math nodes give the numbers their docs promise (and the expressions give), bad inputs are
//! errors naming the port, and frames cooked alone equal a full cook.

use std::f64::consts::{PI, TAU};

use pyrograph_core::{BuildOptions, CookCtx, Evaluator, Graph, GraphDoc, NodeError, PortType, Registry, Value};

/// A graph of built-in nodes from its `nodes` and `edges` RON.
fn graph(nodes: &str, edges: &str) -> Graph {
    let text = format!("(version: 4, nodes: {{ {nodes} }}, edges: [{edges}])");
    let doc = GraphDoc::from_ron(&text).unwrap_or_else(|e| panic!("{e}\n{text}"));
    Graph::build(&doc, &Registry::with_builtins(), std::path::Path::new("."), &BuildOptions::default())
        .unwrap_or_else(|e| panic!("{e:?}"))
}

fn clip(ev: &mut Evaluator, g: &Graph, endpoint: &str, ctx: &CookCtx) -> pyrograph_core::Clip {
    match ev.output(g, endpoint, ctx).unwrap() {
        Value::Clip(c) => c,
        other => panic!("{endpoint} is {}, not a clip", other.type_name()),
    }
}

fn floats(values: &[Value]) -> Vec<f64> {
    values.iter().map(|v| if let Value::Float(x) = v { *x } else { panic!("{v:?} is not a Float") }).collect()
}

/// Every frame of `endpoint` in a full cook.
fn cook(g: &Graph, endpoint: &str) -> Vec<f64> {
    let ctx = CookCtx::new();
    floats(&clip(&mut Evaluator::new(), g, endpoint, &ctx).materialize(&ctx).unwrap())
}

/// The error of frame `frame` of `endpoint`, as text.
fn frame_error(g: &Graph, endpoint: &str, frame: usize) -> String {
    let ctx = CookCtx::new();
    let c = clip(&mut Evaluator::new(), g, endpoint, &ctx);
    c.get(frame, &ctx).expect_err("the frame fails").to_string()
}

#[test]
fn a_keyed_channel_through_fit_drives_a_per_frame_consumer_frame_by_frame() {
    let g = graph(
        r#""ch": (type: "time.channel", params: {"frames": 30, "value": keys([(0, 0.0, linear), (16, 16.0, linear), (24, 0.0)])}),
           "fit": (type: "math.fit", params: {"from_min": 0.0, "from_max": 8.0, "to_min": 100.0, "to_max": 180.0}),
           "add": (type: "math.add", params: {"b": 0.5}),"#,
        r#"("ch.value", "fit.x"), ("fit.value", "add.a")"#,
    );
    let got = cook(&g, "add.value");
    assert_eq!(got.len(), 30);
    for (f, got) in got.iter().enumerate() {
        // The channel: up 0..16, down to 0 at 24, held there; fit maps 0..8 to 100..180 and clamps.
        let v = if f <= 16 { f as f64 } else { (48.0 - 2.0 * f as f64).max(0.0) };
        let want = 100.0 + 10.0 * v.min(8.0) + 0.5;
        assert_eq!(*got, want, "frame {f}");
    }
}

#[test]
fn time_frame_drives_a_sine_per_frame() {
    let g = graph(
        r#""t": (type: "time.frame", params: {"frames": 48, "fps": 24.0}),
           "s": (type: "math.sine", params: {"frequency": 0.125, "amplitude": 2.0, "phase": 0.25, "offset": 1.0}),
           "sec": (type: "math.sine"),"#,
        r#"("t.frame", "s.x"), ("t.time", "sec.x")"#,
    );
    let s = cook(&g, "s.value");
    assert_eq!(s.len(), 48);
    // 2·sin(2π(f/8 + 1/4)) + 1 = 2·cos(πf/4) + 1: 3 at frame 0, 1 at frame 2, −1 at frame 4, period 8.
    for (f, want) in [(0, 3.0), (2, 1.0), (4, -1.0), (6, 1.0), (8, 3.0), (44, -1.0)] {
        assert!((s[f] - want).abs() < 1e-12, "frame {f}: {} against {want}", s[f]);
    }
    for (f, got) in s.iter().enumerate() {
        assert!((got - (2.0 * (PI * f as f64 / 4.0).cos() + 1.0)).abs() < 1e-12, "frame {f}: {got}");
    }
    // The time clip is in seconds: frame 6 of 24 fps is 0.25 s, a quarter cycle at 1 Hz.
    let sec = cook(&g, "sec.value");
    assert_eq!(sec[6], (TAU * 0.25).sin());
    assert_eq!(sec[30], (TAU * 1.25).sin());
    let ctx = CookCtx::new();
    let time = floats(&clip(&mut Evaluator::new(), &g, "t.time", &ctx).materialize(&ctx).unwrap());
    assert_eq!(time[30], 1.25);
}

#[test]
fn fit_with_an_empty_input_range_is_a_step_and_unclamped_fit_continues_the_line() {
    let g = graph(
        r#""t": (type: "time.frame", params: {"frames": 10}),
           "step": (type: "math.fit", params: {"from_min": 5.0, "from_max": 5.0, "to_min": -1.0, "to_max": 3.0}),
           "line": (type: "math.fit", params: {"from_min": 0.0, "from_max": 4.0, "to_min": 10.0, "to_max": 0.0, "clamp": false}),"#,
        r#"("t.frame", "step.x"), ("t.frame", "line.x")"#,
    );
    assert_eq!(cook(&g, "step.value"), [-1.0, -1.0, -1.0, -1.0, -1.0, 3.0, 3.0, 3.0, 3.0, 3.0]);
    assert_eq!(cook(&g, "line.value"), [10.0, 7.5, 5.0, 2.5, 0.0, -2.5, -5.0, -7.5, -10.0, -12.5]);
}

#[test]
fn clamp_with_min_above_max_is_an_error_naming_the_port() {
    let g = graph(
        r#""t": (type: "time.frame", params: {"frames": 10}),
           "c": (type: "math.clamp", params: {"min": 2.0, "max": 1.0}),
           "one": (type: "math.clamp", params: {"x": 0.5, "min": 2.0, "max": 1.0}),
           "ok": (type: "math.clamp", params: {"min": 2.0, "max": 6.0}),"#,
        r#"("t.frame", "c.x"), ("t.frame", "ok.x")"#,
    );
    let e = frame_error(&g, "c.value", 3);
    assert!(e.contains("'c'") && e.contains("min") && e.contains("above max") && e.contains("frame 3"), "{e}");
    // Not lifted: the node cooks once, and its error names the port too.
    let err = Evaluator::new().output(&g, "one.value", &CookCtx::new()).unwrap_err();
    let NodeError::InNode { source, .. } = &err else { panic!("{err:?}") };
    assert!(matches!(&**source, NodeError::Port { port, .. } if port == "min"), "{err:?}");
    assert_eq!(cook(&g, "ok.value"), [2.0, 2.0, 2.0, 3.0, 4.0, 5.0, 6.0, 6.0, 6.0, 6.0]);
}

#[test]
fn an_unclamped_fit_of_a_vanishing_range_is_an_error_naming_the_range_not_infinity() {
    let g = graph(
        r#""t": (type: "time.frame", params: {"frames": 4}),
           "f": (type: "math.fit", params: {"from_min": 0.0, "from_max": 1e-310, "to_max": 1e12, "clamp": false}),"#,
        r#"("t.frame", "f.x")"#,
    );
    let ctx = CookCtx::new();
    let first = clip(&mut Evaluator::new(), &g, "f.value", &ctx).get(0, &ctx).unwrap();
    assert!(matches!(first, Value::Float(0.0)), "{first:?}");
    let e = frame_error(&g, "f.value", 2);
    assert!(e.contains("from_max") && e.contains("widen the range") && e.contains("frame 2"), "{e}");
}

#[test]
fn a_channel_value_out_of_range_fails_the_frame_naming_port_and_frame() {
    let g = graph(r#""ch": (type: "time.channel", params: {"frames": 20, "value": expr("frame * 1e11")}),"#, "");
    let ctx = CookCtx::new();
    let c = clip(&mut Evaluator::new(), &g, "ch.value", &ctx);
    let last_in_range = c.get(10, &ctx).unwrap();
    assert!(matches!(last_in_range, Value::Float(1e12)), "{last_in_range:?}");
    let e = c.get(11, &ctx).unwrap_err().to_string();
    assert!(e.contains("value") && e.contains("frame 11") && e.contains("outside the range"), "{e}");
}

#[test]
fn the_nodes_give_the_numbers_of_the_expressions_they_stand_for() {
    let g = graph(
        r#""t": (type: "time.frame", params: {"frames": 60}),
           "n": (type: "math.noise", params: {"frequency": 0.1, "amplitude": 2.0, "seed": 3}),
           "en": (type: "time.channel", params: {"frames": 60, "value": expr("noise(frame * 0.1, 3) * 2")}),
           "f": (type: "math.fit", params: {"from_min": 10.0, "from_max": 40.0, "to_min": 1.5, "to_max": 0.2}),
           "ef": (type: "time.channel", params: {"frames": 60, "value": expr("fit(frame, 10, 40, 1.5, 0.2)")}),"#,
        r#"("t.frame", "n.x"), ("t.frame", "f.x")"#,
    );
    let (n, en) = (cook(&g, "n.value"), cook(&g, "en.value"));
    assert_eq!(n.iter().map(|x| x.to_bits()).collect::<Vec<_>>(), en.iter().map(|x| x.to_bits()).collect::<Vec<_>>());
    assert!(n.iter().any(|x| *x > 0.3) && n.iter().any(|x| *x < -0.3), "the noise moves: {n:?}");
    assert_eq!(cook(&g, "f.value"), cook(&g, "ef.value"));
}

/// A channel, the time and three math nodes: every kind of clip these nodes make.
fn chain() -> Graph {
    graph(
        r#""ch": (type: "time.channel", params: {"frames": 48, "value": expr("sin(time * 3) * 40 + noise(frame * 0.2) * 10")}),
           "t": (type: "time.frame", params: {"frames": 48}),
           "n": (type: "math.noise", params: {"frequency": 0.05, "seed": 7}),
           "s": (type: "math.sine", params: {"frequency": 0.5}),
           "m": (type: "math.mix", params: {"t": 0.25}),"#,
        r#"("ch.value", "n.x"), ("t.time", "s.x"), ("n.value", "m.a"), ("s.value", "m.b")"#,
    )
}

/// The chain's `m.value` as one expression: the same operations in the same order, so the same bits.
const CHAIN: &str = "mix(noise((sin(time * 3) * 40 + noise(frame * 0.2) * 10) * 0.05, 7), sin(2 * pi * (0.5 * time)), 0.25)";

#[test]
fn frames_cooked_alone_in_any_order_equal_a_full_cook() {
    let full = cook(&chain(), "m.value");
    assert_eq!(full.len(), 48);
    // Every frame shares one process-wide cache, so a later cook could be served what the full
    // cook stored: the frames are checked against the expression the chain computes as well.
    let whole = pyrograph_core::anim::Expr::parse(CHAIN).unwrap();
    for (f, x) in full.iter().enumerate() {
        assert_eq!(x.to_bits(), whole.eval(f as f64, 24.0).unwrap().to_bits(), "frame {f} of the full cook");
    }
    // Chunks of 5, last first, each in an evaluator and a graph of its own, as farm tasks cook them.
    for start in (0..48).step_by(5).rev() {
        let end = (start + 5).min(48);
        let ctx = CookCtx::new();
        let c = clip(&mut Evaluator::new(), &chain(), "m.value", &ctx);
        for f in (start..end).rev() {
            let Value::Float(x) = c.get(f, &ctx).unwrap() else { panic!() };
            assert_eq!(x.to_bits(), full[f].to_bits(), "frame {f}");
        }
    }
}

#[test]
fn moving_a_key_recooks_only_the_frames_whose_channel_value_moved() {
    let doc = |last: &str| {
        graph(
            &format!(
                r#""ch": (type: "time.channel", params: {{"frames": 40, "value": keys([(0, 0.0, linear), (10, 10.0, linear), (20, 10.0, linear), {last}])}}),
                   "s": (type: "math.sine"),"#
            ),
            r#"("ch.value", "s.x")"#,
        )
    };
    let mut ev = Evaluator::new();
    let ctx = CookCtx::new().with_frame_log();
    let before = floats(&clip(&mut ev, &doc("(30, 0.0)"), "s.value", &ctx).materialize(&ctx).unwrap());
    ctx.take_frame_log();
    let after = floats(&clip(&mut ev, &doc("(30, 5.0)"), "s.value", &ctx).materialize(&ctx).unwrap());
    let mut frames: Vec<usize> = ctx.take_frame_log().into_iter().filter(|(n, _)| n == "s").map(|(_, f)| f).collect();
    frames.sort_unstable();
    // Frames 21..=29 now run 9.5, 9, 8.5, …, 5.5 and frames 30.. hold 5: a frame is keyed by its
    // value, so only the values the first cook never had (the halves, at odd frames) are cooked.
    assert_eq!(frames, [21, 23, 25, 27, 29], "only frames with a value not cooked before");
    assert_eq!(before[..21], after[..21]);
    assert_ne!(before[25], after[25]);
}

#[test]
fn every_time_and_math_node_is_documented_with_ranges_on_its_numbers() {
    let r = Registry::with_builtins();
    for name in ["time.frame", "time.channel", "math.fit", "math.clamp", "math.mix", "math.sine", "math.noise"] {
        let d = r.desc(name).unwrap_or_else(|| panic!("{name} is registered"));
        assert!(!d.doc.is_empty(), "{name} has a doc");
        assert_eq!(d.category, if name.starts_with("time.") { "Time" } else { "Math" });
        for p in &d.inputs {
            assert!(!p.doc.is_empty(), "{name}.{} has a doc", p.name);
            if matches!(p.ty, PortType::Float | PortType::Int) {
                assert!(p.range.is_some(), "{name}.{} has a range", p.name);
            }
        }
    }
}
