//! The A/B compare: besides the preview (A, the selected node), a second viewer (B) pinned to a
//! node, output and frame of its own, cooked in the same job as A, shown side by side or with a
//! wipe (Nuke's viewer wipe, Houdini's flipbook compare). With the frames locked, moving A's
//! frame moves B's by the same amount.

use crate::cook::{CookOutcome, Preview, PreviewRequest};

use super::Editor;

/// How the two viewers share the preview panel.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum CompareMode {
    /// A on the left, B on the right.
    #[default]
    SideBySide,
    /// One picture: A left of a vertical line, B right of it.
    Wipe,
}

/// The B viewer.
#[derive(Clone, Debug, Default)]
pub struct Compare {
    request: Option<PreviewRequest>,
    preview: Option<Preview>,
    serial: u64,
    /// B's frame minus A's while the frames are locked together.
    lock: Option<i64>,
    /// Side by side or wipe.
    pub mode: CompareMode,
    /// Where the wipe line is, 0 (left edge) to 1.
    pub wipe: f32,
}

impl Editor {
    /// Pins B to what A shows now (node, output and frame); the next cook previews both.
    pub fn pin_b(&mut self) -> bool {
        let Some(a) = self.preview_req.clone() else { return false };
        self.set_status(format!("B: {} at frame {}", a.node, a.frame), false);
        self.compare.request = Some(a);
        self.compare.preview = None;
        self.compare.lock = None;
        if self.compare.wipe <= 0.0 || self.compare.wipe >= 1.0 {
            self.compare.wipe = 0.5;
        }
        self.request_preview();
        true
    }

    /// Closes the B viewer.
    pub fn clear_b(&mut self) {
        self.compare = super::viewers::Compare { mode: self.compare.mode, wipe: self.compare.wipe, ..Default::default() };
    }

    /// What B is pinned to.
    pub fn compare_request(&self) -> Option<&PreviewRequest> {
        self.compare.request.as_ref()
    }

    /// B's latest preview, and its serial (increasing with each new one).
    pub fn compare_preview(&self) -> (Option<&Preview>, u64) {
        (self.compare.preview.as_ref(), self.compare.serial)
    }

    /// The compare settings, to change the mode or the wipe.
    pub fn compare_mut(&mut self) -> &mut Compare {
        &mut self.compare
    }

    /// Moves B to frame `frame` (of B's clip).
    pub fn set_b_frame(&mut self, frame: usize) {
        if let Some(b) = &mut self.compare.request
            && b.frame != frame
        {
            b.frame = frame;
            if let Some(a) = &self.preview_req {
                self.compare.lock = self.compare.lock.map(|_| frame as i64 - a.frame as i64);
            }
            self.request_preview();
        }
    }

    /// Whether B's frame follows A's.
    pub fn b_locked(&self) -> bool {
        self.compare.lock.is_some()
    }

    /// Locks B's frame to A's at their current distance, or unlocks it.
    pub fn lock_b(&mut self, lock: bool) {
        let offset = match (&self.compare.request, &self.preview_req) {
            (Some(b), Some(a)) if lock => Some(b.frame as i64 - a.frame as i64),
            _ => None,
        };
        self.compare.lock = offset;
    }

    /// B as the next cook asks for it; `None` when B's node is gone from the document.
    pub(super) fn compare_target(&mut self) -> Option<PreviewRequest> {
        let b = self.compare.request.clone()?;
        if self.desc(&b.node).is_none() {
            self.clear_b();
            return None;
        }
        Some(b)
    }

    /// With the frames locked, moves B along with A (now at `frame`).
    pub(super) fn follow_with_b(&mut self, frame: usize) {
        if let (Some(offset), Some(b)) = (self.compare.lock, &mut self.compare.request) {
            b.frame = (frame as i64 + offset).max(0) as usize;
        }
    }

    /// Takes B's preview from a finished cook.
    pub(super) fn receive_compare(&mut self, outcome: &CookOutcome) {
        if let Some(p) = &outcome.compare
            && !(outcome.cancelled && p.image.is_none())
        {
            self.compare.preview = Some(p.clone());
            self.compare.serial += 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use std::time::Duration;

    use pyrograph_frontend::core::{GraphDoc, NodeDoc, ParamValue};

    use crate::Editor;

    #[test]
    fn b_keeps_its_node_and_frame_follows_a_when_locked_and_goes_with_its_node() {
        let mut ed = Editor::with_default_registry();
        let mut doc = GraphDoc::new();
        doc.add_node("t", NodeDoc::new("time.frame").param("frames", ParamValue::Int(20)));
        doc.add_node("add", NodeDoc::new("math.add").param("b", ParamValue::Float(100.0)));
        doc.connect("t.frame", "add.a");
        ed.edit(None, |d| *d = doc);
        ed.select("add");
        ed.set_frame(3);
        assert!(ed.wait_idle(Duration::from_secs(10)));
        assert!(ed.pin_b());
        ed.select("t");
        assert!(ed.wait_idle(Duration::from_secs(10)));
        let b = ed.compare_request().cloned().unwrap();
        assert_eq!((b.node.as_str(), b.frame), ("add", 3));
        let (p, _) = ed.compare_preview();
        assert_eq!(p.map(|p| p.summary.as_str()), Some("103"), "B shows add at frame 3: {:?}", p.map(|p| &p.error));
        assert_eq!(ed.preview().map(|p| p.summary.as_str()), Some("3"), "A shows t at frame 3");
        // Unlocked, B stays where it is; locked, it keeps its distance.
        ed.set_frame(5);
        assert_eq!(ed.compare_request().map(|b| b.frame), Some(3));
        ed.lock_b(true);
        ed.set_frame(9);
        assert!(ed.wait_idle(Duration::from_secs(10)));
        assert_eq!(ed.compare_request().map(|b| b.frame), Some(7));
        assert_eq!(ed.compare_preview().0.map(|p| p.summary.as_str()), Some("107"));
        // Deleting B's node closes B.
        ed.remove_nodes(&["add".to_string()]);
        ed.request_preview();
        assert!(ed.compare_request().is_none());
    }
}
