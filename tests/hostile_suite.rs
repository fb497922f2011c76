//! The hostile-input suite: one case per class of hostile or huge input, each built here, run
//! through the binary under a 1 GiB data limit (`prlimit --data`: an allocation past it fails
//! and the process dies, so a case that ends with its message stayed under it). Every case ends
//! with a clear error (exit 1) or a completed bounded job (exit 0), never a panic, within 10 s,
//! and writes nothing outside its output folder.
//!
//! Classes with a suite of their own: symbolic links and writers (`confinement.rs`), reads
//! confined with --read-root (`read_roots.rs`), a full disk and a video over the pixel budget
//! (`hostile_cli.rs`, ignored: they need unshare and ffmpeg), Python callers
//! (`apps/python/tests/test_hostile.py`), the editor (`apps/editor/tests/big_graphs.rs`), and the
//! parsers' fuzzing (`crates/core/tests/fuzz.rs`).

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

const GIB: u64 = 1 << 30;

struct Outcome {
    code: Option<i32>,
    text: String,
    took: Duration,
}

/// Runs the binary with `args` in `dir` under a 1 GiB data limit.
fn run(dir: &Path, args: &[&str]) -> Outcome {
    let started = Instant::now();
    let o = Command::new("prlimit")
        .arg(format!("--data={GIB}"))
        .arg("--")
        .arg(env!("CARGO_BIN_EXE_pyrograph"))
        .args(args)
        .current_dir(dir)
        .output()
        .expect("prlimit (util-linux) runs the binary");
    let text = format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    Outcome { code: o.status.code(), text, took: started.elapsed() }
}

fn case(name: &str, dir: &Path, args: &[&str], code: i32, says: &[&str]) -> Outcome {
    let o = run(dir, args);
    let shown: String = o.text.chars().take(2000).collect();
    assert_eq!(o.code, Some(code), "{name}: exit {:?} (a signal means the 1 GiB limit or a crash):\n{shown}", o.code);
    assert!(!o.text.contains("panicked") && !o.text.contains("stack overflow"), "{name}:\n{shown}");
    for s in says {
        assert!(o.text.contains(s), "{name}: expected {s:?} in:\n{shown}");
    }
    assert!(o.took < Duration::from_secs(10), "{name}: took {:?}", o.took);
    eprintln!("{name}: exit {code} in {:.2} s", o.took.as_secs_f64());
    o
}

/// A case whose input is huge: its error quotes only the start of it.
fn short_case(name: &str, dir: &Path, args: &[&str], says: &[&str]) {
    let o = case(name, dir, args, 1, says);
    assert!(o.text.len() < 4000, "{name}: {} bytes of messages", o.text.len());
}

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

#[test]
fn every_class_of_hostile_input_ends_cleanly_within_bounds() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();

    // Include bombs: 31 files each including the next twice (2^32 nodes flattened).
    let bombs = dir.join("bombs");
    std::fs::create_dir_all(&bombs).unwrap();
    let bomb = pyrograph_testing::include_bomb(&bombs, 30, false);
    case("include bomb", dir, &["check", bomb.to_str().unwrap()], 1, &["more than the 1000000 pyrograph builds", "--max-nodes"]);
    let broken = dir.join("broken");
    std::fs::create_dir_all(&broken).unwrap();
    let leaf = pyrograph_testing::include_bomb(&broken, 12, true);
    case("broken leaf included 4,096 times", dir, &["check", leaf.to_str().unwrap()], 1, &["unknown node type 'math.nope'"]);

    // Long chains: checked, cooked, refused by a lowered limit, and closed into one cycle.
    write(dir, "chain.ron", &pyrograph_testing::chain_ron(100_000));
    case("100,000-node chain, check", dir, &["check", "chain.ron"], 0, &[]);
    case("100,000-node chain, render", dir, &["render", "chain.ron", "--node", "n99999"], 0, &["100000"]);
    case(
        "100,000-node chain over --max-nodes",
        dir,
        &["check", "chain.ron", "--max-nodes", "1000"],
        1,
        &["the graph has 100000 nodes, more than the 1000"],
    );
    let cycle = pyrograph_testing::chain_ron(100_000).replace("\n])", "\n(\"n99999.value\", \"n0.a\"),\n])");
    write(dir, "cycle.ron", &cycle);
    case("cycle through 100,000 nodes", dir, &["check", "cycle.ron"], 1, &["cycle", "100000 nodes"]);

    // Deep nesting in a document and in a --set value.
    let deep = format!(
        r#"(version: 4, nodes: {{"n": (type: "math.add", params: {{"b": {}1.0{}}})}}, edges: [])"#,
        "[".repeat(100_000),
        "]".repeat(100_000)
    );
    write(dir, "deep.ron", &deep);
    short_case("document nested 100,000 deep", dir, &["check", "deep.ron"], &["deep.ron", "nested too deep"]);
    // (One argument may hold 128 KiB on Linux.)
    let set = format!("n0.b={}1{}", "(".repeat(60_000), ")".repeat(60_000));
    short_case(
        "--set nested 60,000 deep",
        dir,
        &["render", "chain.ron", "--node", "n0", "--set", &set],
        &["port 'b'", "characters)"],
    );
    let expr = format!("n0.b=expr(\"{}\")", "(".repeat(50_000));
    short_case("--set expression of 50,000 parentheses", dir, &["render", "chain.ron", "--node", "n0", "--set", &expr], &["n0"]);
    let name = format!("{}.add", "m".repeat(2_000_000));
    write(dir, "long-type.ron", &format!(r#"(version: 4, nodes: {{"n": (type: "{name}")}}, edges: [])"#));
    short_case(
        "a node type of 2,000,000 characters",
        dir,
        &["check", "long-type.ron"],
        &["unknown node type", "(2000004 characters)"],
    );

    // Images that declare enormous sizes.
    std::fs::write(dir.join("bomb.png"), pyrograph_testing::png_declaring(40_000, 40_000)).unwrap();
    write(dir, "png.ron", r#"(version: 4, nodes: {"i": (type: "imaging.load_image", params: {"path": "bomb.png"})}, edges: [])"#);
    case("PNG declaring 40,000 × 40,000", dir, &["check", "png.ron"], 1, &["declares 40000 × 40000 pixels", "--max-pixels"]);
    case("the same, rendered", dir, &["render", "png.ron", "--node", "i"], 1, &["declares 40000 × 40000 pixels"]);

    // Writers leaving --out by name.
    let out = dir.join("out");
    std::fs::create_dir_all(&out).unwrap();
    write(
        dir,
        "escape.ron",
        r#"(version: 4, nodes: {"c": (type: "imaging.constant_color", params: {"width": 8, "height": 8}),
            "w": (type: "imaging.write_image", params: {"path": "../escaped.png"})}, edges: [("c.image", "w.image")])"#,
    );
    case("a writer climbing out of --out", dir, &["render", "escape.ron", "--out", "out"], 1, &["outside the output folder"]);
    assert!(!dir.join("escaped.png").exists());

    // A preset library of 3,000 files (a thousand of them not graphs).
    let lib = dir.join("lib");
    std::fs::create_dir_all(&lib).unwrap();
    for i in 0..3000 {
        let text = if i % 3 == 0 {
            format!("junk {i}")
        } else {
            format!(
                r#"(version: 4, nodes: {{"c": (type: "imaging.constant_color")}}, edges: [],
                    interface: (outputs: {{"image": "c.image"}}), preset: (name: "p{i}", tags: ["t{}"]))"#,
                i % 7
            )
        };
        write(&lib, &format!("p{i:04}.ron"), &text);
    }
    case("a preset folder of 3,000 files", dir, &["presets", "--dir", "lib", "--json"], 1, &["p2999", "p0000.ron"]);

    // Nothing was written outside the case folders.
    let mut outside: Vec<String> =
        std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    outside.sort();
    let expected = [
        "bomb.png",
        "bombs",
        "broken",
        "chain.ron",
        "cycle.ron",
        "deep.ron",
        "escape.ron",
        "lib",
        "long-type.ron",
        "out",
        "png.ron",
    ];
    assert_eq!(outside, expected);
}
