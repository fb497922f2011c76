//! Harness helpers shared by the editor's egui_kittest tests.

use std::time::{Duration, Instant};

use egui_kittest::Harness;
use pyrograph_editor::EditorApp;

/// How long a test waits for the cook worker before going on (and failing on what it finds).
const WAIT: Duration = Duration::from_secs(30);

/// Steps the harness until the editor's cook worker is idle, then twice more to draw the result.
pub fn settle(h: &mut Harness<'_, EditorApp>) {
    let start = Instant::now();
    loop {
        h.step();
        if !h.state().editor.is_cooking() || start.elapsed() > WAIT {
            break;
        }
        std::thread::sleep(Duration::from_millis(5));
    }
    h.run_steps(2);
}

/// The pixels the preview shows after selecting `node` (which the preview must then show).
// Not every test file previews pixels.
#[allow(dead_code)]
pub fn preview_of(h: &mut Harness<'_, EditorApp>, node: &str) -> Vec<u8> {
    h.state_mut().editor.select(node);
    settle(h);
    let p = h.state().editor.preview().expect("a preview");
    assert_eq!(p.request.as_ref().map(|r| r.node.as_str()), Some(node));
    p.image.as_ref().unwrap_or_else(|| panic!("no image for {node}: {:?}", p.error)).rgba.clone()
}
