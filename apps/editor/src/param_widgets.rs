//! Parameter widgets: one per port type, honouring the port's range and options.

use eframe::egui;
use pyrograph_frontend::core::{ParamValue, PortDesc, PortType};

fn number(pv: &ParamValue) -> Option<f64> {
    match pv {
        ParamValue::Int(v) => Some(*v as f64),
        ParamValue::Float(v) => Some(*v),
        _ => None,
    }
}

fn numbers(pv: &ParamValue) -> Option<Vec<f64>> {
    match pv {
        ParamValue::List(items) => items.iter().map(number).collect(),
        _ => None,
    }
}

/// A colour from its file form: `(r, g, b)`, `(r, g, b, a)` or `"#rrggbb"`.
pub fn as_color(pv: &ParamValue) -> Option<[f32; 4]> {
    match pv {
        ParamValue::String(s) => pyrograph_frontend::core::graph::parse_hex_color(s),
        _ => match numbers(pv)?.as_slice() {
            [r, g, b] => Some([*r as f32, *g as f32, *b as f32, 1.0]),
            [r, g, b, a] => Some([*r as f32, *g as f32, *b as f32, *a as f32]),
            _ => None,
        },
    }
}

/// A drag speed suited to a range.
fn speed(range: Option<(f64, f64)>, v: f64) -> f64 {
    match range {
        Some((lo, hi)) if (hi - lo).is_finite() && hi - lo <= 1e4 => ((hi - lo) / 300.0).max(1e-4),
        _ => (v.abs() / 100.0).max(0.01),
    }
}

/// Whether a range is small enough for a slider.
fn slider_range(range: Option<(f64, f64)>) -> Option<(f64, f64)> {
    range.filter(|(lo, hi)| lo.is_finite() && hi.is_finite() && hi - lo <= 1000.0 && hi > lo)
}

/// Shows the widget for `port` with the current `value`; returns the new value when the user
/// changed it. Values of the wrong kind (from a hand-edited file) get a raw text field.
pub fn param_widget(ui: &mut egui::Ui, id: egui::Id, port: &PortDesc, value: &ParamValue) -> Option<ParamValue> {
    match &port.ty {
        PortType::Float => {
            let mut v = number(value)?;
            let changed = match slider_range(port.range) {
                Some((lo, hi)) => ui.add(egui::Slider::new(&mut v, lo..=hi).clamping(egui::SliderClamping::Always)).changed(),
                None => {
                    let (lo, hi) = port.range.unwrap_or((f64::NEG_INFINITY, f64::INFINITY));
                    let sp = speed(port.range, v);
                    ui.add(egui::DragValue::new(&mut v).range(lo..=hi).speed(sp)).changed()
                }
            };
            changed.then_some(ParamValue::Float(v))
        }
        PortType::Int => {
            let ParamValue::Int(mut v) = *value else { return None };
            let changed = match slider_range(port.range) {
                Some((lo, hi)) => {
                    ui.add(egui::Slider::new(&mut v, lo as i64..=hi as i64).clamping(egui::SliderClamping::Always)).changed()
                }
                None => {
                    let (lo, hi) = port.range.unwrap_or((i64::MIN as f64, i64::MAX as f64));
                    let sp = speed(port.range, v as f64).max(0.2);
                    ui.add(egui::DragValue::new(&mut v).range(lo as i64..=hi as i64).speed(sp)).changed()
                }
            };
            changed.then_some(ParamValue::Int(v))
        }
        PortType::Bool => {
            let ParamValue::Bool(mut b) = *value else { return None };
            ui.checkbox(&mut b, "").changed().then_some(ParamValue::Bool(b))
        }
        PortType::Color => {
            let mut c = as_color(value)?;
            let changed = ui.color_edit_button_rgba_unmultiplied(&mut c).changed();
            changed.then(|| ParamValue::List(c.iter().map(|v| ParamValue::Float((*v as f64 * 1e4).round() / 1e4)).collect()))
        }
        PortType::Vec2 | PortType::Vec3 => {
            let mut v = numbers(value)?;
            let want = if port.ty == PortType::Vec2 { 2 } else { 3 };
            if v.len() != want {
                return None;
            }
            let mut changed = false;
            ui.horizontal(|ui| {
                for c in v.iter_mut() {
                    changed |= ui.add(egui::DragValue::new(c).speed(0.01).max_decimals(4)).changed();
                }
            });
            changed.then(|| ParamValue::List(v.into_iter().map(ParamValue::Float).collect()))
        }
        PortType::Enum => {
            let ParamValue::String(cur) = value else { return None };
            let mut sel = cur.clone();
            egui::ComboBox::from_id_salt(id).selected_text(sel.clone()).show_ui(ui, |ui| {
                for o in &port.options {
                    ui.selectable_value(&mut sel, o.clone(), o);
                }
            });
            (sel != *cur).then_some(ParamValue::String(sel))
        }
        PortType::String | PortType::Path => {
            let ParamValue::String(cur) = value else { return None };
            buffered_text(ui, id, cur, false).map(ParamValue::String)
        }
        _ => None,
    }
}

/// The fallback for values of the wrong kind: RON text, parsed when edited.
pub fn raw_widget(ui: &mut egui::Ui, value: &ParamValue) -> Option<ParamValue> {
    let cur = value.to_string();
    let mut s = cur.clone();
    let r = ui.add(egui::TextEdit::singleline(&mut s).text_color(egui::Color32::LIGHT_RED));
    (r.changed() && s != cur).then(|| ParamValue::parse_cli(&s))
}

/// A text field that edits a copy: Enter (or Tab, or clicking elsewhere) commits it, Escape
/// reverts it, so typing a path does not re-cook on every key. `multiline` fields take Enter
/// as a new line and commit when they lose focus. Returns the committed text when it differs.
pub fn buffered_text(ui: &mut egui::Ui, id: egui::Id, current: &str, multiline: bool) -> Option<String> {
    let buf_id = id.with("edit-buffer");
    let mut buf = ui.data(|d| d.get_temp::<String>(buf_id)).unwrap_or_else(|| current.to_string());
    let edit = if multiline { egui::TextEdit::multiline(&mut buf).desired_rows(4) } else { egui::TextEdit::singleline(&mut buf) };
    // Escape takes the focus away before the frame is drawn; drop the copy then, so the frame
    // that sees the focus lost finds nothing to commit.
    let escaped = ui.input(|i| i.key_pressed(egui::Key::Escape));
    let r = ui.add(edit.id(id).desired_width(f32::INFINITY));
    if r.has_focus() && !escaped {
        ui.data_mut(|d| d.insert_temp(buf_id, buf));
        return None;
    }
    let edited = ui.data_mut(|d| d.remove_temp::<String>(buf_id));
    if escaped || !r.lost_focus() {
        return None;
    }
    edited.filter(|b| b != current)
}
