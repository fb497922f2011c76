//! The side panels: the inspector (parameters of the current node with their key toggles, or
//! the selected group or comment) and the preview with its frame scrubber and key strip.

use std::time::Instant;

use eframe::egui::{self, Color32, RichText};

use crate::annotate::{Annotation, COMMENT_COLOR, GROUP_COLOR, hex_rgb, rgb_hex};
use crate::app::EditorApp;
use crate::keying::animated_row;
use crate::param_widgets::{buffered_text, param_widget, raw_widget};
use crate::state::{IncludeSetting, SetBy};
use pyrograph_frontend::core::ParamValue;

impl EditorApp {
    pub(crate) fn inspector(&mut self, ui: &mut egui::Ui) {
        if self.editor.selection().is_empty()
            && let Some(which) = self.canvas.annotation
        {
            self.annotation_inspector(ui, which);
            return;
        }
        let Some(id) = self.editor.current().map(str::to_string) else {
            ui.weak("Click a node to edit its parameters.");
            return;
        };
        let Some(nd) = self.editor.node_doc(&id).cloned() else { return };
        ui.horizontal(|ui| {
            ui.heading(&id);
            ui.weak(&nd.type_name);
        });
        for p in self.editor.node_problems(&id) {
            ui.colored_label(Color32::from_rgb(255, 120, 120), format!("⚠ {p}"));
        }
        for w in self.editor.node_warnings(&id) {
            ui.colored_label(Color32::from_rgb(255, 190, 70), format!("⚠ warning: {w}"));
        }
        let Some(desc) = self.editor.desc(&id).cloned() else {
            ui.colored_label(Color32::from_rgb(255, 120, 120), "unknown node type: no parameters to show");
            return;
        };
        ui.collapsing("About", |ui| {
            ui.label(format!("{} · {}", desc.category, desc.time.name()));
            ui.label(&desc.doc);
        });
        let mut pins = self.canvas.param_pins.contains(&id);
        if ui.checkbox(&mut pins, "Show parameters as pins").changed() {
            self.canvas.toggle_param_pins(&id);
        }
        ui.separator();
        let mut change = None;
        let mut reset = None;
        let frame = self.editor.frame() as f64;
        let fps = self.editor.fps();
        egui::Grid::new(("params", &id)).num_columns(4).striped(true).spacing([8.0, 4.0]).show(ui, |ui| {
            for port in &desc.inputs {
                let label = ui.label(&port.name).on_hover_text(format!("{}: {}\n{}", port.name, port.ty, port.doc));
                let _ = label;
                if let Some(src) = self.editor.incoming(&id, &port.name) {
                    ui.label("");
                    ui.label(RichText::new(format!("from {src}")).italics().color(Color32::from_rgb(140, 190, 250)))
                        .on_hover_text("driven by a connection");
                    ui.label("");
                    ui.end_row();
                    continue;
                }
                if let Some(set) = self.editor.set_by_include(&id, &port.name) {
                    include_setting_cell(ui, &set, nd.params.get(&port.name));
                    continue;
                }
                if !port.ty.is_parameter() {
                    let (t, c) = if port.is_required() {
                        ("not connected (required)", Color32::from_rgb(255, 130, 130))
                    } else {
                        ("default", Color32::GRAY)
                    };
                    ui.label("");
                    ui.label(RichText::new(t).color(c));
                    ui.label("");
                    ui.end_row();
                    continue;
                }
                let set = nd.params.get(&port.name).cloned();
                use pyrograph_frontend::core::PortType as T;
                if matches!(port.ty, T::Float | T::Int | T::Bool | T::Vec2 | T::Vec3 | T::Color) {
                    self.key_toggle_cell(ui, &id, port, set.as_ref());
                } else {
                    ui.label("");
                }
                if let Some(v) = self.value_cell(ui, &id, port, set.as_ref(), frame, fps) {
                    change = Some((port.name.clone(), v));
                }
                if set.is_some() {
                    if ui.small_button("⟲").on_hover_text("reset to default").clicked() {
                        reset = Some(port.name.clone());
                    }
                } else {
                    ui.label("");
                }
                ui.end_row();
            }
        });
        if let Some((name, v)) = change {
            let animated = v.is_animated();
            if let Err(e) = self.editor.set_param(&id, &name, v) {
                self.editor.set_status(e, true);
            }
            // Keys or an expression typed in: one step, as Enter commits them.
            if animated {
                self.editor.seal();
            }
        }
        if let Some(name) = reset {
            self.editor.reset_param(&id, &name);
            self.editor.seal();
        }
    }

    /// The play button and frame slider of a clip of `len` frames, with the key strip under them.
    fn scrubber(&mut self, ui: &mut egui::Ui, req: &crate::cook::PreviewRequest, len: usize) {
        let mut slider = None;
        ui.horizontal(|ui| {
            if ui.button(if self.playback.playing { "⏸" } else { "▶" }).on_hover_text("play / pause (Space)").clicked() {
                self.playback.toggle();
            }
            let mut realtime = self.playback.realtime;
            let tip = "On: play at the clip's frame rate, skipping frames the cook is late for. \
                       Off: show every frame as soon as it has cooked.";
            if ui.checkbox(&mut realtime, "real time").on_hover_text(tip).changed() {
                self.playback.set_realtime(realtime);
            }
            let mut frame = req.frame.min(len - 1);
            let r = ui.add(egui::Slider::new(&mut frame, 0..=len - 1).show_value(false));
            slider = Some(r.rect);
            if r.changed() {
                self.playback.set_playing(false);
                self.editor.set_frame(frame);
            }
            ui.label(format!("frame {} / {}", frame, len - 1));
        });
        if let Some(rect) = slider {
            self.key_strip(ui, &req.node, rect, len);
        }
    }

    /// The value cell of a parameter row: the widget for its type, the row of an animated
    /// value, the raw text of a value of the wrong kind, or a field for a required value.
    fn value_cell(
        &mut self,
        ui: &mut egui::Ui,
        id: &str,
        port: &pyrograph_frontend::core::PortDesc,
        set: Option<&ParamValue>,
        frame: f64,
        fps: f64,
    ) -> Option<ParamValue> {
        let widget_id = egui::Id::new(("param", id, &port.name));
        match self.editor.param_value(id, port) {
            Some(value) if value.is_animated() => animated_row(ui, widget_id, port, &value, frame, fps),
            Some(value) => {
                ui.scope(|ui| {
                    match structured_widget(ui, widget_id, port, &value).or_else(|| param_widget(ui, widget_id, port, &value)) {
                        Some(v) => Some(v),
                        None if set.is_some() && !kind_ok(port, &value) => raw_widget(ui, &value),
                        None => None,
                    }
                })
                .inner
            }
            None => {
                let mut s = String::new();
                let changed = ui.add(egui::TextEdit::singleline(&mut s).hint_text("required")).changed();
                changed.then(|| ParamValue::parse_cli(&s))
            }
        }
    }

    pub(crate) fn advance_playback(&mut self, ctx: &egui::Context) {
        let (len, fps) = self.editor.preview().map_or((0, 24.0), |p| (p.clip_len.unwrap_or(0), p.fps));
        let frame = self.editor.preview_request().map_or(0, |p| p.frame);
        let (ask, wake) = self.playback.step(Instant::now(), frame, len, fps, self.editor.is_cooking());
        // One frame ahead: the next frame cooks while this one is drawn, and an edit made while
        // playing waits for at most that frame.
        self.editor.set_read_ahead(usize::from(self.playback.playing));
        if let Some(f) = ask {
            self.editor.set_frame(f);
        }
        if let Some(wake) = wake {
            ctx.request_repaint_after(wake);
        }
    }

    pub(crate) fn preview_ui(&mut self, ui: &mut egui::Ui) {
        let Some(req) = self.editor.preview_request().cloned() else {
            ui.weak("Select a node to preview its output.");
            return;
        };
        let desc = self.editor.desc(&req.node).cloned();
        ui.horizontal(|ui| {
            ui.label(RichText::new(format!("Preview: {}", req.node)).strong());
            if let Some(desc) = &desc
                && desc.outputs.len() > 1
            {
                let mut out = req.output;
                egui::ComboBox::from_id_salt("preview-output")
                    .selected_text(desc.outputs.get(out).map_or("?", |p| p.name.as_str()))
                    .show_ui(ui, |ui| {
                        for (i, p) in desc.outputs.iter().enumerate() {
                            ui.selectable_value(&mut out, i, &p.name);
                        }
                    });
                if out != req.output {
                    self.editor.set_preview_output(out);
                }
            }
            self.compare_header(ui);
        });
        if self.editor.is_cooking() {
            let st = self.editor.cook_status();
            ui.horizontal(|ui| {
                let (frac, text) = match (st.frames, &st.node) {
                    (Some((d, t)), Some(n)) if t > 0 => (d as f32 / t as f32, format!("{n}: frame {d}/{t}")),
                    (_, Some(n)) => ((st.nodes_done as f32 / st.nodes_total.max(1) as f32).min(1.0), format!("cooking {n}")),
                    _ => (0.0, "cooking…".to_string()),
                };
                ui.add(egui::ProgressBar::new(frac).text(text).desired_width(ui.available_width() - 80.0).animate(true));
                if ui.button("Cancel").clicked() {
                    self.editor.cancel();
                }
            });
        }
        let Some(p) = self.editor.preview().cloned() else {
            ui.weak("waiting for the cook…");
            return;
        };
        if let Some(e) = &p.error {
            ui.colored_label(Color32::from_rgb(255, 120, 120), e);
        }
        if !p.summary.is_empty() {
            ui.label(RichText::new(&p.summary).monospace());
        }
        if let Some(len) = p.clip_len
            && len > 0
        {
            self.scrubber(ui, &req, len);
        }
        if let Some(img) = &p.image {
            crate::compare_ui::upload_texture(ui.ctx(), &mut self.texture, "preview", self.editor.preview_serial(), img);
        }
        if self.editor.compare_request().is_some() {
            self.compare_view(ui, &p);
            return;
        }
        let size = p
            .image
            .as_ref()
            .map(|i| egui::vec2(i.size[0] as f32, i.size[1] as f32))
            .or_else(|| p.contour_size.map(|s| egui::vec2(s[0] as f32, s[1] as f32)));
        let Some(size) = size.filter(|s| s.x > 0.0 && s.y > 0.0) else { return };
        let avail = ui.available_size();
        let scale = (avail.x / size.x).min(avail.y / size.y).max(0.01);
        let (rect, resp) = ui.allocate_exact_size(size * scale, egui::Sense::hover());
        let painter = ui.painter_at(rect);
        match (&p.image, &self.texture) {
            (Some(_), Some((_, tex))) => {
                painter.image(
                    tex.id(),
                    rect,
                    egui::Rect::from_min_max(egui::pos2(0.0, 0.0), egui::pos2(1.0, 1.0)),
                    Color32::WHITE,
                );
            }
            _ => {
                painter.rect_filled(rect, 0.0, Color32::from_gray(20));
            }
        }
        if !p.contours.is_empty() {
            let cs = p.contour_size.map_or(size, |s| egui::vec2(s[0] as f32, s[1] as f32));
            let k = egui::vec2(rect.width() / cs.x.max(1.0), rect.height() / cs.y.max(1.0));
            for c in &p.contours {
                let pts: Vec<egui::Pos2> = c.iter().map(|q| rect.min + egui::vec2(q[0] * k.x, q[1] * k.y)).collect();
                if pts.len() > 1 {
                    painter.add(egui::Shape::closed_line(pts, egui::Stroke::new(1.5, Color32::from_rgb(80, 230, 255))));
                }
            }
        }
        let _ = resp.on_hover_text(format!("{}×{}", size.x, size.y));
    }
}

/// Whether a stored value has the kind the port expects (else the raw editor is offered).
/// The ramp editor or the point list field, for ports of those types (`None` otherwise, and when
/// nothing changed).
fn structured_widget(
    ui: &mut egui::Ui,
    id: egui::Id,
    port: &pyrograph_frontend::core::PortDesc,
    value: &pyrograph_frontend::core::ParamValue,
) -> Option<ParamValue> {
    use pyrograph_frontend::core::PortType;
    match &port.ty {
        PortType::Ramp(width) => crate::gradient::ramp_widget(ui, id, &port.name, *width, value),
        PortType::Points => crate::gradient::points_widget(ui, id, value),
        _ => None,
    }
}

fn kind_ok(port: &pyrograph_frontend::core::PortDesc, v: &pyrograph_frontend::core::ParamValue) -> bool {
    use pyrograph_frontend::core::{ParamValue as P, PortType as T};
    match (&port.ty, v) {
        (T::Float, P::Float(_) | P::Int(_)) | (T::Int, P::Int(_)) | (T::Bool, P::Bool(_)) => true,
        (T::String | T::Path | T::Enum, P::String(_)) => true,
        (T::Color, _) => crate::param_widgets::as_color(v).is_some(),
        (T::Vec2 | T::Vec3, P::List(_)) => true,
        (T::Ramp(width), _) => crate::gradient::read_keys(v, *width).is_some(),
        // The point list's field shows any value as text, a bad one included.
        (T::Points, _) => true,
        _ => false,
    }
}

impl EditorApp {
    /// The inspector of a group (title, colour, its nodes) or a comment (text, colour).
    fn annotation_inspector(&mut self, ui: &mut egui::Ui, which: Annotation) {
        let doc = self.editor.doc();
        let (kind, text, color, members) = match which {
            Annotation::Group(i) => match doc.groups.get(i) {
                Some(g) => ("Group", g.title.clone(), g.color.clone(), g.nodes.clone()),
                None => return,
            },
            Annotation::Comment(i) => match doc.comments.get(i) {
                Some(c) => ("Comment", c.text.clone(), c.color.clone(), Vec::new()),
                None => return,
            },
        };
        ui.heading(kind);
        let multiline = matches!(which, Annotation::Comment(_));
        ui.label(if multiline {
            "Text (click elsewhere or Tab to commit, Escape reverts)"
        } else {
            "Title (Enter commits, Escape reverts)"
        });
        if let Some(t) = buffered_text(ui, egui::Id::new(("annotation-text", format!("{which:?}"))), &text, multiline) {
            match which {
                Annotation::Group(i) => self.editor.set_group_title(i, &t),
                Annotation::Comment(i) => self.editor.set_comment_text(i, &t),
            }
            self.editor.seal();
        }
        ui.horizontal(|ui| {
            ui.label("Colour");
            let fallback = if multiline { COMMENT_COLOR } else { GROUP_COLOR };
            let mut rgb = color.as_deref().and_then(hex_rgb).or_else(|| hex_rgb(fallback)).unwrap_or([128, 128, 128]);
            if ui.color_edit_button_srgb(&mut rgb).changed() {
                self.editor.set_annotation_color(which, &rgb_hex(rgb));
            }
        });
        if !members.is_empty() {
            ui.label(format!("{} node(s): {}", members.len(), members.join(", ")));
            if ui.button("Select its nodes").clicked() {
                self.editor.set_selection(members);
                self.canvas.annotation = None;
            }
        }
        if ui.button(if multiline { "Delete comment" } else { "Ungroup (keeps the nodes)" }).clicked() {
            self.editor.remove_annotation(which);
            self.canvas.annotation = None;
        }
    }
}

/// The inspector row of a parameter the include one level up overrides (see
/// `Editor::set_by_include`): what cooks and where to change it, in place of an editor that
/// would change nothing.
fn include_setting_cell(ui: &mut egui::Ui, set: &IncludeSetting, here: Option<&ParamValue>) {
    let (text, what) = match &set.by {
        SetBy::Value(v) => {
            (format!("{v} (set by {}'s {})", set.include, set.exposed), format!("sets its parameter '{}' to {v}", set.exposed))
        }
        SetBy::Connection(from) => (
            format!("from {from} (through {}'s {})", set.include, set.exposed),
            format!("connects {from} to its parameter '{}'", set.exposed),
        ),
    };
    let inner = here.map_or_else(|| "the default".to_string(), ToString::to_string);
    ui.label("");
    ui.label(RichText::new(text).italics().color(Color32::from_rgb(120, 210, 160))).on_hover_text(format!(
        "The include '{}' one level up {what}, which overrides this graph's value ({inner}) when it cooks. \
         Change it on the include, or unset it there to use this graph's value.",
        set.include
    ));
    ui.label("");
    ui.end_row();
}
