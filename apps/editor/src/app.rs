//! The egui layer: menus, canvas, inspector, preview and status bar over an [`Editor`].

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

use eframe::egui::{self, Color32, Key, Modifiers, RichText};

use crate::annotate::Annotation;
use crate::browser::{PresetBrowser, SavePresetDialog};
use crate::canvas::Canvas;
use crate::key_ui::KeyUi;
use crate::palette::palette_ui;
use crate::state::{Editor, diagnostic_nodes};

mod actions;
mod dump;
mod scope_ui;

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
    pub(crate) texture: Option<(u64, egui::TextureHandle)>,
    /// The B viewer's texture (A/B compare).
    pub(crate) texture_b: Option<(u64, egui::TextureHandle)>,
    /// The preview's player (play / pause, real time, frames dropped).
    pub playback: crate::playback::Playback,
    title: String,
    notify_set: bool,
    first_frame: bool,
    show_problems: bool,
    /// Milliseconds of the latest frames' UI pass (tests check the UI stays responsive).
    pub frame_times: Vec<f64>,
    /// Frames drawn since the window opened.
    pub frames_drawn: u64,
    /// A node to select when the file being opened arrives (`--select NODE`).
    pub select_on_open: Option<String>,
    /// Where to write the state dump (`--state-dump FILE`), for tests that drive a real window.
    pub state_dump: Option<PathBuf>,
    /// The preset browser, when open.
    pub browser: Option<PresetBrowser>,
    /// The "Save selection as preset" dialog, when open.
    pub save_preset: Option<SavePresetDialog>,
    /// Keyframing: the selected keys, the curve editor's view and drag.
    pub key_ui: KeyUi,
    last_dump: String,
    /// The breadcrumb, stepping into includes, and the "Save into preset" confirmation.
    pub scope_ui: scope_ui::ScopeUi,
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
            texture_b: None,
            playback: crate::playback::Playback::default(),
            title: String::new(),
            notify_set: false,
            first_frame: true,
            show_problems: true,
            frame_times: Vec::new(),
            frames_drawn: 0,
            select_on_open: None,
            state_dump: None,
            last_dump: String::new(),
            browser: None,
            save_preset: None,
            key_ui: KeyUi::default(),
            scope_ui: scope_ui::ScopeUi::default(),
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
        if self.editor.poll_open().is_some() {
            self.canvas.frame_all();
            self.texture = None;
            self.playback.set_playing(false);
            if let Some(id) = self.select_on_open.take() {
                self.editor.select(&id);
            }
        }
        if self.editor.opening().is_some() {
            ctx.request_repaint_after(std::time::Duration::from_millis(30));
        }
        self.key_ui.sync(self.editor.current());
        self.handle_keys(&ctx);
        self.key_ui.panel_rect = None;
        self.key_ui.toggle_rects.clear();
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
        if self.curves_wanted() {
            egui::Panel::bottom("curves").resizable(true).default_size(240.0).min_size(140.0).show(ui, |ui| self.curves_ui(ui));
        }
        self.breadcrumb_panel(ui);
        let actions =
            egui::CentralPanel::default().frame(egui::Frame::NONE).show(ui, |ui| self.canvas.show(ui, &self.editor)).inner;
        if self.first_frame {
            self.first_frame = false;
        }
        self.apply(actions);
        self.after_canvas(&ctx);
        self.palette_window(&ctx);
        self.browser_window(&ctx);
        self.save_preset_window(&ctx);
        self.dialog_window(&ctx);
        self.preset_confirm_window(&ctx);
        self.toast(&ctx);

        if self.editor.is_cooking() {
            ctx.request_repaint_after(std::time::Duration::from_millis(50));
        }
        self.write_state_dump(&ctx);
        self.frame_times.push(start.elapsed().as_secs_f64() * 1000.0);
        self.frames_drawn += 1;
        if self.frame_times.len() > 1000 {
            self.frame_times.drain(..500);
        }
    }

    fn after_canvas(&mut self, ctx: &egui::Context) {
        let idle = !ctx.input(|i| i.pointer.any_down());
        if idle {
            let moved = self.canvas.moved_nodes();
            if !moved.is_empty() {
                let one = (moved.len() == 1).then(|| moved[0].0.clone());
                for (id, p) in moved {
                    self.editor.move_node(&id, (p.x, p.y));
                }
                self.editor.seal();
                // One unwired node dropped onto a wire is spliced into it, with the drag one undo step.
                if let Some(id) = one
                    && let Some((from, to)) = self.canvas.wire_through(self.editor.doc(), &id)
                {
                    let _ = self.editor.insert_on_wire(&id, &from, &to, true);
                }
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
            let new = self.editor.duplicate(&sel);
            self.editor.set_selection(new);
        }
        if typing {
            return;
        }
        self.clipboard_events(ctx);
        let (tab, del, frame, home, space, esc) = ctx.input_mut(|i| {
            (
                i.consume_key(Modifiers::NONE, Key::Tab),
                i.consume_key(Modifiers::NONE, Key::Delete) || i.consume_key(Modifiers::NONE, Key::Backspace),
                i.consume_key(Modifiers::NONE, Key::F),
                i.consume_key(Modifiers::NONE, Key::Home),
                i.consume_key(Modifiers::NONE, Key::Space),
                // Read, not consumed: a text field that Escape just left reverts on it too.
                i.key_pressed(Key::Escape),
            )
        });
        let collapse = ctx.input_mut(|i| i.consume_key(cmd | Modifiers::SHIFT, Key::G));
        if collapse {
            let sel = self.editor.selection().to_vec();
            self.apply(vec![crate::action::Action::Collapse(sel)]);
        }
        let (all, group, comment, map, bypass) = ctx.input_mut(|i| {
            (
                i.consume_key(cmd, Key::A),
                i.consume_key(cmd, Key::G),
                i.consume_key(Modifiers::SHIFT, Key::C),
                i.consume_key(Modifiers::NONE, Key::M),
                i.consume_key(Modifiers::NONE, Key::B),
            )
        });
        if bypass {
            let sel = self.editor.selection().to_vec();
            self.editor.toggle_bypass(&sel);
        }
        self.scope_keys(ctx);
        if tab {
            self.open_palette(ctx);
        }
        if del {
            self.delete_selected_keys_or_nodes();
        }
        if frame && self.key_ui.hovered(ctx) {
            self.key_ui.request_fit();
        } else if frame {
            let sel = self.editor.selection().to_vec();
            self.canvas.frame_nodes(&sel);
        }
        if home {
            self.canvas.frame_all();
        }
        if space {
            self.playback.toggle();
        }
        if esc {
            self.palette_open = None;
        }
        if all {
            let ids = self.editor.doc().nodes.0.iter().map(|(id, _)| id.clone()).collect();
            self.editor.set_selection(ids);
        }
        if group {
            self.group_selected();
        }
        if comment {
            self.add_comment_at_pointer(ctx);
        }
        if map {
            self.canvas.show_minimap = !self.canvas.show_minimap;
        }
    }

    /// Ctrl+C, Ctrl+X and Ctrl+V arrive as clipboard events (the window system reads and
    /// writes the clipboard); the nodes travel as RON text.
    fn clipboard_events(&mut self, ctx: &egui::Context) {
        let events: Vec<egui::Event> = ctx.input(|i| {
            i.events
                .iter()
                .filter(|e| matches!(e, egui::Event::Copy | egui::Event::Cut | egui::Event::Paste(_)))
                .cloned()
                .collect()
        });
        for e in events {
            match e {
                egui::Event::Copy | egui::Event::Cut => {
                    let sel = self.editor.selection().to_vec();
                    if let Some(text) = self.editor.copy_text(&sel) {
                        ctx.copy_text(text);
                        self.editor.set_status(format!("copied {} node(s)", sel.len()), false);
                        if e == egui::Event::Cut {
                            self.editor.remove_nodes(&sel);
                        }
                    }
                }
                egui::Event::Paste(text) => {
                    let at = ctx.input(|i| i.pointer.latest_pos()).filter(|p| self.canvas.rect_contains(*p));
                    let at = at.map(|p| self.canvas.to_graph(p)).unwrap_or_else(|| self.canvas.view_center());
                    if let Err(e) = self.editor.paste_text(&text, Some((at.x, at.y))) {
                        self.editor.set_status(e, true);
                    }
                }
                _ => {}
            }
        }
    }

    /// Deletes the selected keys of the current node if any are selected (in the curve editor or
    /// the key strip), else the selected nodes, group or comment.
    pub fn delete_selected_keys_or_nodes(&mut self) {
        let keys = self.key_ui.selected().to_vec();
        if let (false, Some(node)) = (keys.is_empty(), self.editor.current().map(str::to_string)) {
            let _ = self.editor.delete_keys_at(&node, &keys);
            self.key_ui.clear_selection();
            return;
        }
        self.delete_selected();
    }

    /// Deletes the selected nodes, or else the selected group (its nodes stay) or comment.
    pub fn delete_selected(&mut self) {
        let sel = self.editor.selection().to_vec();
        if !sel.is_empty() {
            self.editor.remove_nodes(&sel);
        } else if let Some(a) = self.canvas.annotation.take() {
            self.editor.remove_annotation(a);
        }
    }

    /// Groups the selected nodes (Ctrl+G) and selects the new group for naming.
    pub fn group_selected(&mut self) {
        let sel = self.editor.selection().to_vec();
        if let Some(i) = self.editor.group_nodes(&sel, "Group") {
            self.editor.set_selection(Vec::new());
            self.canvas.annotation = Some(Annotation::Group(i));
        }
    }

    /// Adds a comment under the pointer (Shift+C) and selects it for typing.
    pub fn add_comment_at_pointer(&mut self, ctx: &egui::Context) {
        let at = ctx.input(|i| i.pointer.latest_pos()).filter(|p| self.canvas.rect_contains(*p));
        let at = at.map(|p| self.canvas.to_graph(p)).unwrap_or_else(|| self.canvas.view_center());
        let i = self.editor.add_comment("Comment", (at.x, at.y));
        self.editor.set_selection(Vec::new());
        self.canvas.annotation = Some(Annotation::Comment(i));
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

    /// Opens the preset browser (reading the library afresh) with the search field focused.
    pub fn open_preset_browser(&mut self) {
        self.browser.get_or_insert_with(PresetBrowser::default).reopen();
    }

    /// Whether the preset browser is open.
    pub fn preset_browser_is_open(&self) -> bool {
        self.browser.is_some()
    }

    /// Opens "Save selection as preset" for the selected nodes.
    pub fn open_save_selection_as_preset(&mut self) {
        if self.editor.selection().is_empty() {
            self.editor.set_status("select the nodes to save as a preset first", true);
            return;
        }
        self.save_preset = Some(SavePresetDialog::focused());
    }

    /// The preset browser's window, while it is open.
    fn browser_window(&mut self, ctx: &egui::Context) {
        let Some(mut b) = self.browser.take() else { return };
        if b.window(ctx, &mut self.editor, &self.canvas) {
            self.browser = Some(b);
        }
    }

    /// The "Save selection as preset" dialog, while it is open.
    fn save_preset_window(&mut self, ctx: &egui::Context) {
        let Some(mut d) = self.save_preset.take() else { return };
        if d.window(ctx, &mut self.editor, self.browser.as_mut()) {
            self.save_preset = Some(d);
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

    /// Opens `path` on a loader thread; the canvas frames it when it arrives (see `ui`).
    fn open_file(&mut self, path: PathBuf) {
        self.editor.begin_open(&path);
    }

    fn menu_bar(&mut self, ui: &mut egui::Ui) {
        egui::MenuBar::new().ui(ui, |ui| {
            ui.menu_button("File", |ui| self.file_menu(ui));
            ui.menu_button("Presets", |ui| self.presets_menu(ui));
            ui.menu_button("Edit", |ui| self.edit_menu(ui));
            ui.menu_button("Add", |ui| self.add_menu(ui));
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
            ui.weak(
                "Tab: add node · click / Shift-click / drag: select · F: frame selection · Ctrl+C/V: copy/paste · Ctrl+G: group",
            );
        });
    }

    /// The File menu: new, open (and open recent), save and save as.
    fn file_menu(&mut self, ui: &mut egui::Ui) {
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
            let cur =
                self.editor.path().map_or_else(|| format!("{}untitled.ron", self.default_dir()), |p| p.display().to_string());
            self.dialog = Some(FileDialog::SaveAs(cur));
            ui.close();
        }
        ui.separator();
        if ui.button("Reload plugins").on_hover_text("Read the Python plugin files again after editing them").clicked() {
            self.editor.reload_plugins();
            ui.close();
        }
    }

    /// The Presets menu: the preset browser and saving the selection as a preset.
    fn presets_menu(&mut self, ui: &mut egui::Ui) {
        if ui.button("Preset browser…").clicked() {
            self.open_preset_browser();
            ui.close();
        }
        let any = !self.editor.selection().is_empty();
        if ui.add_enabled(any, egui::Button::new("Save selection as preset…")).clicked() {
            self.open_save_selection_as_preset();
            ui.close();
        }
    }

    /// The Edit menu: undo and redo, the selection (copy, duplicate, delete, group), comments,
    /// framing the view, the minimap and the frame cache.
    fn edit_menu(&mut self, ui: &mut egui::Ui) {
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
        if ui.add_enabled(!sel.is_empty(), egui::Button::new("Copy  (Ctrl+C)")).clicked() {
            if let Some(text) = self.editor.copy_text(&sel) {
                ui.ctx().copy_text(text);
            }
            ui.close();
        }
        if ui.add_enabled(!sel.is_empty(), egui::Button::new("Duplicate  (Ctrl+D)")).clicked() {
            let new = self.editor.duplicate(&sel);
            self.editor.set_selection(new);
            ui.close();
        }
        if ui.add_enabled(!sel.is_empty() || self.canvas.annotation.is_some(), egui::Button::new("Delete  (Del)")).clicked() {
            self.delete_selected();
            ui.close();
        }
        if ui.button("Select all  (Ctrl+A)").clicked() {
            let ids = self.editor.doc().nodes.0.iter().map(|(id, _)| id.clone()).collect();
            self.editor.set_selection(ids);
            ui.close();
        }
        ui.separator();
        if ui.add_enabled(!sel.is_empty(), egui::Button::new("Group selection  (Ctrl+G)")).clicked() {
            self.group_selected();
            ui.close();
        }
        if ui.button("Add comment  (Shift+C)").clicked() {
            let at = self.canvas.view_center();
            let i = self.editor.add_comment("Comment", (at.x, at.y));
            self.canvas.annotation = Some(Annotation::Comment(i));
            ui.close();
        }
        ui.separator();
        if ui.button("Frame selection  (F)").clicked() {
            self.canvas.frame_nodes(&sel);
            ui.close();
        }
        if ui.button("Frame all  (Home)").clicked() {
            self.canvas.frame_all();
            ui.close();
        }
        ui.checkbox(&mut self.canvas.show_minimap, "Minimap  (M)");
        ui.checkbox(&mut self.key_ui.show_curves, "Curve editor (for animated parameters)");
        ui.separator();
        frame_cache_ui(ui);
        let mut outside = crate::state::allow_outside_out();
        let tip = "Let writer nodes write outside the graph's folder (absolute paths, paths climbing out with ..), \
                   as the command line's --allow-outside-out does. Off by default and for each new session.";
        if ui.checkbox(&mut outside, "Writes outside the graph's folder").on_hover_text(tip).changed() {
            self.editor.set_allow_outside_out(outside);
        }
    }

    /// The Add menu: the node palette, adding at the centre of the view.
    fn add_menu(&mut self, ui: &mut egui::Ui) {
        ui.set_min_width(320.0);
        if let Some(item) = palette_ui(ui, &self.editor, &mut self.palette_query, false) {
            let pos = self.canvas.view_center();
            self.add_item(&item, pos);
            self.palette_query.clear();
            ui.close();
        }
    }

    fn status_bar(&mut self, ui: &mut egui::Ui) {
        ui.horizontal(|ui| {
            if self.editor.is_dirty() {
                ui.label(RichText::new("● modified").color(Color32::from_rgb(240, 190, 80)));
            }
            if let Some((path, elapsed)) = self.editor.opening() {
                ui.spinner();
                ui.label(format!("opening {}… {:.1} s", path.display(), elapsed.as_secs_f64()));
            } else if let Some(s) = self.editor.status() {
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
                    && let Some(n) = nodes.iter().find(|n| self.editor.node_doc(n).is_some())
                {
                    self.editor.select(n);
                    self.canvas.focus_node(n);
                }
            }
        });
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

impl eframe::App for EditorApp {
    fn ui(&mut self, ui: &mut egui::Ui, _frame: &mut eframe::Frame) {
        EditorApp::ui(self, ui);
    }
}

/// The frame-cache preference: the budget every clip's cached frames share, and what it holds.
fn frame_cache_ui(ui: &mut egui::Ui) {
    let cache = pyrograph_frontend::core::FrameCache::global();
    let stats = cache.stats();
    let mut mib = stats.budget >> 20;
    ui.horizontal(|ui| {
        ui.label("Frame cache");
        let drag = egui::DragValue::new(&mut mib).range(16..=1 << 20).suffix(" MiB").speed(16.0);
        if ui.add(drag).on_hover_text("Memory for cooked frames of every clip; older frames are recomputed").changed() {
            cache.set_budget(mib << 20);
        }
    });
    ui.weak(format!("holds {} frames, {} MiB; {} hits, {} misses", stats.frames, stats.bytes >> 20, stats.hits, stats.misses));
}
