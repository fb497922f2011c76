//! The `pyrograph` command's own library: what only the CLI does (job bundles for render farms,
//! per-task manifests, wedges, the evaluator benchmark, look measurements) and the embedded demo
//! graph. It is shared by the binary, its tests and examples; no other crate depends on it. What
//! every front end needs (registry, checks, node reference, presets) is `pyrograph-frontend`.
#![deny(missing_docs)]

pub mod bench;
pub mod demo;
pub mod job;
pub mod look;
pub mod manifest;
pub mod wedge;

/// `println!` for text that may echo a user's input (node ids, paths, values): control characters
/// escaped and overlong runs cut, so a hostile graph cannot drive the user's terminal
/// ([`pyrograph_frontend::core::text::printable`]). Every line the command prints goes through it
/// or, for `--json`, through [`pyrograph_frontend::core::text::printable_json`].
#[macro_export]
macro_rules! outln {
    () => { println!() };
    ($($t:tt)*) => { println!("{}", pyrograph_frontend::core::text::printable(&format!($($t)*))) };
}

/// `eprintln!` as [`outln!`] prints: control characters escaped, overlong runs cut.
#[macro_export]
macro_rules! errln {
    () => { eprintln!() };
    ($($t:tt)*) => { eprintln!("{}", pyrograph_frontend::core::text::printable(&format!($($t)*))) };
}
