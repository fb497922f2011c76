//! The A/B compare in the preview panel: a "Pin as B" button keeps what the preview shows in a
//! second viewer; A (the selected node) and B are then drawn side by side or as one picture split
//! by a wipe line that a drag moves, with B's own frame slider or its frame locked to A's.

use eframe::egui::{self, Color32, Rect, RichText, TextureHandle};

use crate::app::EditorApp;
use crate::cook::{Preview, PreviewImage};
use crate::state::viewers::CompareMode;

/// The colour B's label and wipe line are drawn in.
const B_COLOR: Color32 = Color32::from_rgb(120, 200, 255);

/// Uploads `img` into the texture in `slot` unless it holds `serial` already.
pub(crate) fn upload_texture(
    ctx: &egui::Context,
    slot: &mut Option<(u64, TextureHandle)>,
    name: &str,
    serial: u64,
    img: &PreviewImage,
) {
    if slot.as_ref().is_some_and(|(s, _)| *s == serial) {
        return;
    }
    let ci = egui::ColorImage::from_rgba_unmultiplied(img.size, &img.rgba);
    match slot {
        Some((s, t)) => {
            t.set(ci, egui::TextureOptions::LINEAR);
            *s = serial;
        }
        None => *slot = Some((serial, ctx.load_texture(name, ci, egui::TextureOptions::LINEAR))),
    }
}

/// The largest size of `size`'s aspect that fits `avail`.
fn fit(size: egui::Vec2, avail: egui::Vec2) -> egui::Vec2 {
    size * (avail.x / size.x).min(avail.y / size.y).max(0.01)
}

fn image_size(p: Option<&Preview>) -> Option<egui::Vec2> {
    p.and_then(|p| p.image.as_ref()).map(|i| egui::vec2(i.size[0] as f32, i.size[1] as f32)).filter(|s| s.x > 0.0 && s.y > 0.0)
}

const FULL_UV: Rect = Rect::from_min_max(egui::pos2(0.0, 0.0), egui::pos2(1.0, 1.0));

impl EditorApp {
    /// The preview header's B controls: "Pin as B", or B's node and frame with a close button.
    pub(crate) fn compare_header(&mut self, ui: &mut egui::Ui) {
        match self.editor.compare_request().cloned() {
            None => {
                let tip = "Keep this node and frame in a second viewer (B) to compare with what you select next: side by side or with a wipe";
                if ui.button("Pin as B").on_hover_text(tip).clicked() {
                    self.editor.pin_b();
                }
            }
            Some(b) => {
                ui.label(RichText::new(format!("B: {} @ {}", b.node, b.frame)).color(B_COLOR));
                if ui.small_button("×").on_hover_text("close the B viewer").clicked() {
                    self.editor.clear_b();
                    self.texture_b = None;
                }
            }
        }
    }

    /// A (`a`, whose texture is uploaded) and B drawn together, with the compare's controls.
    pub(crate) fn compare_view(&mut self, ui: &mut egui::Ui, a: &Preview) {
        let locked = self.editor.b_locked();
        ui.horizontal(|ui| {
            let c = self.editor.compare_mut();
            ui.selectable_value(&mut c.mode, CompareMode::SideBySide, "side by side");
            ui.selectable_value(&mut c.mode, CompareMode::Wipe, "wipe");
            let mut lock = locked;
            if ui.checkbox(&mut lock, "lock frames").on_hover_text("B's frame moves with A's, keeping their distance").changed() {
                self.editor.lock_b(lock);
            }
        });
        let (b, serial) = self.editor.compare_preview();
        let b = b.cloned();
        if let (Some(b), Some(req)) = (&b, self.editor.compare_request().cloned()) {
            if let Some(e) = &b.error {
                ui.colored_label(Color32::from_rgb(255, 120, 120), format!("B: {e}"));
            }
            if let Some(len) = b.clip_len.filter(|n| *n > 1 && !locked) {
                let mut frame = req.frame.min(len - 1);
                let slider = egui::Slider::new(&mut frame, 0..=len - 1).text("B frame");
                if ui.add(slider).changed() {
                    self.editor.set_b_frame(frame);
                }
            }
            if let Some(img) = &b.image {
                upload_texture(ui.ctx(), &mut self.texture_b, "preview-b", serial, img);
            }
        }
        let (a_size, b_size) = (image_size(Some(a)), image_size(b.as_ref()));
        let Some(size) = a_size.or(b_size) else { return };
        let a_tex = self.texture.as_ref().filter(|_| a_size.is_some()).map(|(_, t)| t.id());
        let b_tex = self.texture_b.as_ref().filter(|_| b_size.is_some()).map(|(_, t)| t.id());
        let a_name = a.request.as_ref().map(|r| format!("A: {} @ {}", r.node, r.frame)).unwrap_or_default();
        let b_name = self.editor.compare_request().map(|r| format!("B: {} @ {}", r.node, r.frame)).unwrap_or_default();
        match self.editor.compare_mut().mode {
            CompareMode::SideBySide => {
                let half = egui::vec2((ui.available_width() - 8.0) / 2.0, ui.available_height());
                ui.horizontal(|ui| {
                    for (tex, s, label) in [(a_tex, a_size, a_name.as_str()), (b_tex, b_size, b_name.as_str())] {
                        let (rect, _) = ui.allocate_exact_size(fit(s.unwrap_or(size), half), egui::Sense::hover());
                        paint(ui, rect, tex, rect);
                        ui.painter().text(
                            rect.left_top() + egui::vec2(4.0, 4.0),
                            egui::Align2::LEFT_TOP,
                            label,
                            egui::FontId::proportional(12.0),
                            Color32::WHITE,
                        );
                    }
                });
            }
            CompareMode::Wipe => {
                let (rect, resp) = ui.allocate_exact_size(fit(size, ui.available_size()), egui::Sense::click_and_drag());
                let c = self.editor.compare_mut();
                if let Some(p) = resp.interact_pointer_pos() {
                    c.wipe = ((p.x - rect.left()) / rect.width()).clamp(0.0, 1.0);
                }
                let x = rect.left() + c.wipe * rect.width();
                paint(ui, rect, a_tex, rect);
                paint(ui, rect, b_tex, Rect::from_min_max(egui::pos2(x, rect.top()), rect.max));
                let painter = ui.painter_at(rect);
                painter.line_segment([egui::pos2(x, rect.top()), egui::pos2(x, rect.bottom())], egui::Stroke::new(2.0, B_COLOR));
                let font = egui::FontId::proportional(12.0);
                painter.text(
                    rect.left_top() + egui::vec2(4.0, 4.0),
                    egui::Align2::LEFT_TOP,
                    &a_name,
                    font.clone(),
                    Color32::WHITE,
                );
                painter.text(rect.right_top() + egui::vec2(-4.0, 4.0), egui::Align2::RIGHT_TOP, &b_name, font, B_COLOR);
                let _ = resp.on_hover_text("drag to move the wipe: A left of the line, B right of it");
            }
        }
    }
}

/// Draws texture `tex` over `rect`, only where it meets `clip` (dark gray when there is none).
fn paint(ui: &egui::Ui, rect: Rect, tex: Option<egui::TextureId>, clip: Rect) {
    let painter = ui.painter_at(clip);
    match tex {
        Some(t) => {
            painter.image(t, rect, FULL_UV, Color32::WHITE);
        }
        None => {
            painter.rect_filled(rect, 0.0, Color32::from_gray(20));
        }
    }
}
