//! The ramp editor, as Houdini's ramp parameter and Nuke's colour-curve knobs work: a gradient
//! bar (colour ramps) or a curve plot (scalar curves) with a handle per key. Drag a handle along
//! the bar (and, on a curve, up and down) to move the key; click the bar to add a key (Houdini's ramp does the same) with
//! the colour or value the ramp has there; the selected key's colour, value and position are
//! edited below, and "−" removes it. The keys are also shown as the text a graph file holds, for
//! exact edits. Point lists get that text field alone.

use eframe::egui::{self, Color32, Pos2, Rect, Sense, Stroke, Vec2, WidgetInfo, WidgetType};
use pyrograph_frontend::core::ParamValue;
use pyrograph_frontend::core::value::{Points, RampKeys};

use crate::param_widgets::buffered_text;

/// The fill of a curve's key handles (the key colour of the curve editor).
const HANDLE: Color32 = Color32::from_rgb(240, 190, 60);
/// Samples the bar and the curve plot draw.
const STEPS: usize = 64;

/// A ramp's keys, `(position, components)`, as the editor changes them.
pub type Keys = Vec<(f64, [f64; 4])>;

/// The keys a parameter holds (the typed form, or the text form older files hold).
pub fn read_keys(value: &ParamValue, width: usize) -> Option<Keys> {
    let keys = match value {
        ParamValue::String(text) => RampKeys::parse_legacy(text, width),
        other => RampKeys::from_param(other, width),
    };
    keys.ok().map(|k| k.keys().to_vec())
}

/// The file form of `keys` (positions and values rounded to 1e-4, as the sliders show them).
pub fn write_keys(keys: &[(f64, [f64; 4])], width: usize) -> Option<ParamValue> {
    let round = |x: f64| (x * 1e4).round() / 1e4;
    let keys = keys.iter().map(|(p, v)| (round(*p), v.map(round))).collect();
    RampKeys::new(width, keys).ok().map(|k| k.to_param())
}

/// The ramp's value at `pos`: linear between keys, held past the ends (as the nodes read it).
pub fn eval(keys: &[(f64, [f64; 4])], pos: f64) -> [f64; 4] {
    let i = keys.partition_point(|(p, _)| *p <= pos);
    match (i, keys.len()) {
        (_, 0) => [0.0; 4],
        (0, _) => keys[0].1,
        (i, n) if i == n => keys[n - 1].1,
        (i, _) => {
            let ((p0, a), (p1, b)) = (keys[i - 1], keys[i]);
            let f = if p1 > p0 { (pos - p0) / (p1 - p0) } else { 0.0 };
            std::array::from_fn(|c| a[c] + (b[c] - a[c]) * f)
        }
    }
}

/// Adds a key at `pos` with the ramp's value there; returns its index.
pub fn insert_key(keys: &mut Keys, pos: f64) -> usize {
    let pos = pos.clamp(0.0, 1.0);
    let value = eval(keys, pos);
    let i = keys.partition_point(|(p, _)| *p <= pos);
    keys.insert(i, (pos, value));
    i
}

/// Moves key `index` to `pos` (kept in 0..1), keeping the keys in order; returns its new index.
pub fn move_key(keys: &mut Keys, index: usize, pos: f64) -> usize {
    let (_, value) = keys.remove(index);
    let pos = pos.clamp(0.0, 1.0);
    let i = keys.partition_point(|(p, _)| *p <= pos);
    keys.insert(i, (pos, value));
    i
}

fn to_color32(v: &[f64; 4], width: usize) -> Color32 {
    let c = |x: f64| (x.clamp(0.0, 1.0) * 255.0).round() as u8;
    let a = if width == 4 { v[3] } else { 1.0 };
    Color32::from_rgba_unmultiplied(c(v[0]), c(v[1]), c(v[2]), c(a.max(0.15)))
}

/// The ramp editor for a `width`-component ramp parameter named `name`; the new value when the
/// user changed it.
pub fn ramp_widget(ui: &mut egui::Ui, id: egui::Id, name: &str, width: usize, value: &ParamValue) -> Option<ParamValue> {
    let keys = read_keys(value, width)?;
    // A grid cell lays widgets out in a row: the bar, the key row and the text go in a column.
    ui.vertical(|ui| ramp_column(ui, id, name, width, value, keys)).inner
}

fn ramp_column(
    ui: &mut egui::Ui,
    id: egui::Id,
    name: &str,
    width: usize,
    value: &ParamValue,
    mut keys: Keys,
) -> Option<ParamValue> {
    let sel_id = id.with("selected");
    let mut selected = ui.data(|d| d.get_temp::<usize>(sel_id)).unwrap_or(0).min(keys.len() - 1);
    let mut changed = false;
    let curve = width == 1;
    // As wide as the visible part of the inspector (a grid cell reports more than is shown).
    let w = (ui.clip_rect().right() - ui.cursor().left() - 12.0).clamp(100.0, 320.0);
    let (rect, bar) = ui.allocate_exact_size(Vec2::new(w, if curve { 64.0 } else { 22.0 }), Sense::click());
    bar.widget_info(|| WidgetInfo::labeled(WidgetType::Other, true, format!("ramp {name}")));
    let (lo, hi) = value_span(&keys, curve);
    let to_x = |p: f64| rect.left() + (p as f32) * rect.width();
    let to_y = |v: f64| rect.bottom() - ((v - lo) / (hi - lo)) as f32 * rect.height();
    draw_ramp(ui.painter(), rect, &keys, width, (lo, hi));
    if bar.clicked()
        && let Some(p) = bar.interact_pointer_pos()
    {
        selected = insert_key(&mut keys, f64::from((p.x - rect.left()) / rect.width()));
        changed = true;
    }
    for i in 0..keys.len() {
        let (pos, v) = keys[i];
        let centre = if curve { Pos2::new(to_x(pos), to_y(v[0])) } else { Pos2::new(to_x(pos), rect.bottom() + 5.0) };
        let handle = ui.interact(Rect::from_center_size(centre, Vec2::splat(12.0)), id.with(("key", i)), Sense::click_and_drag());
        handle.widget_info(|| WidgetInfo::labeled(WidgetType::Button, true, format!("key {} of {name}", i + 1)));
        if handle.clicked() || handle.drag_started() {
            selected = i;
        }
        if handle.dragged()
            && let Some(p) = handle.interact_pointer_pos()
        {
            let new_pos = f64::from((p.x - rect.left()) / rect.width().max(1.0));
            if curve {
                keys[i].1[0] = lo + f64::from((rect.bottom() - p.y) / rect.height().max(1.0)) * (hi - lo);
            }
            selected = move_key(&mut keys, i, new_pos);
            changed = true;
            break;
        }
        let stroke =
            Stroke::new(if i == selected { 2.0 } else { 1.0 }, if i == selected { Color32::WHITE } else { Color32::GRAY });
        if curve {
            ui.painter().circle(centre, 4.0, HANDLE, stroke);
        } else {
            let tri = vec![centre + Vec2::new(0.0, -5.0), centre + Vec2::new(5.0, 4.0), centre + Vec2::new(-5.0, 4.0)];
            ui.painter().add(egui::Shape::convex_polygon(tri, to_color32(&v, width), stroke));
        }
    }
    if !curve {
        ui.add_space(10.0);
    }
    changed |= selected_key_row(ui, &mut keys, &mut selected, width);
    ui.data_mut(|d| d.insert_temp(sel_id, selected));
    let text = buffered_text(ui, id.with("text"), &written(value, width), false);
    if let Some(text) = text {
        return Some(ParamValue::parse_cli(&text));
    }
    if changed { write_keys(&keys, width) } else { None }
}

/// The selected key's row: its position, its colour or value, and "−" to remove it.
fn selected_key_row(ui: &mut egui::Ui, keys: &mut Keys, selected: &mut usize, width: usize) -> bool {
    let mut changed = false;
    ui.horizontal(|ui| {
        let i = *selected;
        ui.label(format!("key {}", i + 1));
        let mut pos = keys[i].0;
        if ui.add(egui::DragValue::new(&mut pos).range(0.0..=1.0).speed(0.005).max_decimals(4)).changed() {
            *selected = move_key(keys, i, pos);
            changed = true;
        }
        let i = *selected;
        let v = &mut keys[i].1;
        changed |= match width {
            1 => ui.add(egui::DragValue::new(&mut v[0]).speed(0.01).max_decimals(4)).changed(),
            3 => {
                let mut c = [v[0] as f32, v[1] as f32, v[2] as f32];
                let r = ui.color_edit_button_rgb(&mut c).changed();
                v[..3].iter_mut().zip(c).for_each(|(o, x)| *o = f64::from(x));
                r
            }
            _ => {
                let mut c = [v[0] as f32, v[1] as f32, v[2] as f32, v[3] as f32];
                let r = ui.color_edit_button_rgba_unmultiplied(&mut c).changed();
                v.iter_mut().zip(c).for_each(|(o, x)| *o = f64::from(x));
                r
            }
        };
        let remove = ui.add_enabled(keys.len() > 1, egui::Button::new("−").small()).on_hover_text("remove this key");
        if remove.clicked() {
            keys.remove(i);
            *selected = i.min(keys.len() - 1);
            changed = true;
        }
    });
    changed
}

/// The span of values a curve plot shows: the keys' values with a margin, at least 0..1.
fn value_span(keys: &[(f64, [f64; 4])], curve: bool) -> (f64, f64) {
    if !curve {
        return (0.0, 1.0);
    }
    let (lo, hi) = keys.iter().fold((0.0f64, 1.0f64), |(lo, hi), (_, v)| (lo.min(v[0]), hi.max(v[0])));
    let pad = (hi - lo) * 0.1;
    (lo - pad, hi + pad)
}

fn draw_ramp(painter: &egui::Painter, rect: Rect, keys: &[(f64, [f64; 4])], width: usize, (lo, hi): (f64, f64)) {
    painter.rect_filled(rect, 2.0, Color32::from_gray(30));
    let at = |k: usize| k as f64 / STEPS as f64;
    if width == 1 {
        let y = |v: f64| rect.bottom() - ((v - lo) / (hi - lo)) as f32 * rect.height();
        let points: Vec<Pos2> =
            (0..=STEPS).map(|k| Pos2::new(rect.left() + at(k) as f32 * rect.width(), y(eval(keys, at(k))[0]))).collect();
        painter.add(egui::Shape::line(points, Stroke::new(1.5, Color32::from_rgb(120, 200, 120))));
        return;
    }
    let mut mesh = egui::Mesh::default();
    for k in 0..=STEPS {
        let x = rect.left() + at(k) as f32 * rect.width();
        let c = to_color32(&eval(keys, at(k)), width);
        mesh.colored_vertex(Pos2::new(x, rect.top()), c);
        mesh.colored_vertex(Pos2::new(x, rect.bottom()), c);
        if k > 0 {
            let b = (2 * k) as u32;
            mesh.add_triangle(b - 2, b - 1, b);
            mesh.add_triangle(b - 1, b + 1, b);
        }
    }
    painter.add(egui::Shape::mesh(mesh));
}

/// The typed text of a ramp or point list, as a graph file holds it (older text forms shown
/// typed too).
fn written(value: &ParamValue, width: usize) -> String {
    let typed = read_keys(value, width).and_then(|k| RampKeys::new(width, k).ok());
    typed.map_or_else(|| value.to_string(), |k| k.summary())
}

/// A point list's field: the typed list as text; the text form older files hold is accepted and
/// written back typed.
pub fn points_widget(ui: &mut egui::Ui, id: egui::Id, value: &ParamValue) -> Option<ParamValue> {
    let points = match value {
        ParamValue::String(text) => Points::parse_legacy(text),
        other => Points::from_param(other),
    };
    let shown = points.as_ref().map_or_else(|_| value.to_string(), Points::summary);
    let text = buffered_text(ui, id, &shown, false)?;
    Some(match ParamValue::parse_cli(&text) {
        ParamValue::String(s) => Points::parse_legacy(&s).map_or(ParamValue::String(s), |p| p.to_param()),
        typed => typed,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn keys(text: &str, width: usize) -> Keys {
        read_keys(&ParamValue::parse_cli(text), width).unwrap()
    }

    #[test]
    fn a_key_added_takes_the_ramps_value_and_a_moved_key_keeps_the_order() {
        let mut k = keys("[(0, (0, 0, 0)), (1, (1, 0.5, 0))]", 3);
        assert_eq!(insert_key(&mut k, 0.25), 1);
        assert_eq!(k[1], (0.25, [0.25, 0.125, 0.0, 0.0]), "the colour the ramp had there");
        // Dragged past the last key, it becomes the last; past the end, it stops at 1.
        assert_eq!(move_key(&mut k, 1, 1.7), 2);
        assert_eq!(k.iter().map(|(p, _)| *p).collect::<Vec<_>>(), [0.0, 1.0, 1.0]);
        assert_eq!(k[2].1, [0.25, 0.125, 0.0, 0.0]);
        assert_eq!(read_keys(&write_keys(&k, 3).unwrap(), 3).unwrap(), k, "written as typed keys");
    }

    #[test]
    fn the_old_text_form_reads_and_writes_back_typed() {
        let old = ParamValue::String("0: 0.67; 0.5: 1.07; 1: 0.67".into());
        let text = written(&old, 1);
        assert_eq!(text, "[(0.0, 0.67), (0.5, 1.07), (1.0, 0.67)]");
        assert_eq!(read_keys(&ParamValue::parse_cli(&text), 1), read_keys(&old, 1), "the text reads back as the keys");
        assert!((eval(&read_keys(&old, 1).unwrap(), 0.75)[0] - 0.87).abs() < 1e-12);
        assert!(read_keys(&ParamValue::parse_cli("[(0.5, 1), (0.2, 0)]"), 1).is_none(), "keys out of order are not a ramp");
    }
}
