//! The node palette: node types and presets matching a search, for the Tab menu and the Add menu.

use std::collections::HashSet;
use std::path::PathBuf;

use pyrograph_frontend::core::GraphDoc;
use pyrograph_frontend::core::builtin::INCLUDE_TYPE;

use eframe::egui::{self, Color32, Ui};

use crate::state::{Editor, PaletteItem};

impl Editor {
    /// Node types and presets matching `query` (every word must appear in the type name,
    /// category or doc), best matches first.
    pub fn palette(&self, query: &str) -> Vec<PaletteItem> {
        let words: Vec<String> = query.split_whitespace().map(str::to_lowercase).collect();
        let mut items: Vec<(u32, PaletteItem)> = Vec::new();
        let score = |name: &str, category: &str, doc: &str| -> Option<u32> {
            let (name, category, doc) = (name.to_lowercase(), category.to_lowercase(), doc.to_lowercase());
            let mut s = 0;
            for w in &words {
                if name.contains(w.as_str()) {
                    s += if name.rsplit('.').next().is_some_and(|n| n.starts_with(w.as_str())) { 0 } else { 1 };
                } else if category.contains(w.as_str()) {
                    s += 2;
                } else if doc.contains(w.as_str()) {
                    s += 4;
                } else {
                    return None;
                }
            }
            Some(s)
        };
        for desc in self.registry().descs() {
            if desc.type_name == INCLUDE_TYPE {
                continue;
            }
            if let Some(s) = score(&desc.type_name, &desc.category, &desc.doc) {
                items.push((
                    s,
                    PaletteItem {
                        type_name: desc.type_name.clone(),
                        category: desc.category.clone(),
                        summary: desc.summary().to_string(),
                        preset: None,
                    },
                ));
            }
        }
        for file in self.presets() {
            let name = file.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
            let summary = GraphDoc::load(&file).ok().and_then(|d| d.description).unwrap_or_default();
            if let Some(s) = score(&name, "Preset", &summary) {
                items.push((
                    s,
                    PaletteItem {
                        type_name: INCLUDE_TYPE.into(),
                        category: "Preset".into(),
                        summary: format!("{name}: {summary}"),
                        preset: Some(file),
                    },
                ));
            }
        }
        items.sort_by(|a, b| a.0.cmp(&b.0).then(a.1.category.cmp(&b.1.category)).then(a.1.type_name.cmp(&b.1.type_name)));
        items.into_iter().map(|(_, i)| i).collect()
    }

    /// Preset files (`*.ron` with an interface) in the preset folders.
    pub fn presets(&self) -> Vec<PathBuf> {
        let mut seen = HashSet::new();
        let mut out = Vec::new();
        for dir in self.preset_dirs() {
            let Ok(entries) = std::fs::read_dir(dir) else { continue };
            let mut files: Vec<PathBuf> =
                entries.filter_map(|e| e.ok()).map(|e| e.path()).filter(|p| p.extension().is_some_and(|e| e == "ron")).collect();
            files.sort();
            for f in files {
                let key = std::fs::canonicalize(&f).unwrap_or_else(|_| f.clone());
                let name = f.file_name().map(|n| n.to_os_string());
                if seen.insert(key) && seen.insert(PathBuf::from(name.unwrap_or_default())) {
                    out.push(f);
                }
            }
        }
        out
    }
}

/// The node palette: a search field and the matching node types and presets. Returns the item
/// the user picked (click, or Enter for the first match).
pub fn palette_ui(ui: &mut Ui, editor: &Editor, query: &mut String, focus: bool) -> Option<PaletteItem> {
    search_list_ui(ui, query, focus, |q| editor.palette(q))
}

/// A search field over the list `items(query)` returns; the item picked (click, or Enter for
/// the first).
pub fn search_list_ui(
    ui: &mut Ui,
    query: &mut String,
    focus: bool,
    items: impl FnOnce(&str) -> Vec<PaletteItem>,
) -> Option<PaletteItem> {
    let resp =
        ui.add(egui::TextEdit::singleline(query).hint_text("search nodes (name, category, doc)…").id_salt("palette-search"));
    if focus {
        resp.request_focus();
    }
    let items = items(query);
    let enter = resp.lost_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter));
    let mut picked = None;
    if enter {
        picked = items.first().cloned();
    }
    egui::ScrollArea::vertical().max_height(320.0).show(ui, |ui| {
        let mut last_cat = String::new();
        for item in items.iter().take(60) {
            if item.category != last_cat {
                last_cat = item.category.clone();
                ui.label(egui::RichText::new(&item.category).small().color(category_color(&item.category).gamma_multiply(2.0)));
            }
            let label = match &item.preset {
                Some(p) => format!("preset {}", p.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default()),
                None => item.type_name.clone(),
            };
            if ui.selectable_label(false, label).on_hover_text(&item.summary).clicked() {
                picked = Some(item.clone());
            }
        }
        if items.is_empty() {
            ui.weak("no match");
        }
    });
    picked
}

/// A header colour per palette category.
pub fn category_color(category: &str) -> Color32 {
    let h = category.bytes().fold(2166136261u32, |h, b| (h ^ b as u32).wrapping_mul(16777619));
    let hue = (h % 360) as f32 / 360.0;
    let c = egui::ecolor::Hsva::new(hue, 0.55, 0.38, 1.0);
    Color32::from(c)
}
