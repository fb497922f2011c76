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
