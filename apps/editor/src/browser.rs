//! The preset browser and "Save selection as preset" (issue 30): a window listing the presets on
//! the search path with their thumbnails, tags and a search field; click a preset to insert it at
//! the centre of the canvas, or drag it onto the canvas to drop it where the pointer is. Either
//! way it becomes a `graph.include` node with the preset's exposed ports.

use std::collections::{BTreeSet, HashMap};
use std::path::{Path, PathBuf};

use eframe::egui::{self, Color32, RichText};
use pyrograph_frontend::presets::Preset;

use crate::canvas::Canvas;
use crate::state::{Editor, SelectionPreset, filter_presets};

/// Thumbnail size in the browser, in points (half the files' 256×144).
const THUMB: egui::Vec2 = egui::vec2(128.0, 72.0);

/// The browser's state: the search, the tags ticked, and what was read from disk.
#[derive(Default)]
pub struct PresetBrowser {
    /// Words every listed preset contains (name, description or tags).
    pub query: String,
    /// Tags every listed preset carries.
    pub tags: BTreeSet<String>,
    focus: bool,
    presets: Option<Vec<Preset>>,
    thumbs: HashMap<PathBuf, Option<egui::TextureHandle>>,
}

/// A preset being dragged from the browser.
#[derive(Clone, Debug)]
pub struct PresetDrag(pub PathBuf);

/// The "Save selection as preset" dialog.
#[derive(Clone, Debug, Default)]
pub struct SavePresetDialog {
    /// Where the preset goes, relative to the graph's folder; empty: `presets/<name>.ron` there.
    pub file: String,
    /// The preset's name.
    pub name: String,
    /// What it makes.
    pub description: String,
    /// Comma-separated tags.
    pub tags: String,
    /// The parameters ticked for exposure, as `(node, parameter)`.
    pub ticked: BTreeSet<(String, String)>,
    /// Replace an existing file.
    pub overwrite: bool,
    /// Why the last save failed.
    pub error: Option<String>,
    focus: bool,
}

impl SavePresetDialog {
    /// The file the dialog saves to, for the graph folder `base`.
    pub fn target(&self, base: &Path) -> PathBuf {
        if !self.file.trim().is_empty() {
            // A relative file is taken from the graph's folder, like every path in the graph.
            return base.join(self.file.trim());
        }
        let slug: String = self
            .name
            .trim()
            .chars()
            .map(|c| if c.is_ascii_alphanumeric() { c.to_ascii_lowercase() } else { '-' })
            .collect::<String>()
            .split('-')
            .filter(|s| !s.is_empty())
            .collect::<Vec<_>>()
            .join("-");
        base.join("presets").join(format!("{}.ron", if slug.is_empty() { "preset" } else { &slug }))
    }
}

impl PresetBrowser {
    /// Reads the library afresh on the next frame and focuses the search field.
    pub(crate) fn reopen(&mut self) {
        self.presets = None;
        self.focus = true;
    }

    /// Shows the browser window over `editor`'s library; a preset clicked is inserted at the
    /// centre of `canvas`, one dragged onto it where it is dropped. `false` once the window is
    /// closed.
    pub(crate) fn window(&mut self, ctx: &egui::Context, editor: &mut Editor, canvas: &Canvas) -> bool {
        let presets = self.presets.get_or_insert_with(|| editor.browse_presets("", &[])).clone();
        let mut open = true;
        let mut insert = None;
        egui::Window::new("Presets")
            .open(&mut open)
            .default_pos(egui::pos2(40.0, 60.0))
            .default_width(380.0)
            .default_height(520.0)
            .show(ctx, |ui| {
                let r =
                    ui.add(egui::TextEdit::singleline(&mut self.query).hint_text("search presets").desired_width(f32::INFINITY));
                if self.focus {
                    r.request_focus();
                    self.focus = false;
                }
                let all_tags: BTreeSet<&String> = presets.iter().flat_map(|p| &p.meta.tags).collect();
                ui.horizontal_wrapped(|ui| {
                    for t in all_tags {
                        let on = self.tags.contains(t);
                        if ui.selectable_label(on, format!("#{t}")).clicked() {
                            if on {
                                self.tags.remove(t);
                            } else {
                                self.tags.insert(t.clone());
                            }
                        }
                    }
                });
                ui.separator();
                let tags: Vec<String> = self.tags.iter().cloned().collect();
                // Filtered from the library read when the browser opened (not re-read every frame).
                let shown = filter_presets(&presets, &self.query, &tags);
                if shown.is_empty() {
                    ui.weak("no preset matches");
                }
                egui::ScrollArea::vertical().auto_shrink([false, false]).show(ui, |ui| {
                    for p in &shown {
                        ui.horizontal(|ui| {
                            match thumb(&mut self.thumbs, ctx, p) {
                                Some(t) => ui.add(egui::Image::new((t.id(), THUMB))),
                                None => ui.add_sized(THUMB, egui::Label::new(RichText::new("no thumbnail").weak())),
                            };
                            ui.vertical(|ui| {
                                let r = ui
                                    .add(egui::Button::new(RichText::new(&p.name).strong()).sense(egui::Sense::click_and_drag()))
                                    .on_hover_text(format!(
                                        "{}\n{}\nclick: insert · drag onto the canvas",
                                        p.description,
                                        p.file.display()
                                    ));
                                if r.clicked() {
                                    insert = Some((p.file.clone(), None));
                                }
                                if r.drag_started() {
                                    egui::DragAndDrop::set_payload(ctx, PresetDrag(p.file.clone()));
                                }
                                ui.label(
                                    RichText::new(p.meta.tags.iter().map(|t| format!("#{t}")).collect::<Vec<_>>().join(" "))
                                        .weak(),
                                );
                            });
                        });
                    }
                });
            });
        if let Some(drag) = egui::DragAndDrop::payload::<PresetDrag>(ctx) {
            let name = drag.0.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
            let released = ctx.input(|i| i.pointer.any_released());
            let at = ctx.input(|i| i.pointer.latest_pos());
            if let Some(p) = at {
                egui::Area::new(egui::Id::new("preset-drag"))
                    .order(egui::Order::Tooltip)
                    .fixed_pos(p + egui::vec2(14.0, 14.0))
                    .interactable(false)
                    .show(ctx, |ui| egui::Frame::popup(ui.style()).show(ui, |ui| ui.label(format!("preset {name}"))));
            }
            let over_window = ctx.layer_id_at(at.unwrap_or_default()).is_some_and(|l| l.order != egui::Order::Background);
            if released {
                egui::DragAndDrop::clear_payload(ctx);
                if let Some(at) = at.filter(|p| canvas.rect_contains(*p) && !over_window) {
                    insert = Some((drag.0.clone(), Some(at)));
                }
            }
        }
        if let Some((file, at)) = insert {
            let pos = at.map_or_else(|| canvas.view_center(), |p| canvas.to_graph(p));
            match editor.add_preset(&file, (pos.x, pos.y)) {
                Ok(id) => editor.select(&id),
                Err(e) => editor.set_status(e, true),
            }
        }
        open
    }
}

impl SavePresetDialog {
    /// A dialog for a new preset, its name field focused.
    pub(crate) fn focused() -> Self {
        SavePresetDialog { focus: true, ..SavePresetDialog::default() }
    }

    /// Shows the dialog for the nodes selected in `editor` and saves the preset when asked (the
    /// open `browser`, if any, then reads the library afresh). `false` once the dialog is closed
    /// or the preset saved.
    pub(crate) fn window(&mut self, ctx: &egui::Context, editor: &mut Editor, browser: Option<&mut PresetBrowser>) -> bool {
        let mut open = true;
        let mut save = false;
        let base = editor.base_dir();
        let selection = editor.selection().to_vec();
        egui::Window::new("Save selection as preset").open(&mut open).collapsible(false).default_width(460.0).show(ctx, |ui| {
            egui::Grid::new("save-preset").num_columns(2).show(ui, |ui| {
                ui.label("Name");
                let r = ui.add(egui::TextEdit::singleline(&mut self.name).hint_text("my torch").desired_width(300.0));
                if self.focus {
                    r.request_focus();
                    self.focus = false;
                }
                ui.end_row();
                ui.label("Description");
                ui.add(egui::TextEdit::singleline(&mut self.description).desired_width(300.0));
                ui.end_row();
                ui.label("Tags");
                ui.add(egui::TextEdit::singleline(&mut self.tags).hint_text("fire, torch").desired_width(300.0));
                ui.end_row();
                ui.label("File");
                let default = self.target(&base).display().to_string();
                ui.add(egui::TextEdit::singleline(&mut self.file).hint_text(default).desired_width(300.0));
                ui.end_row();
            });
            ui.separator();
            ui.label("Parameters to expose:");
            egui::ScrollArea::vertical().max_height(260.0).show(ui, |ui| {
                for id in &selection {
                    let Some(desc) = editor.desc(id).cloned() else { continue };
                    let params: Vec<_> =
                        desc.inputs.iter().filter(|p| p.ty.is_parameter() && editor.incoming(id, &p.name).is_none()).collect();
                    if params.is_empty() {
                        continue;
                    }
                    ui.label(RichText::new(id).strong());
                    ui.indent(("params", id), |ui| {
                        for p in params {
                            let key = (id.clone(), p.name.clone());
                            let mut on = self.ticked.contains(&key);
                            if ui.checkbox(&mut on, format!("{id}.{}", p.name)).on_hover_text(&p.doc).changed() {
                                if on {
                                    self.ticked.insert(key);
                                } else {
                                    self.ticked.remove(&key);
                                }
                            }
                        }
                    });
                }
            });
            ui.separator();
            ui.checkbox(&mut self.overwrite, "Overwrite an existing file");
            if let Some(e) = &self.error {
                ui.colored_label(Color32::from_rgb(255, 120, 120), e);
            }
            save = ui.button("Save preset").clicked();
        });
        // The selection may change while the dialog is open: ticks of nodes no longer selected
        // have no checkbox left to untick, so they go.
        self.ticked.retain(|(node, _)| selection.contains(node));
        if save {
            let spec = SelectionPreset {
                name: self.name.clone(),
                description: self.description.clone(),
                tags: self.tags.split(',').map(|t| t.trim().to_lowercase()).filter(|t| !t.is_empty()).collect(),
                params: self.ticked.iter().cloned().collect(),
                overwrite: self.overwrite,
            };
            match editor.save_selection_as_preset(&self.target(&base), &spec) {
                Ok(_) => {
                    if let Some(b) = browser {
                        b.presets = None;
                    }
                    return false;
                }
                Err(e) => self.error = Some(e),
            }
        }
        open
    }
}

/// The thumbnail texture of `p`, loaded once (none when it has no readable thumbnail).
fn thumb<'a>(
    cache: &'a mut HashMap<PathBuf, Option<egui::TextureHandle>>,
    ctx: &egui::Context,
    p: &Preset,
) -> Option<&'a egui::TextureHandle> {
    let file = pyrograph_frontend::preset_cook::thumbnail_path(&p.file, p.meta.thumbnail.as_deref());
    cache
        .entry(file.clone())
        .or_insert_with(|| {
            let img = pyrograph_frontend::imaging::io::load_image(&file).ok()?;
            let rgba = pyrograph_frontend::imaging::convert::to_rgba8(&img);
            let size = [rgba.width() as usize, rgba.height() as usize];
            let ci = egui::ColorImage::from_rgba_unmultiplied(size, rgba.as_raw());
            Some(ctx.load_texture(file.display().to_string(), ci, egui::TextureOptions::LINEAR))
        })
        .as_ref()
}
