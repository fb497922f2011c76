use super::*;
use proptest::prelude::*;

fn value(text: &str, frame: f64, fps: f64) -> f64 {
    match Expr::parse(text) {
        Ok(expr) => expr.eval(frame, fps).unwrap_or_else(|err| panic!("{text:?} at frame {frame}: {err}")),
        Err(err) => panic!("{text:?} does not parse: {err}"),
    }
}

fn at(text: &str, frame: f64) -> f64 {
    value(text, frame, 24.0)
}

fn parse_err(text: &str) -> ExprError {
    match Expr::parse(text) {
        Ok(expr) => panic!("{text:?} parsed as {expr:?}"),
        Err(err) => err,
    }
}

fn eval_err(text: &str, frame: f64) -> ExprError {
    match Expr::parse(text).map(|expr| expr.eval(frame, 24.0)) {
        Ok(Ok(v)) => panic!("{text:?} gave {v} at frame {frame}"),
        Ok(Err(err)) => err,
        Err(err) => panic!("{text:?} does not parse: {err}"),
    }
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-12 * (1.0 + b.abs())
}

macro_rules! assert_close {
    ($a:expr, $b:expr) => {{
        let (a, b): (f64, f64) = ($a, $b);
        assert!(close(a, b), "{} = {a}, expected {b}", stringify!($a));
    }};
}

/// Parses and, if that succeeds, evaluates on a thread with rayon's 2 MiB worker stack.
fn parse_on_small_stack(text: String) -> Result<f64, ExprError> {
    let worker = std::thread::Builder::new().stack_size(2 << 20).spawn(move || Expr::parse(&text)?.eval(3.0, 24.0));
    worker.expect("spawn").join().expect("no stack overflow or panic")
}

#[test]
fn artist_examples() {
    assert_close!(value("0.5 + 0.2 * sin(time * 3)", 12.0, 24.0), 0.5 + 0.2 * 1.5f64.sin());
    assert_close!(at("fit(frame, 0, 40, 0.2, 1.5)", 20.0), 0.85);
    assert_close!(at("fit(frame, 0, 40, 0.2, 1.5)", -5.0), 0.2);
    assert_close!(at("fit(frame, 0, 40, 0.2, 1.5)", 90.0), 1.5);
    let t: f64 = 30.0 / 24.0;
    assert_close!(at("noise(time * 2) * 0.3", 30.0), PERLIN.get([t * 2.0, 0.5, 0.25]) * 0.3);
    assert_close!(at("if frame < 40 { 0 } else { 2.5 }", 39.5), 0.0);
    assert_close!(at("if frame < 40 { 0 } else { 2.5 }", 40.0), 2.5);
}

#[test]
fn float_semantics() {
    assert_eq!(at("1/2", 0.0), 0.5);
    assert_eq!(at("2^3", 0.0), 8.0);
    assert_eq!(at("2 ^ -1", 0.0), 0.5);
    assert_eq!(at("2.0^3", 0.0), 8.0);
    assert_eq!(at("2^0.5", 0.0), 2f64.sqrt());
    assert_eq!(at("frame^2", 3.0), 9.0);
    // `^` binds tighter than `*` and `+`, and to the right, as in maths.
    assert_eq!(at("1 + 2^3", 0.0), 9.0);
    assert_eq!(at("2 * 3^2", 0.0), 18.0);
    assert_eq!(at("2^3^2", 0.0), 512.0);
    assert_eq!(at("2**3", 0.0), 8.0);
    assert_eq!(at("7 % 3", 0.0), 1.0);
    assert_eq!(at("frame % 10", 23.5), 3.5);
    assert_eq!(at("frame > 5", 6.0), 1.0);
    assert_eq!(at("frame > 5", 4.0), 0.0);
    assert_eq!(at("true", 0.0), 1.0);
    assert_eq!(at("-3", 0.0), -3.0);
    assert_eq!(at("1e3 + 0x10 + 1_000 + 0b11 + 0o7", 0.0), 2026.0);
    assert_eq!(at("7 / 2 + 0x10 / 0x20", 0.0), 4.0);
    assert_eq!(at("1.5e1 + 2E-1 + 3e+1", 0.0), 45.2);
    assert_eq!(at("-7 % 3", 0.0), -1.0);
    // Beyond the integer range a literal is still a number.
    assert_eq!(at("99999999999999999999 * 10", 0.0), 1e21);
    assert_eq!(at("frame < 10 && frame > 2", 5.0), 1.0);
}

#[test]
fn variables() {
    assert_eq!(value("frame", 12.5, 24.0), 12.5);
    assert_eq!(value("time", 12.0, 24.0), 0.5);
    assert_eq!(value("time", 30.0, 60.0), 0.5);
    assert_eq!(value("fps", 3.0, 30.0), 30.0);
    assert_eq!(at("pi", 0.0), PI);
    // The thread's reused scope must not keep values from an earlier call.
    let expr = Expr::parse("frame * 100 + fps").expect("parses");
    assert_eq!(expr.eval(1.0, 24.0), Ok(124.0));
    assert_eq!(expr.eval(2.0, 25.0), Ok(225.0));
}

#[test]
fn known_function_values() {
    assert_close!(at("sin(pi / 2)", 0.0), 1.0);
    assert_close!(at("cos(0)", 0.0), 1.0);
    assert_close!(at("tan(pi / 4)", 0.0), 1.0);
    assert_close!(at("asin(1)", 0.0), PI / 2.0);
    assert_close!(at("acos(1)", 0.0), 0.0);
    assert_close!(at("atan(1)", 0.0), PI / 4.0);
    assert_close!(at("atan(1, 0)", 0.0), PI / 2.0);
    assert_close!(at("atan(0, -1)", 0.0), PI);
    assert_close!(at("sqrt(16)", 0.0), 4.0);
    assert_close!(at("pow(2, 10)", 0.0), 1024.0);
    assert_close!(at("exp(1)", 0.0), std::f64::consts::E);
    assert_close!(at("ln(exp(2))", 0.0), 2.0);
    assert_close!(at("log(1000)", 0.0), 3.0);
    assert_close!(at("log(8, 2)", 0.0), 3.0);
    assert_close!(at("abs(-3)", 0.0), 3.0);
    assert_close!(at("abs(-2.5)", 0.0), 2.5);
    assert_close!(at("sign(-2.5) + 10 * sign(4) + 100 * sign(0)", 0.0), 9.0);
    assert_close!(at("floor(-1.5) + floor(2)", 0.0), 0.0);
    assert_close!(at("ceil(1.2)", 0.0), 2.0);
    assert_close!(at("round(2.5) + round(-2.5) + round(1.4)", 0.0), 1.0);
    assert_close!(at("frac(-1.25)", 0.0), 0.75);
    assert_close!(at("frac(frame)", 7.25), 0.25);
    assert_close!(at("min(3, 1.5) + max(2, 7)", 0.0), 8.5);
    assert_close!(at("clamp(frame, 0, 10)", 12.0), 10.0);
    assert_close!(at("clamp(frame, 0, 10)", -1.0), 0.0);
    assert_close!(at("clamp(frame, 0, 10)", 4.5), 4.5);
    assert_close!(at("fit01(0.25, 10, 20)", 0.0), 12.5);
    assert_close!(at("fit01(2, 10, 20)", 0.0), 20.0);
    assert_close!(at("fit(5, 10, 0, 0, 1)", 0.0), 0.5);
    assert_close!(at("fit(5, 3, 3, 0, 1) + fit(2, 3, 3, 0, 1)", 0.0), 1.0);
    assert_close!(at("mix(10, 20, 0.25) + lerp(0, 1, 2)", 0.0), 14.5);
    assert_close!(at("smoothstep(0, 10, 5)", 0.0), 0.5);
    assert_close!(at("smoothstep(0, 10, 2.5)", 0.0), 0.15625);
    assert_close!(at("smoothstep(0, 10, -1) + smoothstep(0, 10, 11)", 0.0), 1.0);
    assert_close!(at("step(10, frame)", 9.9), 0.0);
    assert_close!(at("step(10, frame)", 10.0), 1.0);
    assert_close!(at("pulse(frame, 10, 20)", 10.0), 1.0);
    assert_close!(at("pulse(frame, 10, 20)", 20.0), 1.0);
    assert_close!(at("pulse(frame, 10, 20)", 20.5), 0.0);
    assert_close!(at("pulse(frame, 10, 20)", 9.5), 0.0);
    assert_close!(at("radians(180)", 0.0), PI);
    assert_close!(at("degrees(pi)", 0.0), 180.0);
}

#[test]
fn noise_and_rand() {
    assert_close!(at("noise(frame)", 3.3), PERLIN.get([3.3, 0.5, 0.25]));
    assert_close!(at("noise(frame, 0)", 3.3), at("noise(frame)", 3.3));
    assert_ne!(at("noise(frame, 1)", 3.3), at("noise(frame, 2)", 3.3));
    assert_ne!(at("noise(frame, 1)", 3.3), at("noise(frame)", 3.3));
    // Whole-number literals and decimals give the same result.
    assert_eq!(at("noise(2)", 0.0), at("noise(2.0)", 0.0));
    assert_eq!(at("rand(5)", 0.0), at("rand(5.0)", 0.0));
    assert_eq!(at("rand(frame)", 7.0), at("rand(frame)", 7.0));
    assert_ne!(at("rand(frame)", 7.0), at("rand(frame)", 8.0));
    assert_eq!(at("rand(-0.0)", 0.0), at("rand(0)", 0.0));
    let samples: Vec<f64> = (0..1000).map(|i| rand(f64::from(i))).collect();
    assert!(samples.iter().all(|r| (0.0..1.0).contains(r)));
    let mean = samples.iter().sum::<f64>() / 1000.0;
    assert!((mean - 0.5).abs() < 0.05, "mean {mean}");
    // Huge inputs stay in range instead of running off the noise crate's integer corner.
    assert!(at("noise(1e20)", 0.0).abs() <= 1.0);
}

/// Found by libFuzzer (fuzz/, target `expression`): an infinite argument reached the noise
/// crate, which panicked turning it into a lattice cell.
#[test]
fn noise_of_an_infinite_or_nan_argument_is_an_error_not_a_panic() {
    for text in ["if frame < 40  { clamp(noise(time/ 0), -1, 1) }", "noise(-1 / 0)", "noise(0 / 0, 3)", "noise(1, 1 / 0) * 0"] {
        let e = Expr::parse(text).unwrap_or_else(|err| panic!("{text}: {err}"));
        match e.eval(12.0, 24.0) {
            Ok(v) => assert!(v.is_finite(), "{text}: {v}"),
            Err(err) => assert!(!err.to_string().contains("panicked"), "{text}: {err}"),
        }
    }
}

#[test]
fn every_listed_function_is_callable_with_whole_and_decimal_arguments() {
    for (usage, help) in FUNCTIONS {
        assert!(!help.is_empty());
        let name = usage.split('(').next().unwrap_or(usage);
        let arity = usage.matches(',').count() + 1;
        for literal in ["3", "0.5"] {
            let call = format!("{name}({})", vec![literal; arity].join(", "));
            let expr = Expr::parse(&call).unwrap_or_else(|err| panic!("{call}: {err}"));
            // Some give NaN for these arguments (asin(3)); only an unresolved call would be wrong.
            if let Err(err) = expr.eval(0.0, 24.0) {
                assert!(err.message.starts_with("gives NaN"), "{call}: {err}");
            }
        }
    }
}

#[test]
fn integer_arguments_work_everywhere() {
    assert_eq!(at("clamp(frame, 0, 10)", 3.0), 3.0);
    assert_eq!(at("sin(0)", 0.0), 0.0);
    assert_eq!(at("floor(3)", 0.0), 3.0);
    assert_eq!(at("fit(5, 0, 10, 0, 100)", 0.0), 50.0);
    assert_eq!(at("ln(1)", 0.0), 0.0);
}

#[test]
fn syntax_error_has_column() {
    let err = parse_err("1 +* 2");
    assert_eq!(err.column, Some(4));
    assert!(err.message.contains("unexpected '*'"), "{err}");
    assert_eq!(err.to_string(), format!("at column 4: {}", err.message));
    // Columns count the artist's characters even after `^` became `**`.
    assert_eq!(parse_err("2^3 + framee").column, Some(7));
    let err = parse_err("2 ^^ 3");
    assert_eq!(err.column, Some(4));
    assert!(err.message.contains("'^'"), "{err}");
    // Pasted multi-line text counts from the start of the text.
    assert_eq!(parse_err("1 +\n* 2").column, Some(5));
    // Messages quote what the artist typed, not the rewritten `40.0` rhai saw.
    let err = parse_err("frame 40");
    assert_eq!((err.column, err.message.as_str()), (Some(7), "unexpected '40'"));
    assert_eq!(parse_err("1 + 2 3 + framee").column, Some(7));
    assert_eq!(parse_err("10 + 20 + framee").column, Some(11));
    assert_eq!(parse_err("0x10 + framee").column, Some(8));
    assert_eq!(parse_err("(frame + 1").column, Some(11));
    assert!(parse_err("frame +").message.contains("ends too early"));
    assert!(parse_err("  ").message.contains("empty"));
}

#[test]
fn unknown_variable_is_named_at_its_column() {
    let err = parse_err("framee");
    assert_eq!(err.column, Some(1));
    assert!(err.message.contains("unknown variable 'framee'"), "{err}");
    assert!(err.message.contains("did you mean 'frame'"), "{err}");
    assert!(err.message.contains("variables: frame, time, fps, pi"), "{err}");
    assert_eq!(parse_err("1 + speed * 2").column, Some(5));
}

#[test]
fn unknown_function_is_named_with_hint() {
    let err = parse_err("1 + foo(frame)");
    assert_eq!(err.column, Some(5));
    assert!(err.message.starts_with("unknown function 'foo'"), "{err}");
    assert!(err.message.contains("functions: sin, cos, tan"), "{err}");
    assert!(err.message.contains("fit, fit01"), "{err}");
    assert!(parse_err("nois(frame)").message.contains("did you mean 'noise'"));
    // Found even in a branch frame 0 does not take, and with space or a comment before the bracket.
    assert_eq!(parse_err("if frame > 10 { fooo(1) } else { 0 }").column, Some(17));
    assert!(parse_err("bar /* c */ (1)").message.contains("'bar'"));
    // Names rhai has but the artist vocabulary does not are refused too.
    assert!(parse_err("to_int(frame)").message.contains("unknown function 'to_int'"));
    assert!(parse_err("PI()").message.contains("unknown function 'PI'"));
}

#[test]
fn wrong_arguments_are_explained() {
    let err = parse_err("fit(1, 2)");
    assert_eq!(err.column, Some(1));
    assert!(err.message.contains("'fit'") && err.message.contains("fit(x, a, b, c, d)"), "{err}");
    let err = parse_err("1 + sin(\"a\")");
    assert!(err.message.contains("'sin' needs numbers, not text"), "{err}");
    assert_eq!(err.column, Some(5));
    let err = parse_err("min(1, \"a\")");
    assert!(err.message.contains("'min' needs numbers") && err.message.contains("min(a, b)"), "{err}");
    let err = parse_err("\"a\" + 1");
    assert!(err.message.contains("'+' cannot be used on text and a number"), "{err}");
    let err = parse_err("if frame { 1 } else { 2 }");
    assert!(err.message.contains("needs true/false here, not a number"), "{err}");
}

#[test]
fn messages_never_name_rust_types() {
    let texts = ["fit(1, 2)", "sin(\"a\")", "\"a\" + 1", "!frame", "min(1, \"a\")", "1 +* 2", "'a'", "1..2"];
    for text in texts {
        let err = Expr::parse(text).and_then(|expr| expr.eval(1.0, 24.0)).expect_err(text);
        for rust in ["i64", "f64", "ImmutableString", "&str", "char", "()"] {
            assert!(!err.message.contains(rust), "{text:?}: {err}");
        }
    }
}

#[test]
fn statements_are_refused() {
    for (text, word) in [
        ("while true { }", "while"),
        ("let x = 1", "let"),
        ("fn f() { 1 }", "fn"),
        ("print(1)", "print"),
        ("eval(\"1\")", "eval"),
        ("loop { }", "loop"),
        ("Fn(\"sin\")", "Fn"),
        ("1 + type_of(1)", "type_of"),
        ("switch frame { _ => 1 }", "switch"),
    ] {
        let err = parse_err(text);
        assert!(err.message.contains(&format!("'{word}' is not allowed in an expression")), "{text:?}: {err}");
    }
    assert!(parse_err("frame = 2").message.contains("unexpected '='"));
    assert!(parse_err("1; 2").message.contains("unexpected ';'"));
    // The words are only refused as words: inside a comment or as part of a name they are fine.
    assert_eq!(at("1 // while", 0.0), 1.0);
    assert!(parse_err("letter").message.contains("unknown variable 'letter'"));
}

#[test]
fn rewrites_leave_strings_comments_and_names_alone() {
    let prepared = prepare("\"2^3\" + 2^3 /* 4^5 */ + x1 + 1.5 + 1e3 + 0x1f // 6").expect("prepares");
    assert_eq!(prepared.source, "\"2^3\" + 2.0**3.0 /* 4^5 */ + x1 + 1.5 + 1e3 + 31.0 // 6");
    assert_eq!(prepared.columns.len(), prepared.source.chars().count());
    assert_eq!(at("1 /* a /* b */ c^2 */ + 2^2", 0.0), 5.0);
    assert!(parse_err("frame2").message.contains("unknown variable 'frame2'"));
    assert!(parse_err("1 + \"sin(\" + foo").message.contains("unknown variable 'foo'"));
}

#[test]
fn deep_nesting_is_a_clean_error_on_a_small_stack() {
    let inputs = [
        format!("{}1{}", "(".repeat(100_000), ")".repeat(100_000)),
        format!("{}1", "- ".repeat(100_000)),
        format!("{}1{}", "sin(".repeat(100_000), ")".repeat(100_000)),
        format!("{}1", "1+".repeat(100_000)),
    ];
    for text in inputs {
        let err = parse_on_small_stack(text).expect_err("refused");
        assert!(err.message.contains("characters long"), "{err}");
    }
    // Within the length limit the depth limit must catch it, before rhai recurses far.
    let inputs = [
        format!("{}1{}", "(".repeat(2000), ")".repeat(2000)),
        format!("{}1", "- ".repeat(2000)),
        format!("{}1", "!".repeat(4000)),
        format!("{}1{}", "sin(".repeat(800), ")".repeat(800)),
        format!("{}1", "1+".repeat(2000)),
        format!("{}1", "frame*".repeat(600)),
        format!("{}1{}", "if frame < 1 { ".repeat(140), " } else { 2 }".repeat(140)),
    ];
    for text in inputs {
        assert!(text.chars().count() <= MAX_CHARS);
        let err = parse_on_small_stack(text).expect_err("refused");
        assert!(err.message.contains("nested too deeply"), "{err}");
        assert!(err.column.is_some());
    }
    // The deepest accepted expressions still evaluate on the small stack.
    let deep_but_fine = format!("{}frame{}", "(".repeat(30), ")".repeat(30));
    assert_eq!(parse_on_small_stack(deep_but_fine), Ok(3.0));
    assert_eq!(parse_on_small_stack(format!("{}frame", "- ".repeat(60))), Ok(3.0));
    assert_eq!(parse_on_small_stack(format!("{}1", "frame + ".repeat(60))), Ok(181.0));
}

#[test]
fn length_limit() {
    let err = parse_err(&format!("1{}", " ".repeat(4999)));
    assert!(err.message.contains("is 5000 characters long; expressions are limited to 4096"), "{err}");
    assert_eq!(err.column, None);
    assert_eq!(at(&format!("1{}", " ".repeat(MAX_CHARS - 1)), 0.0), 1.0);
}

#[test]
fn results_that_are_not_numbers() {
    assert_eq!(parse_err("\"abc\"").message, "gives text, not a number");
    assert_eq!(eval_err("if frame < 1 { 1 } else { \"a\" }", 5.0).message, "gives text, not a number");
    assert!(eval_err("if frame < 1 { 1 }", 5.0).message.starts_with("gives nothing, not a number"));
    assert!(parse_err("1..2").message.starts_with("'..' cannot be used on a number and a number"));
}

#[test]
fn nan_and_infinity_name_the_frame() {
    assert_eq!(eval_err("ln(-1)", 12.5).message, "gives NaN at frame 12.5");
    assert_eq!(eval_err("0/0", 3.0).message, "gives NaN at frame 3");
    assert_eq!(eval_err("1/(frame - 2)", 2.0).message, "gives infinity at frame 2");
    assert_eq!(eval_err("-1/0", 2.0).message, "gives -infinity at frame 2");
    // A division by zero at frame 0 is not a parse error: other frames are fine.
    assert_eq!(at("1/frame", 4.0), 0.25);
}

#[test]
fn run_time_errors_in_plain_words() {
    assert_eq!(eval_err("7 % 0", 1.0).message, "gives NaN at frame 1");
    let err = eval_error(&EvalAltResult::ErrorArithmetic("Division by zero: 1 / 0".into(), Position::new(1, 11)), "1 / 0 ^ 2");
    assert_eq!(err, ExprError::new(Some(7), "cannot compute: division by zero: 1 / 0"));
    let err = eval_error(&EvalAltResult::ErrorTooManyOperations(Position::new(1, 5)), "frame + 1");
    assert_eq!(err, ExprError::new(Some(5), "takes too many steps to compute (the limit is 10000); simplify the expression"));
}

#[test]
fn expr_value_traits() {
    let a = Expr::parse("frame * 2").expect("parses");
    let b = Expr::parse("frame * 2").expect("parses");
    assert_eq!(a, b);
    assert_ne!(a, Expr::parse("frame*2").expect("parses"));
    assert_eq!(a.clone(), a);
    assert_eq!(a.text(), "frame * 2");
    assert_eq!(format!("{a:?}"), "Expr(\"frame * 2\")");
    assert_eq!(ExprError::new(None, "x").to_string(), "x");
    fn shared_across_threads<T: Send + Sync>() {}
    shared_across_threads::<Expr>();
    let handles: Vec<_> = (0..4).map(|i| std::thread::spawn(move || at("frame * 2", f64::from(i)))).collect();
    for (i, handle) in handles.into_iter().enumerate() {
        assert_eq!(handle.join().expect("thread"), 2.0 * i as f64);
    }
}

#[test]
fn vocabulary_is_documented() {
    let expected = [7.0, 7.0 / 24.0, 24.0, PI];
    assert_eq!(VARIABLES.len(), expected.len());
    for ((name, help), expected) in VARIABLES.iter().zip(expected) {
        assert_eq!(at(name, 7.0), expected, "{name}");
        assert!(!help.is_empty());
    }
    let names: Vec<&str> = function_names().collect();
    assert_eq!(names.iter().filter(|n| **n == "noise").count(), 1);
    assert!(names.len() >= 30);
}

proptest! {
    #[test]
    fn frame_round_trips(frame in -1.0e7f64..1.0e7) {
        let expr = Expr::parse("frame").expect("parses");
        prop_assert_eq!(expr.eval(frame, 24.0), Ok(frame));
    }

    #[test]
    fn fit_stays_in_new_range(
        frame in -1.0e4f64..1.0e4,
        a in -1.0e3f64..1.0e3,
        b in -1.0e3f64..1.0e3,
        c in -1.0e3f64..1.0e3,
        d in -1.0e3f64..1.0e3,
    ) {
        let expr = Expr::parse(&format!("fit(frame, {a:?}, {b:?}, {c:?}, {d:?})")).expect("parses");
        let v = expr.eval(frame, 24.0).expect("finite");
        prop_assert!(c.min(d) <= v && v <= c.max(d), "{} not in {}..{}", v, c, d);
    }

    #[test]
    fn noise_is_bounded_and_continuous(x in -1.0e4f64..1.0e4) {
        let expr = Expr::parse("noise(frame)").expect("parses");
        let n = expr.eval(x, 24.0).expect("finite");
        let m = expr.eval(x + 1e-6, 24.0).expect("finite");
        prop_assert!((-1.1..=1.1).contains(&n), "noise({}) = {}", x, n);
        prop_assert!((n - m).abs() < 1e-4, "noise jumps at {}: {} -> {}", x, n, m);
    }
}
