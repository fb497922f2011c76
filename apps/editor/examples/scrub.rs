//! The editor's scrubber on a long video, measured through the editor's own state and cook
//! worker (the code behind the preview panel and its frame slider), without a window.
//!
//! Opens a graph `load_sequence(VIDEO) -> to_gray`, selects the gray node and reports:
//! the first preview (frame 0); jumps to frames far apart (each a seek, never a decode of the
//! whole clip); a drag of the slider across the clip at 60 UI frames a second (every move cancels
//! the cook in flight), and how long after the last move its frame shows; the longest any
//! `poll` (what the UI thread does each frame) took; peak RSS.
//!
//! ```sh
//! cargo run --release -p pyrograph-editor --example scrub -- VIDEO.mp4
//! ```

use std::time::{Duration, Instant};

use pyrograph_editor::Editor;

fn peak_rss_mib() -> u64 {
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    status
        .lines()
        .find_map(|l| l.strip_prefix("VmHWM:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<u64>().ok())
        .map_or(0, |kib| kib >> 10)
}

/// Polls like the UI thread until frame `frame` is shown; returns the wait and the longest poll.
fn wait_for(ed: &mut Editor, frame: usize, limit: Duration) -> Result<(Duration, Duration), String> {
    let start = Instant::now();
    let mut longest = Duration::ZERO;
    loop {
        let t = Instant::now();
        ed.poll();
        longest = longest.max(t.elapsed());
        if let Some(p) = ed.preview()
            && p.request.as_ref().is_some_and(|r| r.frame == frame)
        {
            if let Some(e) = &p.error {
                return Err(format!("frame {frame}: {e}"));
            }
            if p.image.is_some() {
                return Ok((start.elapsed(), longest));
            }
        }
        if start.elapsed() > limit {
            return Err(format!("frame {frame} did not show within {limit:?}"));
        }
        std::thread::sleep(Duration::from_millis(1));
    }
}

fn main() -> Result<(), String> {
    let video = std::env::args().nth(1).ok_or("usage: scrub VIDEO")?;
    let video = std::fs::canonicalize(&video).map_err(|e| format!("{video}: {e}"))?;
    let dir = tempfile::tempdir().map_err(|e| e.to_string())?;
    let graph = dir.path().join("scrub.ron");
    let text = format!(
        "(version: 1, nodes: {{\"load\": (type: \"imaging.load_sequence\", params: {{\"path\": {:?}}}), \
         \"gray\": (type: \"imaging.to_gray\")}}, edges: [(\"load.clip\", \"gray.image\")])",
        video.display().to_string()
    );
    std::fs::write(&graph, text).map_err(|e| e.to_string())?;

    // The editor's own cache settings (main.rs): 1 GiB, 8-bit frames held in bytes.
    pyrograph_frontend::core::FrameCache::global().set_budget(1 << 30);
    pyrograph_frontend::core::FrameCache::global().set_compact(true);
    let mut ed = Editor::with_default_registry();
    ed.open(&graph)?;
    let start = Instant::now();
    ed.select("gray");
    let (first, _) = wait_for(&mut ed, 0, Duration::from_secs(60))?;
    let len = ed.preview().and_then(|p| p.clip_len).ok_or("the preview is not a clip")?;
    println!("{}: {len} frames; first preview (frame 0) in {:.0} ms", video.display(), first.as_secs_f64() * 1e3);
    let _ = start;

    let mut longest_poll = Duration::ZERO;
    let mut jumps = Vec::new();
    for frame in [len - 1, len / 2, 10, len * 3 / 4, len / 4, len - 2, 11] {
        ed.set_frame(frame);
        let (t, p) = wait_for(&mut ed, frame, Duration::from_secs(60))?;
        longest_poll = longest_poll.max(p);
        jumps.push(t.as_secs_f64() * 1e3);
        println!("jump to frame {frame:>5}: shown in {:.0} ms", t.as_secs_f64() * 1e3);
    }

    // A drag across the clip: one slider move per UI frame (60 a second), 40 moves.
    let moves: Vec<usize> = (0..40).map(|k| k * (len - 1) / 39).collect();
    let drag = Instant::now();
    for &frame in &moves {
        ed.set_frame(frame);
        let t = Instant::now();
        ed.poll();
        longest_poll = longest_poll.max(t.elapsed());
        std::thread::sleep(Duration::from_millis(16));
    }
    let last = *moves.last().ok_or("no moves")?;
    let (settle, p) = wait_for(&mut ed, last, Duration::from_secs(60))?;
    longest_poll = longest_poll.max(p);
    jumps.sort_by(f64::total_cmp);
    println!(
        "drag over {} frames in {:.2} s: the last frame ({last}) shown {:.0} ms after the last move",
        len,
        drag.elapsed().as_secs_f64() - settle.as_secs_f64(),
        settle.as_secs_f64() * 1e3
    );
    println!(
        "jumps: median {:.0} ms, slowest {:.0} ms; longest UI poll {:.2} ms; peak RSS {} MiB",
        jumps[jumps.len() / 2],
        jumps[jumps.len() - 1],
        longest_poll.as_secs_f64() * 1e3,
        peak_rss_mib()
    );
    Ok(())
}
