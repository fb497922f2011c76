//! Playing the preview: the cook worker reads ahead while the preview plays, so the next frame
//! is cooked before the UI asks for it, and only then.

use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

use pyrograph_editor::Editor;
use pyrograph_frontend::core::{Cook, CookCtx, GraphDoc, NodeDoc, NodeError, ParamValue, Registry};

static COOKED: [AtomicUsize; 12] = [const { AtomicUsize::new(0) }; 12];

pyrograph_frontend::core::node! {
    /// Counts how often each frame is cooked.
    #[node("test.counted", "Test", PerFrame)]
    pub struct Counted {
        /// The frame number.
        #[range(0, 100)]
        a: f64 = 0.0,
    }
    /// a
    -> value: f64
}

impl Cook for Counted {
    fn cook(self, _: &CookCtx) -> Result<f64, NodeError> {
        if let Some(c) = COOKED.get(self.a as usize) {
            c.fetch_add(1, Ordering::SeqCst);
        }
        Ok(self.a)
    }
}

fn cooked(frame: usize) -> usize {
    COOKED[frame].load(Ordering::SeqCst)
}

/// Waits until `frame` has been cooked, up to 10 s.
fn wait_cooked(frame: usize) -> bool {
    let start = Instant::now();
    while cooked(frame) == 0 && start.elapsed() < Duration::from_secs(10) {
        std::thread::sleep(Duration::from_millis(2));
    }
    cooked(frame) > 0
}

#[test]
fn a_playing_preview_cooks_the_next_frame_before_it_is_asked_for() {
    let mut r = pyrograph_frontend::registry();
    r.declare::<Counted>();
    let mut ed = Editor::new(Arc::new(r) as Arc<Registry>);
    let mut doc = GraphDoc::new();
    doc.add_node("time", NodeDoc::new("time.frame").param("frames", ParamValue::Int(10)));
    doc.add_node("counted", NodeDoc::new("test.counted"));
    doc.connect("time.frame", "counted.a");
    ed.edit(None, |d| *d = doc);
    ed.select("counted");
    assert!(ed.wait_idle(Duration::from_secs(10)));
    assert_eq!(ed.preview().and_then(|p| p.clip_len), Some(10), "{:?}", ed.preview().map(|p| &p.error));
    assert_eq!(cooked(0), 1);
    // Not playing: nothing but the frame asked for.
    std::thread::sleep(Duration::from_millis(100));
    assert_eq!(cooked(1), 0, "no read-ahead while the preview stands still");

    // Playing: frame 2 is asked for, and frame 3 cooks after it without being asked.
    ed.set_read_ahead(1);
    ed.set_frame(2);
    assert!(ed.wait_idle(Duration::from_secs(10)));
    assert!(wait_cooked(3), "the frame after the one asked for is cooked ahead");
    std::thread::sleep(Duration::from_millis(100));
    assert_eq!(cooked(4), 0, "one frame ahead, not more");
    // The request for frame 3 finds it cooked.
    ed.set_frame(3);
    assert!(ed.wait_idle(Duration::from_secs(10)));
    assert_eq!(ed.preview().and_then(|p| p.request.as_ref()).map(|r| r.frame), Some(3));
    assert_eq!(cooked(3), 1, "served from the frame cache, not cooked again");
}
