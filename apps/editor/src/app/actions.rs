//! Applying what the canvas asked for ([`Action`]s) through the editor.

use eframe::egui;

use super::EditorApp;
use crate::action::Action;

impl EditorApp {
    /// Applies canvas gestures through the editor.
    pub fn apply(&mut self, actions: Vec<Action>) {
        for a in actions {
            match a {
                Action::Connect { from, to } => {
                    let _ = self.editor.connect(&from.0, &from.1, &to.0, &to.1);
                }
                Action::Disconnect { from, to } => self.editor.disconnect(&from, &to),
                Action::DropInput(n, p) => self.editor.disconnect_input(&n, &p),
                Action::DropOutput(n, p) => self.editor.disconnect_output(&n, &p),
                Action::Add(item, pos) => self.add_item(&item, pos),
                Action::AddWired(type_name, pos, wire) => {
                    // The reason for a refusal is in the status bar.
                    let _ = self.editor.add_wired(&type_name, (pos.x, pos.y), &wire);
                }
                Action::Remove(ids) => self.editor.remove_nodes(&ids),
                Action::Duplicate(ids) => {
                    self.editor.duplicate(&ids);
                }
                Action::ToggleParamPins(id) => self.canvas.toggle_param_pins(&id),
                Action::Bypass(ids) => self.editor.toggle_bypass(&ids),
                Action::Unpack(id) => {
                    if let Err(e) = self.editor.unpack(&id) {
                        self.editor.set_status(e, true);
                    }
                }
                Action::StepInto(id) => self.step_into(&id),
                Action::StepTo(depth) => self.step_to(depth),
                Action::Collapse(ids) => {
                    if let Err(e) = self.editor.collapse(&ids) {
                        self.editor.set_status(e, true);
                    }
                }
                Action::Preview(id) => {
                    self.key_ui.clear_selection();
                    self.editor.select(&id);
                }
                Action::Select(ids) => {
                    self.key_ui.clear_selection();
                    self.editor.set_selection(ids);
                }
                Action::SelectAnnotation(a) => self.canvas.annotation = a,
                Action::MoveComment(i, p) => {
                    self.editor.move_comment(i, (p.x, p.y));
                    self.editor.seal();
                }
            }
        }
    }

    pub(super) fn add_item(&mut self, item: &crate::state::PaletteItem, pos: egui::Pos2) {
        let r = match &item.preset {
            Some(file) => self.editor.add_preset(file, (pos.x, pos.y)),
            None => self.editor.add_node(&item.type_name, (pos.x, pos.y)),
        };
        match r {
            Ok(id) => self.editor.select(&id),
            Err(e) => self.editor.set_status(e, true),
        }
    }
}
