//! The egui layer: menus, canvas, inspector, preview and status bar over an [`Editor`].

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

use eframe::egui::{self, Color32, Key, Modifiers, RichText};

use crate::canvas::{Action, Canvas, palette_ui};
use crate::params::{param_widget, raw_widget};
use crate::state::{Editor, diagnostic_nodes};

/// Which file dialog is open (a plain path field: no native dialogs needed).
#[derive(Clone, Debug, PartialEq)]
enum FileDialog {
    Open(String),
    SaveAs(String),
}

/// The editor application.
pub struct EditorApp {
    /// The editor logic (document, history, validation, cooking).
    pub editor: Editor,
    /// The canvas view.
    pub canvas: Canvas,
    palette_open: Option<egui::Pos2>,
    palette_focus: bool,
    palette_query: String,
    dialog: Option<FileDialog>,
    texture: Option<(u64, egui::TextureHandle)>,
    playing: bool,
    last_advance: Instant,
    title: String,
    notify_set: bool,
    first_frame: bool,
    show_problems: bool,
    /// Milliseconds of the latest frames' UI pass (tests check the UI stays responsive).
    pub frame_times: Vec<f64>,
}

impl EditorApp {
    /// An app over `editor`.
    pub fn new(editor: Editor) -> Self {
        EditorApp {
            editor,
            canvas: Canvas::new(),
            palette_open: None,
            palette_focus: false,
            palette_query: String::new(),
            dialog: None,
            texture: None,
            playing: false,
            last_advance: Instant::now(),
            title: String::new(),
            notify_set: false,
            first_frame: true,
            show_problems: true,
            frame_times: Vec::new(),
        }
    }

    /// Whether the node palette window is open.
    pub fn palette_is_open(&self) -> bool {
        self.palette_open.is_some()
    }

    /// Draws one frame.
    pub fn ui(&mut self, ui: &mut egui::Ui) {
        let start = Instant::now();
        let ctx = ui.ctx().clone();
        if !self.notify_set {
            let c = ctx.clone();
            self.editor.set_notify(Arc::new(move || c.request_repaint()));
            self.notify_set = true;
        }
        self.editor.poll();
        self.handle_keys(&ctx);
        self.advance_playback(&ctx);

        let title = self.editor.title();
        if title != self.title {
            ctx.send_viewport_cmd(egui::ViewportCommand::Title(title.clone()));
            self.title = title;
        }

        egui::Panel::top("menu").show(ui, |ui| self.menu_bar(ui));
        egui::Panel::bottom("status").show(ui, |ui| self.status_bar(ui));
        if self.show_problems && !self.editor.validation().diagnostics.is_empty() {
            egui::Panel::bottom("problems").resizable(true).default_size(120.0).show(ui, |ui| self.problems_ui(ui));
        }
        egui::Panel::right("side").resizable(true).default_size(440.0).min_size(280.0).show(ui, |ui| {
            let h = ui.available_height();
            egui::Panel::top("inspector").resizable(true).default_size(h * 0.45).show(ui, |ui| {
                egui::ScrollArea::vertical().auto_shrink([false, false]).show(ui, |ui| self.inspector(ui));
            });
            egui::CentralPanel::default().show(ui, |ui| self.preview_ui(ui));
        });
        let actions =
            egui::CentralPanel::default().frame(egui::Frame::NONE).show(ui, |ui| self.canvas.show(ui, &self.editor)).inner;
        if self.first_frame {
            self.first_frame = false;
        }
        self.apply(actions);
        self.after_canvas(&ctx);
        self.palette_window(&ctx);
        self.dialog_window(&ctx);
        self.toast(&ctx);

        if self.editor.is_cooking() {
            ctx.request_repaint_after(std::time::Duration::from_millis(50));
        }
        self.frame_times.push(start.elapsed().as_secs_f64() * 1000.0);
        if self.frame_times.len() > 1000 {
            self.frame_times.drain(..500);
        }
    }

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
                Action::Remove(ids) => self.editor.remove_nodes(&ids),
                Action::Duplicate(ids) => {
                    self.editor.duplicate(&ids);
                }
                Action::ToggleParamPins(id) => self.canvas.toggle_param_pins(&id),
                Action::Preview(id) => self.editor.select(&id),
            }
        }
    }

    fn add_item(&mut self, item: &crate::state::PaletteItem, pos: egui::Pos2) {
        let r = match &item.preset {
            Some(file) => self.editor.add_preset(file, (pos.x, pos.y)),
            None => self.editor.add_node(&item.type_name, (pos.x, pos.y)),
        };
        match r {
            Ok(id) => self.editor.select(&id),
            Err(e) => self.editor.set_status(e, true),
        }
    }

    fn after_canvas(&mut self, ctx: &egui::Context) {
        if let Some(sel) = self.canvas.selection_change(ctx) {
            self.editor.set_selection(sel);
        }
        let idle = !ctx.input(|i| i.pointer.any_down());
        if idle {
            let moved = self.canvas.moved_nodes();
            if !moved.is_empty() {
                for (id, p) in moved {
                    self.editor.move_node(&id, (p.x, p.y));
                }
                self.editor.seal();
            }
            if !ctx.egui_wants_keyboard_input() {
                self.editor.seal();
            }
        }
    }

    fn handle_keys(&mut self, ctx: &egui::Context) {
        let typing = ctx.egui_wants_keyboard_input();
        let cmd = Modifiers::COMMAND;
        let (redo, undo, redo2, save, open, dup) = ctx.input_mut(|i| {
            (
                i.consume_key(cmd | Modifiers::SHIFT, Key::Z),
                i.consume_key(cmd, Key::Z),
                i.consume_key(cmd, Key::Y),
                i.consume_key(cmd, Key::S),
                i.consume_key(cmd, Key::O),
                !typing && i.consume_key(cmd, Key::D),
            )
        });
        if redo || redo2 {
            self.editor.redo();
        } else if undo && !typing {
            self.editor.undo();
        }
        if save {
            self.save();
        }
        if open {
            self.dialog = Some(FileDialog::Open(self.default_dir()));
        }
        if dup {
            let sel = self.editor.selection().to_vec();
            self.editor.duplicate(&sel);
        }
        if typing {
            return;
        }
        let (tab, del, frame, space, esc) = ctx.input_mut(|i| {
            (
                i.consume_key(Modifiers::NONE, Key::Tab),
                i.consume_key(Modifiers::NONE, Key::Delete) || i.consume_key(Modifiers::NONE, Key::Backspace),
                i.consume_key(Modifiers::NONE, Key::F) || i.consume_key(Modifiers::NONE, Key::Home),
                i.consume_key(Modifiers::NONE, Key::Space),
                i.consume_key(Modifiers::NONE, Key::Escape),
            )
        });
        if tab {
            self.open_palette(ctx);
        }
        if del {
            let sel = self.editor.selection().to_vec();
            if !sel.is_empty() {
                self.editor.remove_nodes(&sel);
            }
        }
        if frame {
            self.canvas.frame_all();
        }
        if space {
            self.playing = !self.playing;
        }
        if esc {
            self.palette_open = None;
        }
    }

    /// Opens the node palette at the pointer (Tab).
    pub fn open_palette(&mut self, ctx: &egui::Context) {
        let p = ctx.input(|i| i.pointer.latest_pos()).unwrap_or(egui::pos2(300.0, 200.0));
        self.palette_open = Some(p);
        self.palette_focus = true;
        self.palette_query.clear();
    }

    fn palette_window(&mut self, ctx: &egui::Context) {
        let Some(at) = self.palette_open else { return };
        let mut open = true;
        let mut picked = None;
        egui::Window::new("Add node").open(&mut open).fixed_pos(at).collapsible(false).resizable(false).show(ctx, |ui| {
            ui.set_min_width(320.0);
            picked = palette_ui(ui, &self.editor, &mut self.palette_query, self.palette_focus);
        });
        self.palette_focus = false;
        if let Some(item) = picked {
            let pos = self.canvas.to_graph(at);
            self.add_item(&item, pos);
            open = false;
        }
        if !open {
            self.palette_open = None;
        }
    }

    fn default_dir(&self) -> String {
        let mut d = self.editor.base_dir().display().to_string();
        if !d.ends_with('/') {
            d.push('/');
        }
        d
    }

    fn save(&mut self) {
        if self.editor.path().is_some() {
            let _ = self.editor.save();
        } else {
            self.dialog = Some(FileDialog::SaveAs(format!("{}untitled.ron", self.default_dir())));
        }
    }

    fn open_file(&mut self, path: PathBuf) {
        let _ = self.editor.open(&path);
        self.canvas.frame_all();
        self.texture = None;
        self.playing = false;
    }

    fn menu_bar(&mut self, ui: &mut egui::Ui) {
        egui::MenuBar::new().ui(ui, |ui| {
            ui.menu_button("File", |ui| {
                if ui.button("New").clicked() {
                    self.editor.new_document();
                    ui.close();
                }
                if ui.button("Open…  (Ctrl+O)").clicked() {
                    self.dialog = Some(FileDialog::Open(self.default_dir()));
                    ui.close();
                }
                ui.menu_button("Open recent", |ui| {
                    let recent = self.editor.recent().to_vec();
                    if recent.is_empty() {
                        ui.weak("nothing yet");
                    }
                    for p in recent {
                        if ui.button(p.display().to_string()).clicked() {
                            self.open_file(p);
                            ui.close();
                        }
                    }
                });
                if ui.button("Save  (Ctrl+S)").clicked() {
                    self.save();
                    ui.close();
                }
                if ui.button("Save as…").clicked() {
                    let cur = self
                        .editor
                        .path()
                        .map_or_else(|| format!("{}untitled.ron", self.default_dir()), |p| p.display().to_string());
                    self.dialog = Some(FileDialog::SaveAs(cur));
                    ui.close();
                }
            });
            ui.menu_button("Edit", |ui| {
                if ui.add_enabled(self.editor.can_undo(), egui::Button::new("Undo  (Ctrl+Z)")).clicked() {
                    self.editor.undo();
                    ui.close();
                }
                if ui.add_enabled(self.editor.can_redo(), egui::Button::new("Redo  (Ctrl+Shift+Z)")).clicked() {
                    self.editor.redo();
                    ui.close();
                }
                ui.separator();
                let sel = self.editor.selection().to_vec();
                if ui.add_enabled(!sel.is_empty(), egui::Button::new("Duplicate  (Ctrl+D)")).clicked() {
                    self.editor.duplicate(&sel);
                    ui.close();
                }
                if ui.add_enabled(!sel.is_empty(), egui::Button::new("Delete  (Del)")).clicked() {
                    self.editor.remove_nodes(&sel);
                    ui.close();
                }
                if ui.button("Frame all  (F)").clicked() {
                    self.canvas.frame_all();
                    ui.close();
                }
            });
            ui.menu_button("Add", |ui| {
                ui.set_min_width(320.0);
                if let Some(item) = palette_ui(ui, &self.editor, &mut self.palette_query, false) {
                    let pos = self.canvas.view_center();
                    self.add_item(&item, pos);
                    self.palette_query.clear();
                    ui.close();
                }
            });
            ui.separator();
            let has_graph = self.editor.validation().graph.is_some();
            if ui.add_enabled(has_graph, egui::Button::new("▶ Render")).on_hover_text("Cook the writer nodes").clicked()
                && let Err(e) = self.editor.render()
            {
                self.editor.set_status(e, true);
            }
            if self.editor.is_cooking() && ui.button("■ Cancel").clicked() {
                self.editor.cancel();
            }
            ui.separator();
            ui.weak("Tab / right-click: add node · F: frame all · Del: delete · Ctrl+D: duplicate");
        });
    }

    fn status_bar(&mut self, ui: &mut egui::Ui) {
        ui.horizontal(|ui| {
            if self.editor.is_dirty() {
                ui.label(RichText::new("● modified").color(Color32::from_rgb(240, 190, 80)));
            }
            if let Some(s) = self.editor.status() {
                let color = if s.error { Color32::from_rgb(255, 110, 110) } else { ui.visuals().text_color() };
                ui.label(RichText::new(&s.text).color(color));
            }
            ui.with_layout(egui::Layout::right_to_left(egui::Align::Center), |ui| {
                let n = self.editor.validation().diagnostics.len();
                if n > 0 && ui.link(RichText::new(format!("{n} problem(s)")).color(Color32::from_rgb(255, 110, 110))).clicked() {
                    self.show_problems = !self.show_problems;
                }
                if let Some(o) = self.editor.last_outcome() {
                    ui.weak(format!("last cook {:.0} ms, {} node(s) cooked", o.elapsed.as_secs_f64() * 1000.0, o.log.len()));
                }
            });
        });
    }

    fn problems_ui(&mut self, ui: &mut egui::Ui) {
        ui.label(RichText::new("Problems").strong());
        let diags = self.editor.validation().diagnostics.clone();
        egui::ScrollArea::vertical().auto_shrink([false, true]).show(ui, |ui| {
            for d in &diags {
                let text = format!("{}: {}", d.location, d.message);
                let nodes = diagnostic_nodes(d);
                let r = ui.add(
                    egui::Label::new(RichText::new(format!("⚠ {text}")).color(Color32::from_rgb(255, 130, 130)))
                        .sense(egui::Sense::click()),
                );
                if r.clicked()
                    && let Some(n) = nodes.iter().find(|n| self.editor.doc().node(n).is_some())
                {
                    self.editor.select(n);
                    self.canvas.focus_node(n);
                }
            }
        });
    }

    fn inspector(&mut self, ui: &mut egui::Ui) {
        let Some(id) = self.editor.selection().first().cloned() else {
            ui.weak("Select a node to edit its parameters.");
            return;
        };
        let Some(nd) = self.editor.doc().node(&id).cloned() else { return };
        ui.horizontal(|ui| {
            ui.heading(&id);
            ui.weak(&nd.type_name);
        });
        for p in self.editor.node_problems(&id) {
            ui.colored_label(Color32::from_rgb(255, 120, 120), format!("⚠ {p}"));
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
        egui::Grid::new(("params", &id)).num_columns(3).striped(true).spacing([8.0, 4.0]).show(ui, |ui| {
            for port in &desc.inputs {
                let label = ui.label(&port.name).on_hover_text(format!("{}: {}\n{}", port.name, port.ty, port.doc));
                let _ = label;
                if let Some(src) = self.editor.incoming(&id, &port.name) {
                    ui.label(RichText::new(format!("from {src}")).italics().color(Color32::from_rgb(140, 190, 250)))
                        .on_hover_text("driven by a connection");
                    ui.label("");
                    ui.end_row();
                    continue;
                }
                if !port.ty.is_parameter() {
                    let (t, c) = if port.is_required() {
                        ("not connected (required)", Color32::from_rgb(255, 130, 130))
                    } else {
                        ("default", Color32::GRAY)
                    };
                    ui.label(RichText::new(t).color(c));
                    ui.label("");
                    ui.end_row();
                    continue;
                }
                let set = nd.params.get(&port.name).cloned();
                let widget_id = egui::Id::new(("param", &id, &port.name));
                match self.editor.param_value(&id, port) {
                    Some(value) => {
                        let r = ui
                            .scope(|ui| {
                                let r = param_widget(ui, widget_id, port, &value);
                                match r {
                                    Some(v) => Some(v),
                                    None if set.is_some() && !kind_ok(port, &value) => raw_widget(ui, &value),
                                    None => None,
                                }
                            })
                            .inner;
                        if let Some(v) = r {
                            change = Some((port.name.clone(), v));
                        }
                    }
                    None => {
                        let mut s = String::new();
                        if ui.add(egui::TextEdit::singleline(&mut s).hint_text("required")).changed() {
                            change = Some((port.name.clone(), pyrograph::core::ParamValue::parse_cli(&s)));
                        }
                    }
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
        if let Some((name, v)) = change
            && let Err(e) = self.editor.set_param(&id, &name, v)
        {
            self.editor.set_status(e, true);
        }
        if let Some(name) = reset {
            self.editor.reset_param(&id, &name);
            self.editor.seal();
        }
    }

    fn advance_playback(&mut self, ctx: &egui::Context) {
        if !self.playing {
            return;
        }
        let (len, fps) = match self.editor.preview() {
            Some(p) => (p.clip_len.unwrap_or(0), if p.fps > 0.0 { p.fps } else { 24.0 }),
            None => (0, 24.0),
        };
        if len == 0 {
            self.playing = false;
            return;
        }
        let period = 1.0 / fps;
        if !self.editor.is_cooking() && self.last_advance.elapsed().as_secs_f64() >= period {
            let frame = self.editor.preview_request().map_or(0, |p| p.frame);
            self.editor.set_frame((frame + 1) % len);
            self.last_advance = Instant::now();
        }
        ctx.request_repaint_after(std::time::Duration::from_secs_f64(period / 2.0));
    }

    fn preview_ui(&mut self, ui: &mut egui::Ui) {
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
            ui.horizontal(|ui| {
                if ui.button(if self.playing { "⏸" } else { "▶" }).on_hover_text("play / pause (Space)").clicked() {
                    self.playing = !self.playing;
                    self.last_advance = Instant::now();
                }
                let mut frame = req.frame.min(len - 1);
                let r = ui.add(egui::Slider::new(&mut frame, 0..=len - 1).show_value(false));
                if r.changed() {
                    self.playing = false;
                    self.editor.set_frame(frame);
                }
                ui.label(format!("frame {} / {}", frame, len - 1));
            });
        }
        let serial = self.editor.preview_serial();
        if let Some(img) = &p.image {
            let stale = self.texture.as_ref().is_none_or(|(s, _)| *s != serial);
            if stale {
                let ci = egui::ColorImage::from_rgba_unmultiplied(img.size, &img.rgba);
                match &mut self.texture {
                    Some((s, t)) => {
                        t.set(ci, egui::TextureOptions::LINEAR);
                        *s = serial;
                    }
                    None => self.texture = Some((serial, ui.ctx().load_texture("preview", ci, egui::TextureOptions::LINEAR))),
                }
            }
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

    fn dialog_window(&mut self, ctx: &egui::Context) {
        let Some(dialog) = self.dialog.clone() else { return };
        let (title, mut text, is_open) = match dialog {
            FileDialog::Open(t) => ("Open graph", t, true),
            FileDialog::SaveAs(t) => ("Save graph as", t, false),
        };
        let mut open = true;
        let mut go = false;
        let mut pick: Option<PathBuf> = None;
        egui::Window::new(title).open(&mut open).collapsible(false).default_width(520.0).show(ctx, |ui| {
            let r = ui.add(egui::TextEdit::singleline(&mut text).desired_width(f32::INFINITY));
            go = r.lost_focus() && ui.input(|i| i.key_pressed(Key::Enter));
            if is_open {
                ui.label("Graphs here:");
                let dir = PathBuf::from(&text);
                let dir = if dir.is_dir() { dir } else { dir.parent().map(PathBuf::from).unwrap_or_default() };
                egui::ScrollArea::vertical().max_height(240.0).show(ui, |ui| {
                    let mut entries: Vec<PathBuf> = std::fs::read_dir(&dir)
                        .map(|rd| rd.filter_map(|e| e.ok()).map(|e| e.path()).collect())
                        .unwrap_or_default();
                    entries.sort();
                    for e in entries {
                        let name = e.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
                        if e.is_dir() {
                            if ui.selectable_label(false, format!("📁 {name}/")).clicked() {
                                text = format!("{}/", e.display());
                            }
                        } else if e.extension().is_some_and(|x| x == "ron") && ui.selectable_label(false, &name).clicked() {
                            pick = Some(e);
                        }
                    }
                });
            }
            ui.horizontal(|ui| {
                if ui.button(if is_open { "Open" } else { "Save" }).clicked() {
                    go = true;
                }
            });
        });
        if let Some(p) = pick {
            self.dialog = None;
            self.open_file(p);
            return;
        }
        if go {
            self.dialog = None;
            let path = PathBuf::from(text.trim());
            if is_open {
                self.open_file(path);
            } else {
                let _ = self.editor.save_as(&path);
            }
            return;
        }
        self.dialog = if open { Some(if is_open { FileDialog::Open(text) } else { FileDialog::SaveAs(text) }) } else { None };
    }

    fn toast(&mut self, ctx: &egui::Context) {
        let Some(s) = self.editor.status() else { return };
        let age = s.at.elapsed().as_secs_f32();
        if !s.error || age > 5.0 {
            return;
        }
        let text = s.text.clone();
        egui::Area::new(egui::Id::new("toast"))
            .anchor(egui::Align2::CENTER_BOTTOM, egui::vec2(0.0, -48.0))
            .order(egui::Order::Foreground)
            .show(ctx, |ui| {
                egui::Frame::popup(ui.style()).fill(Color32::from_rgb(90, 20, 20)).show(ui, |ui| {
                    ui.set_max_width(600.0);
                    ui.label(RichText::new(text).color(Color32::WHITE));
                });
            });
        ctx.request_repaint_after(std::time::Duration::from_millis(250));
    }
}

/// Whether a stored value has the kind the port expects (else the raw editor is offered).
fn kind_ok(port: &pyrograph::core::PortDesc, v: &pyrograph::core::ParamValue) -> bool {
    use pyrograph::core::{ParamValue as P, PortType as T};
    match (&port.ty, v) {
        (T::Float, P::Float(_) | P::Int(_)) | (T::Int, P::Int(_)) | (T::Bool, P::Bool(_)) => true,
        (T::String | T::Path | T::Enum, P::String(_)) => true,
        (T::Color, _) => crate::params::as_color(v).is_some(),
        (T::Vec2 | T::Vec3, P::List(_)) => true,
        _ => false,
    }
}

impl eframe::App for EditorApp {
    fn ui(&mut self, ui: &mut egui::Ui, _frame: &mut eframe::Frame) {
        EditorApp::ui(self, ui);
    }
}
