//! The state dump (`--state-dump FILE`): what a test driving the real window reads to know where
//! to click, what the click did, and how fast the window answered.

use eframe::egui;

use super::EditorApp;

impl EditorApp {
    /// The editor's state as JSON: the selection, where each node and each key toggle of the
    /// inspector is on screen (points from the window's top-left), the current node's
    /// parameters as written and the playhead's frame. A test driving the real window with
    /// synthetic mouse events reads it to know where to click and what the click did.
    pub fn state_json(&self, ctx: &egui::Context) -> serde_json::Value {
        let nodes: serde_json::Map<String, serde_json::Value> = self
            .editor
            .doc()
            .nodes
            .0
            .iter()
            .filter_map(|(id, _)| {
                let r = self.canvas.node_screen_rect(id)?;
                Some((id.clone(), serde_json::json!({"x": r.min.x, "y": r.min.y, "w": r.width(), "h": r.height()})))
            })
            .collect();
        let rect = |r: &egui::Rect| serde_json::json!({"x": r.min.x, "y": r.min.y, "w": r.width(), "h": r.height()});
        let toggles: serde_json::Map<String, serde_json::Value> =
            self.key_ui.toggle_rects.iter().map(|(k, r)| (k.clone(), rect(r))).collect();
        let params: serde_json::Map<String, serde_json::Value> = self
            .editor
            .current()
            .and_then(|id| self.editor.node_doc(id))
            .map(|n| n.params.iter().map(|(k, v)| (k.clone(), v.to_string().into())).collect())
            .unwrap_or_default();
        serde_json::json!({
            "frame": self.editor.frame(),
            "key_toggles": toggles,
            "params": params,
            "selection": self.editor.selection(),
            "annotation": self.canvas.annotation.map(|a| format!("{a:?}")),
            "groups": self.editor.doc().groups.len(),
            "comments": self.editor.doc().comments.len(),
            "pixels_per_point": ctx.pixels_per_point(),
            "nodes": nodes,
            "opening": self.editor.opening().is_some(),
            "status": self.editor.status().map(|s| s.text.clone()),
            "frames": self.frames_drawn,
            "slowest_frame_ms": self.frame_times.iter().copied().fold(0.0, f64::max),
            "culled": self.canvas.culled,
            "scope": self.editor.scope().iter().map(|c| c.id.clone()).collect::<Vec<_>>(),
            "crumbs": self.scope_ui.crumb_rects.iter().map(rect).collect::<Vec<_>>(),
        })
    }

    pub(super) fn write_state_dump(&mut self, ctx: &egui::Context) {
        let Some(path) = &self.state_dump else { return };
        let text = self.state_json(ctx).to_string();
        if text != self.last_dump {
            let tmp = path.with_extension("tmp");
            if std::fs::write(&tmp, &text).and_then(|()| std::fs::rename(&tmp, path)).is_ok() {
                self.last_dump = text;
            }
        }
    }
}
