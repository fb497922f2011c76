//! Artist expressions for animated parameters.
//!
//! An artist types a small formula of the current `frame` into a parameter, the way Houdini's
//! `$F`/`fit()` or Nuke's expressions work: `0.5 + 0.2 * sin(time * 3)`,
//! `fit(frame, 0, 40, 0.2, 1.5)`, `noise(time * 2) * 0.3`, `if frame < 40 { 0 } else { 2.5 }`.
//!
//! [`Expr::parse`] checks the text once; [`Expr::eval`] then gives the value at any frame, cheaply
//! and from any thread. The evaluator is [rhai], set up as a pure calculator: no loops, variables,
//! function definitions, printing or I/O, bounded nesting and a bounded number of steps, so a
//! parameter can never hang, crash or touch anything outside the graph.
//!
//! Numbers behave as in HScript and Nuke rather than as in a programming language: every number is
//! a float, so `1/2` is 0.5; `^` is power and binds tighter than `*` (`1 + 2^3` is 9); `%` is the
//! remainder; comparisons give 1 or 0. [`VARIABLES`] and [`FUNCTIONS`] list everything an expression
//! can name.

use std::cell::RefCell;
use std::f64::consts::PI;
use std::fmt;
use std::sync::{Arc, LazyLock};

use noise::{NoiseFn, Perlin};
use rhai::packages::{ArithmeticPackage, BasicMathPackage, LogicPackage, Package};
use rhai::{AST, Dynamic, Engine, EvalAltResult, LexError, ParseError, ParseErrorType, Position, Scope};

use crate::typos::within_edits;

/// Longest accepted expression, in characters: a parameter field, not a program.
const MAX_CHARS: usize = 4096;
/// rhai's nesting limit. Brackets count two levels each and a chain `a + b + …` one per operator;
/// it keeps parsing, evaluation and dropping the AST far from the bottom of a 2 MiB thread stack.
const MAX_DEPTH: usize = 64;
/// Backstop against runaway evaluation; an expression within the length and depth limits uses far fewer.
const MAX_OPERATIONS: u64 = 10_000;
/// Where `parse` tries the expression once, to report calls rhai only resolves when they run.
const TRIAL_FRAME: f64 = 0.0;
const TRIAL_FPS: f64 = 24.0;

/// Names artists can use as variables, each with one line of help.
pub const VARIABLES: &[(&str, &str)] = &[
    ("frame", "the current frame; fractional between frames during simulation sub-steps"),
    ("time", "the current time in seconds: frame / fps"),
    ("fps", "frames per second of the timeline"),
    ("pi", "3.14159…, half a turn in radians"),
];

/// Functions artists can call, each as a call pattern with one line of help.
///
/// This is also the whitelist `parse` checks calls against, so a name missing here cannot be called.
pub const FUNCTIONS: &[(&str, &str)] = &[
    ("sin(x)", "sine of x radians"),
    ("cos(x)", "cosine of x radians"),
    ("tan(x)", "tangent of x radians"),
    ("asin(x)", "arc sine, in radians"),
    ("acos(x)", "arc cosine, in radians"),
    ("atan(x)", "arc tangent, in radians"),
    ("atan(y, x)", "angle of the point (x, y) in radians, like atan2"),
    ("sqrt(x)", "square root"),
    ("pow(a, b)", "a to the power b, same as a ^ b"),
    ("exp(x)", "e to the power x"),
    ("ln(x)", "natural logarithm"),
    ("log(x)", "base-10 logarithm"),
    ("log(x, base)", "logarithm in the given base"),
    ("abs(x)", "absolute value"),
    ("sign(x)", "-1, 0 or 1 by the sign of x"),
    ("floor(x)", "largest whole number not above x"),
    ("ceil(x)", "smallest whole number not below x"),
    ("round(x)", "nearest whole number, halves away from zero"),
    ("frac(x)", "x - floor(x), in [0, 1): turns a rising value into a loop"),
    ("min(a, b)", "the smaller of a and b"),
    ("max(a, b)", "the larger of a and b"),
    ("clamp(x, lo, hi)", "x limited to lo..hi"),
    ("fit(x, a, b, c, d)", "x from a..b to c..d, clamped (Houdini's fit)"),
    ("fit01(x, c, d)", "x from 0..1 to c..d, clamped"),
    ("mix(a, b, t)", "a + (b - a) * t, not clamped (GLSL's mix)"),
    ("lerp(a, b, t)", "same as mix(a, b, t)"),
    ("smoothstep(e0, e1, x)", "0 below e0, 1 above e1, a smooth S-curve between (GLSL's smoothstep)"),
    ("step(edge, x)", "0 where x < edge, else 1"),
    ("pulse(x, start, end)", "1 where start <= x <= end, else 0"),
    ("noise(x)", "smooth Perlin noise in about -1..1, repeating every 256"),
    ("noise(x, seed)", "noise(x) from a different pattern for each whole-number seed"),
    ("rand(x)", "a random number in [0, 1) picked by x: the same x always gives the same number"),
    ("radians(d)", "degrees to radians"),
    ("degrees(r)", "radians to degrees"),
];

/// Words that would turn a formula into a program (separated by spaces), refused with a plain message
/// before rhai sees them.
/// rhai's expression mode rejects most already; listing them gives one clear message and also covers
/// the callable ones (`print`, `eval`, `Fn`, …) that rhai resolves only at run time.
const NOT_ALLOWED: &str = "let const fn while loop for do until break continue return throw try catch import export switch in \
    print debug eval Fn call curry type_of is_def_var is_def_fn is_shared this global private";

/// Why an expression cannot be parsed or evaluated. `column` is 1-based within the expression text when known.
#[derive(Clone, Debug, PartialEq)]
pub struct ExprError {
    /// 1-based character column in the expression text where the problem is, when known.
    pub column: Option<usize>,
    /// What is wrong, in words for artists.
    pub message: String,
}

impl ExprError {
    fn new(column: Option<usize>, message: impl Into<String>) -> Self {
        ExprError { column, message: message.into() }
    }
}

impl fmt::Display for ExprError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.column {
            Some(column) => write!(f, "at column {column}: {}", self.message),
            None => f.write_str(&self.message),
        }
    }
}

impl std::error::Error for ExprError {}

/// A parsed expression of `frame`, `time` and `fps`.
///
/// Cloning is cheap (the compiled form is shared) and an `Expr` can be evaluated from many threads at once.
#[derive(Clone)]
pub struct Expr {
    inner: Arc<Compiled>,
}

struct Compiled {
    text: String,
    ast: AST,
}

impl fmt::Debug for Expr {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_tuple("Expr").field(&self.inner.text).finish()
    }
}

impl PartialEq for Expr {
    fn eq(&self, other: &Self) -> bool {
        self.inner.text == other.inner.text
    }
}

impl Expr {
    /// Parses `text`, refusing anything that is not a formula of [`VARIABLES`] and [`FUNCTIONS`].
    ///
    /// Besides syntax this catches unknown variables and functions anywhere in the text (also in an
    /// `if` branch that frame 0 does not take), wrong arguments to a function, and text in place of a number.
    pub fn parse(text: &str) -> Result<Expr, ExprError> {
        let length = text.chars().count();
        if length > MAX_CHARS {
            let message = format!("the expression is {length} characters long; expressions are limited to {MAX_CHARS}");
            return Err(ExprError::new(None, message));
        }
        if text.trim().is_empty() {
            return Err(ExprError::new(None, "the expression is empty"));
        }
        let prepared = prepare(text)?;
        let ast = ENGINE.compile_expression_with_scope(&base_scope(), &prepared.source).map_err(|err| parse_error(&err, text))?;
        let expr = Expr { inner: Arc::new(Compiled { text: text.to_owned(), ast }) };
        // rhai resolves calls and checks types only when they run, so a call with wrong arguments (or
        // anything the whitelist scan let through) or text where a number belongs shows up here. Every
        // variable is a number, so such errors do not depend on the frame; those that do (a NaN at
        // some frames) are left to `eval`.
        match run(&expr.inner.ast, TRIAL_FRAME, TRIAL_FPS) {
            Err(err) if is_type_error(&err) => Err(eval_error(&err, text)),
            Ok(value) if value.is_string() || value.is_char() => Err(ExprError::new(None, "gives text, not a number")),
            _ => Ok(expr),
        }
    }

    /// The value at `frame` (may be fractional: simulation sub-steps) with `time = frame / fps`.
    ///
    /// A true/false result becomes 1 or 0. A NaN or infinite result is an error naming the frame, so a
    /// bad value never flows silently into a simulation.
    pub fn eval(&self, frame: f64, fps: f64) -> Result<f64, ExprError> {
        let value = run(&self.inner.ast, frame, fps).map_err(|err| eval_error(&err, &self.inner.text))?;
        let number = to_number(&value).map_err(|message| ExprError::new(None, message))?;
        if number.is_finite() {
            return Ok(number);
        }
        let what = if number.is_nan() {
            "NaN"
        } else if number > 0.0 {
            "infinity"
        } else {
            "-infinity"
        };
        Err(ExprError::new(None, format!("gives {what} at frame {frame}")))
    }

    /// The expression exactly as the artist typed it.
    pub fn text(&self) -> &str {
        &self.inner.text
    }
}

// ---------------------------------------------------------------------------------------------
// The engine

/// One engine for every expression: building it registers a few hundred functions, and with the
/// `sync` feature it is shared read-only across threads (a `LazyLock` read is one atomic load).
static ENGINE: LazyLock<Engine> = LazyLock::new(build_engine);

/// The 3-D Perlin field `noise` samples. Building it shuffles a permutation table, so it is built once.
static PERLIN: LazyLock<Perlin> = LazyLock::new(|| Perlin::new(0));

fn build_engine() -> Engine {
    // `new_raw` has no print, debug or I/O; only the maths packages are added back.
    let mut engine = Engine::new_raw();
    ArithmeticPackage::new().register_into_engine(&mut engine);
    BasicMathPackage::new().register_into_engine(&mut engine);
    LogicPackage::new().register_into_engine(&mut engine);
    engine.set_max_expr_depths(MAX_DEPTH);
    engine.set_max_operations(MAX_OPERATIONS);
    engine.set_max_string_size(256);
    // Unknown variables become parse errors with their column instead of run-time surprises.
    engine.set_strict_variables(true);
    // Fast operators: arithmetic and comparisons on numbers run rhai's built-ins directly instead of
    // searching the registered functions first, which halves the cost of a typical expression. They
    // would give integer semantics (`1/2` = 0, `^` as XOR) for integer operands, but `prepare` writes
    // every number literal as a float and every variable and function result is a float, so no
    // integer ever reaches an operator and no operator overloads are needed.
    engine.set_fast_operators(true);
    // `prepare` refuses these first with a clearer message; disabling them here means even a
    // text that bypassed it could not call out of the calculator.
    for word in NOT_ALLOWED.split_whitespace() {
        engine.disable_symbol(word);
    }
    register_functions(&mut engine);
    engine
}

/// Registers a float function twice: with `f64` parameters, which every call from an expression
/// hits directly (its literals are floats), and with `Dynamic` ones, which rhai falls back to for any
/// other argument types: whole numbers (`i64`) still work should one ever arrive, and anything that is
/// not a number gets a plain message instead of "function not found".
macro_rules! math_fn {
    ($engine:expr, $name:literal, |$($arg:ident),+| $body:expr) => {{
        $engine.register_fn($name, |$($arg: f64),+| -> f64 { $body });
        $engine.register_fn($name, |$($arg: Dynamic),+| -> Result<f64, Box<EvalAltResult>> {
            $(let $arg = number_arg($name, &$arg)?;)+
            Ok($body)
        });
    }};
}

fn register_functions(engine: &mut Engine) {
    // rhai's BasicMathPackage has sin..ln, log, floor and round for `f64` only; the `f64` versions
    // here replace those one for one (same maths), so this table alone defines the artist functions.
    // abs, min and max are left to rhai, which has every whole/decimal mix of them.
    math_fn!(engine, "sin", |x| x.sin());
    math_fn!(engine, "cos", |x| x.cos());
    math_fn!(engine, "tan", |x| x.tan());
    math_fn!(engine, "asin", |x| x.asin());
    math_fn!(engine, "acos", |x| x.acos());
    math_fn!(engine, "atan", |x| x.atan());
    math_fn!(engine, "atan", |y, x| y.atan2(x));
    math_fn!(engine, "sqrt", |x| x.sqrt());
    math_fn!(engine, "pow", |a, b| a.powf(b));
    math_fn!(engine, "exp", |x| x.exp());
    math_fn!(engine, "ln", |x| x.ln());
    math_fn!(engine, "log", |x| x.log10());
    math_fn!(engine, "log", |x, base| x.log(base));
    // rhai's `sign` gives an integer and fails on NaN; this one lets NaN through to `eval`'s frame-named error.
    math_fn!(engine, "sign", |x| if x == 0.0 || x.is_nan() { x } else { x.signum() });
    math_fn!(engine, "floor", |x| x.floor());
    math_fn!(engine, "ceil", |x| x.ceil());
    math_fn!(engine, "round", |x| x.round());
    math_fn!(engine, "frac", |x| x - x.floor());
    math_fn!(engine, "clamp", |x, lo, hi| clamp(x, lo, hi));
    math_fn!(engine, "fit", |x, a, b, c, d| fit(x, a, b, c, d));
    math_fn!(engine, "fit01", |x, c, d| fit(x, 0.0, 1.0, c, d));
    math_fn!(engine, "mix", |a, b, t| a + (b - a) * t);
    math_fn!(engine, "lerp", |a, b, t| a + (b - a) * t);
    math_fn!(engine, "smoothstep", |e0, e1, x| smoothstep(e0, e1, x));
    math_fn!(engine, "step", |edge, x| step(edge, x));
    math_fn!(engine, "pulse", |x, start, end| if start <= x && x <= end { 1.0 } else { 0.0 });
    math_fn!(engine, "noise", |x| perlin(x, 0.0));
    math_fn!(engine, "noise", |x, seed| perlin(x, seed));
    math_fn!(engine, "rand", |x| rand(x));
    math_fn!(engine, "radians", |d| d.to_radians());
    math_fn!(engine, "degrees", |r| r.to_degrees());
}

/// A function argument as `f64`: whole numbers convert, anything else is a plain-words error.
fn number_arg(function: &str, value: &Dynamic) -> Result<f64, Box<EvalAltResult>> {
    if let Ok(x) = value.as_float() {
        return Ok(x);
    }
    if let Ok(i) = value.as_int() {
        return Ok(i as f64);
    }
    let message = format!("'{function}' needs numbers, not {}", plain_type(value.type_name()));
    Err(EvalAltResult::ErrorRuntime(message.into(), Position::NONE).into())
}

// ---------------------------------------------------------------------------------------------
// The artist functions

/// `x` limited to `lo..hi`. Unlike `f64::clamp` it never panics: with `lo > hi` it gives `hi`.
fn clamp(x: f64, lo: f64, hi: f64) -> f64 {
    x.max(lo).min(hi)
}

/// Houdini's `fit`: `x` mapped from `omin..omax` to `nmin..nmax`, clamped to the new range (also
/// `math.fit`'s, so a formula moved into nodes keeps its numbers).
pub(crate) fn fit(x: f64, omin: f64, omax: f64, nmin: f64, nmax: f64) -> f64 {
    // An empty old range is a step at `omin` rather than 0/0.
    let t = if omax == omin { step(omin, x) } else { clamp((x - omin) / (omax - omin), 0.0, 1.0) };
    // The final clamp keeps rounding in `nmin + t * (nmax - nmin)` from stepping an ulp outside the range.
    clamp(nmin + t * (nmax - nmin), nmin.min(nmax), nmin.max(nmax))
}

fn step(edge: f64, x: f64) -> f64 {
    if x < edge { 0.0 } else { 1.0 }
}

/// GLSL's `smoothstep`; with `e0 == e1` (undefined in GLSL) a plain step instead of 0/0.
fn smoothstep(e0: f64, e1: f64, x: f64) -> f64 {
    if e0 == e1 {
        return step(e0, x);
    }
    let t = clamp((x - e0) / (e1 - e0), 0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// Perlin noise along a line through the 3-D field.
///
/// The line sits at y = 0.5, z = 0.25 because Perlin noise is zero at every whole-number lattice
/// point; the field repeats every 256 on each axis, so wrapping `x` into `[0, 256)` keeps the output
/// within range for huge `x` (the crate's integer corner would saturate there) without a seam.
/// A seed moves the line to another whole-number cell in y and z, giving an unrelated pattern;
/// seed 0 is the plain `noise(x)`. Also `math.noise`'s.
pub(crate) fn perlin(x: f64, seed: f64) -> f64 {
    // An infinite or NaN `x` (`noise(time / 0)`) has no place on the line; the crate would panic
    // turning it into a lattice cell. NaN makes the expression's result an error, naming it.
    if !x.is_finite() {
        return f64::NAN;
    }
    let cell = (seed.floor() as i64 as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    let y = 0.5 + (cell >> 56) as f64;
    let z = 0.25 + ((cell >> 48) & 0xff) as f64;
    PERLIN.get([x.rem_euclid(256.0), y, z])
}

/// A hash of `x` to `[0, 1)`: SplitMix64's finaliser on the bits of `x`, top 53 bits as the fraction.
fn rand(x: f64) -> f64 {
    // `+ 0.0` turns -0.0 into 0.0 so both zeros give the same number.
    let mut h = (x + 0.0).to_bits().wrapping_add(0x9E37_79B9_7F4A_7C15);
    h = (h ^ (h >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    h = (h ^ (h >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    h ^= h >> 31;
    (h >> 11) as f64 / (1u64 << 53) as f64
}

// ---------------------------------------------------------------------------------------------
// Running

/// Number of variables in [`base_scope`].
const SCOPE_LEN: usize = 4;

/// The variables an expression sees, with placeholder values. `pi` is a constant, so the optimiser
/// folds it into the AST at parse time.
fn base_scope() -> Scope<'static> {
    let mut scope = Scope::with_capacity(SCOPE_LEN);
    scope.push("frame", TRIAL_FRAME).push("time", TRIAL_FRAME / TRIAL_FPS).push("fps", TRIAL_FPS).push_constant("pi", PI);
    scope
}

thread_local! {
    /// One scope per thread, reused: a fresh `Scope` allocates its name strings, which would double
    /// the cost of evaluating a short expression.
    static SCOPE: RefCell<Scope<'static>> = RefCell::new(base_scope());
}

fn run(ast: &AST, frame: f64, fps: f64) -> Result<Dynamic, Box<EvalAltResult>> {
    SCOPE.with(|cell| match cell.try_borrow_mut() {
        Ok(mut scope) => run_in(&mut scope, ast, frame, fps),
        // Only reachable if an expression were evaluated from inside another one's evaluation.
        Err(_) => run_in(&mut base_scope(), ast, frame, fps),
    })
}

fn run_in(scope: &mut Scope<'static>, ast: &AST, frame: f64, fps: f64) -> Result<Dynamic, Box<EvalAltResult>> {
    // An expression cannot declare variables, but keeping the scope at its fixed size makes that
    // invariant local instead of relying on rhai's expression mode.
    scope.rewind(SCOPE_LEN);
    for (name, value) in [("frame", frame), ("time", frame / fps), ("fps", fps)] {
        if let Some(slot) = scope.get_mut(name) {
            *slot = Dynamic::from_float(value);
        }
    }
    ENGINE.eval_ast_with_scope::<Dynamic>(scope, ast)
}

/// Errors about the kinds of values involved rather than their amounts; `number_arg` reports through
/// `ErrorRuntime`, the only source of it since `throw` is refused.
fn is_type_error(err: &EvalAltResult) -> bool {
    matches!(
        err,
        EvalAltResult::ErrorFunctionNotFound(..) | EvalAltResult::ErrorRuntime(..) | EvalAltResult::ErrorMismatchDataType(..)
    )
}

/// The result as a number: whole numbers and true/false convert (true is 1); text and the like do not.
fn to_number(value: &Dynamic) -> Result<f64, String> {
    if let Ok(x) = value.as_float() {
        Ok(x)
    } else if let Ok(i) = value.as_int() {
        Ok(i as f64)
    } else if let Ok(b) = value.as_bool() {
        Ok(if b { 1.0 } else { 0.0 })
    } else if value.is_unit() {
        // The usual cause is an `if` without an `else` whose condition is false.
        Err("gives nothing, not a number (does an `if` lack its `else`?)".to_owned())
    } else {
        Err(format!("gives {}, not a number", plain_type(value.type_name())))
    }
}

// ---------------------------------------------------------------------------------------------
// Checking the text before rhai

/// The text rhai compiles, and where each of its characters came from in the artist's text.
///
/// Two rewrites give HScript semantics with rhai's fast built-in operators: `^` becomes `**` (rhai's
/// `^` is XOR on integers and binds looser than `<`, so `1 + 2^3` would be 27), and a whole-number
/// literal becomes a float literal (`40` → `40.0`, `0x10` → `16.0`), so `1/2` is 0.5 and `2^-1` is 0.5.
struct Prepared {
    source: String,
    /// 1-based column in the artist's text of each character of `source`.
    columns: Vec<usize>,
}

impl Prepared {
    /// Appends `chars[from..to]` unchanged.
    fn copy(&mut self, chars: &[char], from: usize, to: usize) {
        self.source.extend(&chars[from..to]);
        self.columns.extend(from + 1..=to);
    }

    /// Appends `text` written in place of the artist's character at `column`.
    fn insert(&mut self, text: &str, column: usize) {
        self.source.push_str(text);
        self.columns.extend(text.chars().map(|_| column));
    }
}

/// One pass over the text that makes the rewrites above and refuses statements and unknown function names.
///
/// Checking calls here against [`FUNCTIONS`] finds a misspelt name in any branch, not only the one
/// the trial evaluation takes. Strings and comments are copied untouched. Columns count characters,
/// as rhai's positions do.
fn prepare(text: &str) -> Result<Prepared, ExprError> {
    let chars: Vec<char> = text.chars().collect();
    let mut out = Prepared { source: String::with_capacity(text.len() + 16), columns: Vec::with_capacity(chars.len() + 16) };
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        if c == '^' {
            out.insert("**", i + 1);
            i += 1;
        } else if c.is_ascii_digit() {
            i = push_number(&mut out, &chars, i);
        } else {
            let end = if c.is_ascii_alphabetic() || c == '_' {
                let end = scan_while(&chars, i, |c| c.is_ascii_alphanumeric() || c == '_');
                let word: String = chars[i..end].iter().collect();
                check_word(&word, i + 1, next_significant(&chars, end))?;
                end
            } else {
                literal_or_comment_end(&chars, i).unwrap_or(i + 1)
            };
            out.copy(&chars, i, end);
            i = end;
        }
    }
    Ok(out)
}

/// Appends the number literal starting at `i` as a float literal; returns the index past it.
fn push_number(out: &mut Prepared, chars: &[char], i: usize) -> usize {
    let (end, kind) = number_token(chars, i);
    match kind {
        Number::Float => out.copy(chars, i, end),
        Number::Whole => {
            out.copy(chars, i, end);
            out.insert(".0", end);
        }
        Number::Radix(radix) => {
            let digits: String = chars[i + 2..end].iter().filter(|&&c| c != '_').collect();
            match i64::from_str_radix(&digits, radix) {
                Ok(value) => out.insert(&format!("{value}.0"), i + 1),
                // Left for rhai to report as malformed.
                Err(_) => out.copy(chars, i, end),
            }
        }
    }
    end
}

enum Number {
    Whole,
    Float,
    /// `0x`, `0o` or `0b` with the radix.
    Radix(u32),
}

/// The end and kind of the number literal starting at `i`, following rhai's number syntax.
fn number_token(chars: &[char], i: usize) -> (usize, Number) {
    let digits = |from: usize| scan_while(chars, from, |c| c.is_ascii_digit() || c == '_');
    let radix = match (chars[i], chars.get(i + 1)) {
        ('0', Some('x' | 'X')) => Some(16),
        ('0', Some('o' | 'O')) => Some(8),
        ('0', Some('b' | 'B')) => Some(2),
        _ => None,
    };
    if let Some(radix) = radix {
        return (scan_while(chars, i + 2, |c| c.is_ascii_alphanumeric() || c == '_'), Number::Radix(radix));
    }
    let mut end = digits(i);
    let mut kind = Number::Whole;
    if chars.get(end) == Some(&'.') && chars.get(end + 1).is_some_and(char::is_ascii_digit) {
        (end, kind) = (digits(end + 1), Number::Float);
    }
    if matches!(chars.get(end), Some('e' | 'E')) {
        let sign = usize::from(matches!(chars.get(end + 1), Some('+' | '-')));
        if chars.get(end + 1 + sign).is_some_and(char::is_ascii_digit) {
            (end, kind) = (digits(end + 1 + sign), Number::Float);
        }
    }
    (end, kind)
}

fn scan_while(chars: &[char], from: usize, keep: impl Fn(char) -> bool) -> usize {
    chars[from..].iter().position(|&c| !keep(c)).map_or(chars.len(), |n| from + n)
}

/// If a string, character literal or comment starts at `i`, the index just past its end.
fn literal_or_comment_end(chars: &[char], i: usize) -> Option<usize> {
    let next = chars.get(i + 1).copied();
    match chars[i] {
        quote @ ('"' | '\'' | '`') => {
            let mut j = i + 1;
            while j < chars.len() {
                match chars[j] {
                    '\\' => j += 2,
                    c if c == quote => return Some(j + 1),
                    _ => j += 1,
                }
            }
            Some(chars.len())
        }
        '/' if next == Some('/') => Some(scan_while(chars, i, |c| c != '\n')),
        '/' if next == Some('*') => {
            // rhai's block comments nest.
            let (mut depth, mut j) = (0usize, i);
            while j < chars.len() {
                match (chars[j], chars.get(j + 1).copied()) {
                    ('/', Some('*')) => (depth, j) = (depth + 1, j + 2),
                    ('*', Some('/')) if depth == 1 => return Some(j + 2),
                    ('*', Some('/')) => (depth, j) = (depth - 1, j + 2),
                    _ => j += 1,
                }
            }
            Some(chars.len())
        }
        _ => None,
    }
}

/// The first character at or after `i` that is not whitespace or inside a comment.
fn next_significant(chars: &[char], mut i: usize) -> Option<char> {
    loop {
        i = scan_while(chars, i, char::is_whitespace);
        match chars.get(i) {
            Some('/') if matches!(chars.get(i + 1), Some('/' | '*')) => i = literal_or_comment_end(chars, i)?,
            c => return c.copied(),
        }
    }
}

fn check_word(word: &str, column: usize, next: Option<char>) -> Result<(), ExprError> {
    if NOT_ALLOWED.split_whitespace().any(|w| w == word) {
        let message =
            format!("'{word}' is not allowed in an expression: write a formula, e.g. if frame < 40 {{ 0 }} else {{ 2.5 }}");
        return Err(ExprError::new(Some(column), message));
    }
    let keyword = matches!(word, "if" | "else" | "true" | "false");
    if next == Some('(') && !keyword && !function_names().any(|name| name == word) {
        return Err(ExprError::new(Some(column), unknown_function(word)));
    }
    Ok(())
}

// ---------------------------------------------------------------------------------------------
// Errors in plain words

/// Distinct function names in [`FUNCTIONS`] order.
fn function_names() -> impl Iterator<Item = &'static str> {
    FUNCTIONS
        .iter()
        .enumerate()
        .map(|(i, (usage, _))| (i, usage.split('(').next().unwrap_or(usage)))
        .filter(|&(i, name)| !FUNCTIONS[..i].iter().any(|(usage, _)| usage.split('(').next() == Some(name)))
        .map(|(_, name)| name)
}

fn unknown_function(name: &str) -> String {
    let names: Vec<&str> = function_names().collect();
    format!("unknown function '{name}'{}; functions: {}", did_you_mean(name, &names), names.join(", "))
}

fn unknown_variable(name: &str) -> String {
    let names: Vec<&str> = VARIABLES.iter().map(|(name, _)| *name).collect();
    format!("unknown variable '{name}'{}; variables: {}", did_you_mean(name, &names), names.join(", "))
}

/// " (did you mean 'frame'?)" for the closest name within two edits, else nothing.
fn did_you_mean(name: &str, candidates: &[&str]) -> String {
    let best = candidates.iter().filter_map(|c| Some((within_edits(name, c, 2)?, *c))).min_by_key(|&(d, _)| d);
    best.map_or_else(String::new, |(_, c)| format!(" (did you mean '{c}'?)"))
}

/// A rhai type name as artists would say it: no `i64`/`f64`/`ImmutableString` in messages.
fn plain_type(name: &str) -> &'static str {
    let name = name.trim();
    let numeric = |n: &str| {
        n.strip_prefix(['i', 'u', 'f']).is_some_and(|bits| !bits.is_empty() && bits.chars().all(|c| c.is_ascii_digit()))
    };
    match name {
        n if numeric(n) => "a number",
        "bool" => "true/false",
        "()" => "nothing",
        "char" | "string" => "text",
        n if n.contains("str") || n.contains("String") => "text",
        n if n.contains("Range") || n.contains("range") => "a range",
        _ => "a value",
    }
}

/// Replaces rhai's type names in a message rhai wrote, for the rarer errors mapped wholesale.
fn plainer(message: &str) -> String {
    let message = message.split(" (line ").next().unwrap_or(message);
    let mut out = message.replace("&str | ImmutableString | String", "text").replace("ImmutableString", "text");
    for number in ["i64", "f64", "i32", "f32"] {
        out = out.replace(number, "number");
    }
    lower_first(&out)
}

fn lower_first(message: &str) -> String {
    let mut chars = message.chars();
    chars.next().map_or_else(String::new, |first| first.to_lowercase().chain(chars).collect())
}

/// The 1-based column in the artist's text of a rhai position in the rewritten source.
fn locate(text: &str, position: Position) -> Option<usize> {
    locate_span(text, position, 1).map(|(first, _)| first)
}

/// Columns in the artist's text of the first and last of `len` rewritten characters at a rhai position.
fn locate_span(text: &str, position: Position, len: usize) -> Option<(usize, usize)> {
    let (line, column) = (position.line()?, position.position()?);
    let prepared = prepare(text).ok()?;
    // Expressions are normally one line; for pasted multi-line text count from the start of the text.
    let before: usize = prepared.source.split('\n').take(line - 1).map(|l| l.chars().count() + 1).sum();
    let first = before + column;
    // Past the end (an expression that stops too early) maps past the end of the artist's text.
    let original = |rewritten: usize| match prepared.columns.get(rewritten - 1) {
        Some(&column) => column,
        None => text.chars().count() + rewritten - prepared.columns.len(),
    };
    Some((original(first), original(first + len.max(1) - 1)))
}

/// What the artist typed where rhai quotes `token` from the rewritten source (`40` for `40.0`, `^` for `**`).
fn typed_token(text: &str, position: Position, token: &str) -> Option<String> {
    let (first, last) = locate_span(text, position, token.chars().count())?;
    (first <= last && last <= text.chars().count()).then(|| text.chars().skip(first - 1).take(last + 1 - first).collect())
}

fn parse_error(err: &ParseError, text: &str) -> ExprError {
    let column = locate(text, err.1);
    let message = match err.0.as_ref() {
        ParseErrorType::BadInput(LexError::UnexpectedInput(token)) => {
            // rhai quotes the rewritten source (`40.0`, `**`); quote what the artist typed.
            format!("unexpected '{}'", typed_token(text, err.1, token).unwrap_or_else(|| token.clone()))
        }
        ParseErrorType::UnexpectedEOF => "the expression ends too early".to_owned(),
        ParseErrorType::UnknownOperator(op) => format!("unknown operator '{op}'"),
        ParseErrorType::MissingToken(token, why) => format!("missing '{token}' {why}"),
        ParseErrorType::MismatchedType(expected, actual) => format!("expected {expected}, not {actual}"),
        ParseErrorType::VariableUndefined(name) => unknown_variable(name),
        ParseErrorType::ExprTooDeep => {
            format!("the expression is nested too deeply: more than {MAX_DEPTH} levels of brackets, calls or chained operators")
        }
        ParseErrorType::Reserved(word) => format!("'{word}' is not allowed in an expression"),
        other => plainer(&other.to_string()),
    };
    ExprError::new(column, message)
}

fn eval_error(err: &EvalAltResult, text: &str) -> ExprError {
    let column = locate(text, err.position());
    let message = match err {
        EvalAltResult::ErrorFunctionNotFound(signature, _) => call_error(signature),
        EvalAltResult::ErrorTooManyOperations(_) => {
            format!("takes too many steps to compute (the limit is {MAX_OPERATIONS}); simplify the expression")
        }
        EvalAltResult::ErrorArithmetic(message, _) => format!("cannot compute: {}", plainer(message)),
        EvalAltResult::ErrorMismatchDataType(expected, actual, _) => {
            format!("needs {} here, not {}", plain_type(expected), plain_type(actual))
        }
        EvalAltResult::ErrorRuntime(message, _) => message.to_string(),
        EvalAltResult::ErrorVariableNotFound(name, _) => unknown_variable(name),
        EvalAltResult::ErrorDataTooLarge(..) => "text in the expression grows too long".to_owned(),
        other => plainer(&other.to_string()),
    };
    ExprError::new(column, message)
}

/// Explains a call rhai could not resolve, from its signature such as `fit (i64, i64)`.
fn call_error(signature: &str) -> String {
    let (name, args) = signature.split_once(" (").unwrap_or((signature, ")"));
    let args: Vec<&str> = args.trim_end_matches(')').split(", ").filter(|a| !a.is_empty()).collect();
    let kinds: Vec<&str> = args.iter().map(|a| plain_type(a)).collect();
    let usages: Vec<&str> = FUNCTIONS.iter().map(|(usage, _)| *usage).filter(|u| u.split('(').next() == Some(name)).collect();
    let is_name = name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_');
    if !is_name {
        return format!("'{name}' cannot be used on {}", kinds.join(" and "));
    }
    if usages.is_empty() {
        return unknown_function(name);
    }
    let arity_matches = usages.iter().any(|u| u.matches(',').count() + 1 == args.len());
    if arity_matches {
        format!("'{name}' needs numbers, not {}; use {}", kinds.join(", "), usages.join(" or "))
    } else {
        format!("'{name}' takes different arguments than the {} given; use {}", args.len(), usages.join(" or "))
    }
}

#[cfg(test)]
mod tests;
