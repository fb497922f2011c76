//! A graph file of 2,000,000 nodes is refused quickly and in little memory: the node count is
//! read as the file streams in and the refusal comes at the limit, before anything is built
//! (issue 65: it took 19 s and 3.6 GiB). In a file of its own, because the peak memory read here
//! is of every child this test process has waited for.

use std::io::Write;
use std::process::Command;
use std::time::Instant;

/// The largest resident size of the children waited for so far, in MiB (Linux reports KiB).
fn children_peak_mib() -> f64 {
    // SAFETY: getrusage writes the plain struct it is given; a zeroed rusage is a valid value.
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    // SAFETY: `usage` is a valid, writable rusage for the call.
    let ok = unsafe { libc::getrusage(libc::RUSAGE_CHILDREN, &mut usage) } == 0;
    assert!(ok, "getrusage failed");
    usage.ru_maxrss as f64 / 1024.0
}

#[test]
fn a_two_million_node_graph_file_is_refused_in_seconds_and_little_memory() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("huge.ron");
    let mut f = std::io::BufWriter::new(std::fs::File::create(&path).unwrap());
    write!(f, "(version: 1, nodes: {{").unwrap();
    for i in 0..2_000_000 {
        write!(f, "\"n{i}\": (type: \"value.float\", params: {{\"value\": 1.0}}), ").unwrap();
    }
    writeln!(f, "}}, edges: [])").unwrap();
    drop(f);
    let started = Instant::now();
    let o =
        Command::new(env!("CARGO_BIN_EXE_pyrograph")).arg("check").arg(&path).env_remove("PYROGRAPH_MAX_NODES").output().unwrap();
    let seconds = started.elapsed().as_secs_f64();
    let all = format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    assert_eq!(o.status.code(), Some(1), "{all}");
    for needle in ["huge.ron", "the graph has 2000000 nodes, more than the 1000000 pyrograph builds", "--max-nodes 2000000"] {
        assert!(all.contains(needle), "{needle:?} in:\n{all}");
    }
    let peak = children_peak_mib();
    println!("refused in {seconds:.2} s at {peak:.0} MiB peak");
    assert!(peak < 256.0, "peak {peak:.0} MiB");
    // A bound on a refusal, not a benchmark: the file is read only up to the limit.
    assert!(seconds < 2.0, "{seconds:.2} s");
}
