//! The rule that keeps algorithms apart from ports, checked per function: in a node crate, only a
//! node's cook side may use `port!`, `NodeError` or a node struct. The cook side is
//! - the body of an `impl` whose type is a node struct or its outputs (`impl Cook for Crop`, the
//!   node's own helper methods `impl Crop { fn settings(&self) .. }`),
//! - the impls of a port group: a `ports!` struct, or a type with a hand-written `Field` impl
//!   (describing and reading ports is what it is for),
//! - the impls of a lazy clip, a type with `impl FrameSource for ..` (its `frame` is the per-frame
//!   cook of a clip a node returned, and core's trait returns `NodeError`),
//! - `impl .. for NodeError` (turning an algorithm's error into the node's),
//! - the crate root, which registers the nodes.
//!
//! Every other function is an algorithm: it takes plain values, returns its own error, and the
//! cook maps that error to the port it concerns.

use std::collections::BTreeSet;

/// One function with a body: its name, the header of the `impl` it sits in (if any) and its text
/// from `fn` to the closing brace.
struct Function<'a> {
    name: String,
    within: Option<&'a str>,
    body: &'a str,
}

/// The byte offset just past the `{` that opens the item starting at `from` (a `fn` or an
/// `impl`), or `None` when the item has no body (a trait method's `fn f();`). Brackets are
/// followed so a `[f32; 4]` in a signature is not taken for the end of a declaration.
fn body_open(code: &str, from: usize) -> Option<usize> {
    let mut depth = 0i32;
    for (i, c) in code[from..].char_indices() {
        match c {
            '(' | '[' => depth += 1,
            ')' | ']' => depth -= 1,
            ';' if depth == 0 => return None,
            '{' if depth == 0 => return Some(from + i + 1),
            _ => {}
        }
    }
    None
}

/// Whether `word` starts at `at` as a whole word (not inside a longer identifier).
fn word_at(code: &str, at: usize, word: &str) -> bool {
    let ident = |c: char| c.is_ascii_alphanumeric() || c == '_';
    code[at..].starts_with(word)
        && !code[..at].chars().next_back().is_some_and(ident)
        && !code[at + word.len()..].chars().next().is_some_and(ident)
}

/// The top-level functions of `code` (shipped code, comments and strings blanked), each with the
/// `impl` it belongs to. A function nested in another is part of the outer one's body.
fn functions(code: &str) -> Vec<Function<'_>> {
    // An open brace: what it opened (an impl header, a function's start and name, or neither).
    enum Open<'a> {
        Impl(&'a str),
        Fn(usize, String),
        Other,
    }
    let mut stack: Vec<Open> = Vec::new();
    let mut pending: Option<(usize, Open)> = None; // an item whose `{` is still ahead
    let mut out = Vec::new();
    let bytes = code.as_bytes();
    let mut i = 0;
    while i < code.len() {
        if pending.is_none() && (word_at(code, i, "fn") || word_at(code, i, "impl")) {
            let is_fn = code[i..].starts_with("fn");
            if let Some(open) = body_open(code, i) {
                let item = if is_fn {
                    let name: String =
                        code[i + 2..].trim_start().chars().take_while(|c| c.is_alphanumeric() || *c == '_').collect();
                    Open::Fn(i, name)
                } else {
                    Open::Impl(&code[i..open - 1])
                };
                pending = Some((open - 1, item));
            }
        }
        // A brace in a char literal ('{') is not one.
        let quoted = i > 0 && bytes[i - 1] == b'\'' && bytes.get(i + 1) == Some(&b'\'');
        match bytes[i] {
            _ if quoted => {}
            b'{' => match pending.take() {
                Some((at, item)) if at == i => stack.push(item),
                other => {
                    pending = other;
                    stack.push(Open::Other);
                }
            },
            b'}' => {
                if let Some(Open::Fn(start, name)) = stack.pop()
                    && !stack.iter().any(|o| matches!(o, Open::Fn(..)))
                {
                    let within = stack.iter().rev().find_map(|o| match o {
                        Open::Impl(h) => Some(*h),
                        _ => None,
                    });
                    out.push(Function { name, within, body: &code[start..=i] });
                }
            }
            _ => {}
        }
        i += code[i..].chars().next().map_or(1, char::len_utf8);
    }
    out
}

/// The type an `impl` header is for: `impl<T> Trait for Type<T>` → `Type`, `impl Type` → `Type`.
fn impl_type(header: &str) -> String {
    let rest = header.strip_prefix("impl").unwrap_or(header);
    // Skip the impl's own generics.
    let rest = if rest.trim_start().starts_with('<') {
        let mut depth = 0;
        let mut end = rest.len();
        for (j, c) in rest.char_indices() {
            match c {
                '<' => depth += 1,
                '>' => {
                    depth -= 1;
                    if depth == 0 {
                        end = j + 1;
                        break;
                    }
                }
                _ => {}
            }
        }
        &rest[end..]
    } else {
        rest
    };
    let ty = rest.rsplit_once(" for ").map_or(rest, |(_, t)| t).trim();
    let ty = ty.rsplit("::").next().unwrap_or(ty);
    ty.chars().take_while(|c| c.is_alphanumeric() || *c == '_').collect()
}

/// A node crate's cook side: what only it may use, and the types whose impls belong to it.
pub struct CookSide {
    /// The structs of the crate's `node!` blocks (nodes and their outputs).
    nodes: BTreeSet<String>,
    /// Types whose impls are on the cook side: the nodes, the port groups (`ports!` ones and any
    /// type with a hand-written `Field` impl: describing and reading ports is their job), the lazy
    /// clips (`impl FrameSource for T`: a clip's frames are cooked after its node returns),
    /// and `NodeError` (turning an algorithm's error into the node's).
    impls: BTreeSet<String>,
}

impl CookSide {
    /// The cook side of a crate from its files' shipped code; `declared` gives a file's node
    /// structs and its `ports!` groups.
    pub fn of<'a>(files: impl Iterator<Item = &'a str>, declared: impl Fn(&str) -> (BTreeSet<String>, BTreeSet<String>)) -> Self {
        let mut side = CookSide { nodes: BTreeSet::new(), impls: BTreeSet::from(["NodeError".to_string()]) };
        for code in files {
            let (nodes, groups) = declared(code);
            side.impls.extend(nodes.iter().cloned().chain(groups));
            side.nodes.extend(nodes);
            for (i, _) in code.match_indices("impl") {
                let Some(open) = body_open(code, i) else { continue };
                let header = &code[i..open - 1];
                if header.contains("FrameSource for") || header.contains("Field for") {
                    side.impls.insert(impl_type(header));
                }
            }
        }
        side
    }

    /// Every function of a file (shipped code) outside the cook side that uses it, as messages
    /// naming the function and what it uses.
    pub fn outside_cooks(&self, file: &str, code: &str) -> Vec<String> {
        let mut out = Vec::new();
        for f in functions(code) {
            if f.within.is_some_and(|h| self.impls.contains(&impl_type(h))) {
                continue;
            }
            let uses = node_side_uses(f.body, &self.nodes);
            if !uses.is_empty() {
                let at = f.within.map(|h| format!(" (in `{}`)", h.trim())).unwrap_or_default();
                out.push(format!("{file}: fn {}{at} uses {} outside a cook", f.name, uses.join(", ")));
            }
        }
        out
    }
}

/// What of the node side a function's body uses: `port!`, `NodeError`, node structs.
fn node_side_uses(body: &str, nodes: &BTreeSet<String>) -> Vec<String> {
    let mut uses = Vec::new();
    if body.contains("port!(") {
        uses.push("port!".to_string());
    }
    let words: BTreeSet<&str> = body.split(|c: char| !(c.is_alphanumeric() || c == '_')).collect();
    if words.contains("NodeError") {
        uses.push("NodeError".to_string());
    }
    uses.extend(nodes.iter().filter(|n| !n.is_empty() && words.contains(n.as_str())).cloned());
    uses
}

#[test]
fn functions_and_their_impls_are_found() {
    let code = "impl Crop {\n fn a(&self, x: [f32; 4]) -> u8 { if x { 1 } else { 2 } }\n}\nfn free() { fn inner() {} }\ntrait T { fn decl(); }\nimpl<T: Clone> FrameSource for S<T> { fn frame(&self) {} }\n";
    let fs = functions(code);
    let names: Vec<(&str, Option<String>)> = fs.iter().map(|f| (f.name.as_str(), f.within.map(impl_type))).collect();
    assert_eq!(names, vec![("a", Some("Crop".to_string())), ("free", None), ("frame", Some("S".to_string()))],);
    assert!(fs[1].body.contains("inner"));
}

/// The rule on a made-up node crate: each algorithm that reaches into the node side is found,
/// and nothing on the cook side is.
#[test]
fn the_checker_finds_algorithms_that_reach_into_ports() {
    let nodes =
        "node! {\n    pub struct Crop { x: u32 }\n    -> image: Image\n}\nports! {\n    pub struct Look { gain: f32 = 1.0 }\n}\n";
    let code = r#"
impl Cook for Crop {
    fn cook(self, _: &CookCtx) -> Result<Image, NodeError> { crop(self.x).at_port(port!(Crop, x)) }
}
impl Crop {
    fn check(&self) -> Result<(), NodeError> { Err(NodeError::port(port!(Crop, x), "no")) }
}
impl Look {
    fn validate(&self) -> Result<(), NodeError> { Ok(()) }
}
struct Frames;
impl FrameSource for Frames {
    fn frame(&self) -> Result<Value, NodeError> { self.step() }
}
impl Frames {
    fn step(&self) -> Result<Value, NodeError> { Ok(Value::Int(0)) }
}
impl From<CropError> for NodeError {
    fn from(e: CropError) -> Self { NodeError::msg(e.to_string()) }
}
pub fn crop(x: u32) -> Result<Image, CropError> { if x > 4 { Err(CropError) } else { Ok(Image) } }
pub fn reads_a_port(x: u32) -> Result<u32, String> { Err(format!("{} {x}", port!(Crop, x))) }
pub fn returns_a_node_error(x: [f32; 3]) -> Result<(), NodeError> { Ok(()) }
pub fn takes_the_node(c: &Crop) -> u32 { c.x }
struct Layer;
impl Field for Layer {
    fn read(inputs: &Inputs<'_>, name: &str) -> Result<Self, NodeError> { Ok(Layer) }
}
impl Layer {
    fn layer(&self, prefix: &str) -> Result<(), NodeError> { Ok(()) }
}
struct Helper;
impl Helper {
    fn method(&self) -> Result<(), NodeError> { Ok(()) }
}
"#;
    let side = CookSide::of([nodes, code].into_iter(), |t| {
        let structs = |mac: &str| -> BTreeSet<String> {
            t.split(mac)
                .skip(1)
                .flat_map(|b| b.split("struct ").skip(1).map(|r| r.split_whitespace().next().unwrap_or("").to_string()))
                .collect()
        };
        (structs("node!"), structs("ports!"))
    });
    let found = side.outside_cooks("src/crop.rs", code);
    assert_eq!(
        found,
        vec![
            "src/crop.rs: fn reads_a_port uses port!, Crop outside a cook",
            "src/crop.rs: fn returns_a_node_error uses NodeError outside a cook",
            "src/crop.rs: fn takes_the_node uses Crop outside a cook",
            "src/crop.rs: fn method (in `impl Helper`) uses NodeError outside a cook",
        ],
    );
}
