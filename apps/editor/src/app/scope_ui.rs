//! Stepping into includes in the window: double-click an include's header (or I) to step in,
//! the breadcrumb above the canvas (or U) to step back out, Ctrl+Shift+G to collapse the
//! selection into a subgraph, and the confirmation before a local copy is written over its
//! preset file, naming the other graphs that use that file.

use std::path::PathBuf;

use eframe::egui::{self, Color32, Key, Modifiers, RichText};

use super::EditorApp;
use crate::action::Action;

/// What the breadcrumb and the confirmation keep between frames.
#[derive(Default)]
pub struct ScopeUi {
    /// Where each breadcrumb button was drawn (the top level first), for the state dump.
    pub crumb_rects: Vec<egui::Rect>,
    /// A "Save into preset" waiting for its confirmation: the include, the file, its other users.
    confirm: Option<(String, PathBuf, Vec<PathBuf>)>,
}

const LOCAL: Color32 = Color32::from_rgb(120, 200, 255);

impl EditorApp {
    /// Steps into include `id` and frames its graph.
    pub(super) fn step_into(&mut self, id: &str) {
        match self.editor.step_into(id) {
            Ok(()) => self.after_step(),
            Err(e) => self.editor.set_status(e, true),
        }
    }

    /// Steps up to `depth` levels inside.
    pub(super) fn step_to(&mut self, depth: usize) {
        if self.editor.step_to(depth) {
            self.after_step();
        }
    }

    fn after_step(&mut self) {
        self.canvas.frame_all();
        self.texture = None;
        self.texture_b = None;
    }

    /// I steps into the current node when it is an include, U steps out.
    pub(super) fn scope_keys(&mut self, ctx: &egui::Context) {
        let (into, out) = ctx.input_mut(|i| (i.consume_key(Modifiers::NONE, Key::I), i.consume_key(Modifiers::NONE, Key::U)));
        if into && let Some(id) = self.editor.current().map(str::to_string) {
            self.step_into(&id);
        }
        if out {
            let depth = self.editor.scope().len();
            self.step_to(depth.saturating_sub(1));
        }
    }

    /// The breadcrumb above the canvas while inside an include: the file, then each include
    /// stepped into (click one to go back there), what the graph shown is, and its actions.
    pub(super) fn breadcrumb_panel(&mut self, ui: &mut egui::Ui) {
        let crumbs = self.editor.scope();
        self.scope_ui.crumb_rects.clear();
        if crumbs.is_empty() {
            return;
        }
        let mut actions = Vec::new();
        let mut revert = None;
        egui::Panel::top("breadcrumb").show(ui, |ui| {
            ui.horizontal(|ui| {
                let file = self
                    .editor
                    .path()
                    .and_then(|p| p.file_name())
                    .map_or("untitled".into(), |n| n.to_string_lossy().into_owned());
                let top = ui.button(format!("⬆ {file}")).on_hover_text("back to the top level (U goes up one)");
                if top.clicked() {
                    actions.push(Action::StepTo(0));
                }
                self.scope_ui.crumb_rects.push(top.rect);
                for (i, c) in crumbs.iter().enumerate() {
                    ui.label("⏵");
                    let last = i + 1 == crumbs.len();
                    let text = RichText::new(&c.id).strong();
                    let r = if last { ui.add(egui::Button::new(text).selected(true)) } else { ui.button(text) };
                    if r.clicked() && !last {
                        actions.push(Action::StepTo(i + 1));
                    }
                    self.scope_ui.crumb_rects.push(r.rect);
                }
                ui.separator();
                let Some(here) = crumbs.last() else { return };
                let origin = here.origin.as_ref().and_then(|f| f.file_name()).map(|n| n.to_string_lossy().into_owned());
                match (here.local, origin) {
                    (true, Some(name)) => {
                        ui.label(RichText::new(format!("local copy of {name}, saved in this graph")).color(LOCAL));
                        if ui
                            .button("Revert to preset")
                            .on_hover_text("drop the local copy: read the preset file again")
                            .clicked()
                        {
                            revert = Some(here.id.clone());
                        }
                        if ui.button("Save into preset…").on_hover_text("write this copy over the preset file").clicked() {
                            self.ask_save_into_preset(&here.id);
                        }
                    }
                    (true, None) => {
                        ui.label(RichText::new("local subgraph, saved in this graph").color(LOCAL));
                    }
                    (false, Some(name)) => {
                        ui.label(format!("{name}: an edit here makes a local copy for this graph; the file stays as it is"));
                    }
                    (false, None) => {}
                }
            });
        });
        if let Some(id) = revert {
            self.step_to(crumbs.len() - 1);
            if let Err(e) = self.editor.revert_local(&id) {
                self.editor.set_status(e, true);
            }
        }
        self.apply(actions);
    }

    /// Opens the confirmation for writing include `id` (of the level above) into its preset.
    fn ask_save_into_preset(&mut self, id: &str) {
        self.step_to(self.editor.scope().len() - 1);
        let file = self.editor.node_doc(id).and_then(|n| match n.params.get(pyrograph_frontend::core::builtin::INCLUDE_PATH) {
            Some(pyrograph_frontend::core::ParamValue::String(p)) => Some(self.editor.base_dir().join(p)),
            _ => None,
        });
        if let Some(file) = file {
            let users = self.editor.preset_users(&file);
            self.scope_ui.confirm = Some((id.to_string(), file, users));
        }
    }

    /// The confirmation before a preset file is written.
    pub(super) fn preset_confirm_window(&mut self, ctx: &egui::Context) {
        let Some((id, file, users)) = self.scope_ui.confirm.clone() else { return };
        let mut close = false;
        egui::Window::new("Save into preset").collapsible(false).resizable(false).show(ctx, |ui| {
            ui.label(format!("Write {id}'s local copy over {}?", file.display()));
            match users.is_empty() {
                true => ui.label("No other graph found in this folder or the preset folders uses it."),
                false => ui.label(format!("{} other graph(s) use this preset and will cook the new version:", users.len())),
            };
            for u in users.iter().take(20) {
                ui.label(RichText::new(u.display().to_string()).monospace().small());
            }
            if users.len() > 20 {
                ui.label(format!("… and {} more", users.len() - 20));
            }
            ui.horizontal(|ui| {
                if ui.button("Write the preset file").clicked() {
                    if let Err(e) = self.editor.save_into_preset(&id) {
                        self.editor.set_status(e, true);
                    }
                    close = true;
                }
                if ui.button("Cancel").clicked() {
                    close = true;
                }
            });
        });
        if close {
            self.scope_ui.confirm = None;
        }
    }
}
