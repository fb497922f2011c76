//! Tangent handles in the curve editor: when one key is selected, two handles on a line through it
//! show the curve's slope arriving and leaving (accessible as "tangent in of key 2 of strength"
//! and "tangent out of …"). Dragging either sets the key's slope to the line from the key to the
//! pointer, written `tangent(slope)` (value per frame, both sides tied, as Houdini ties a key's
//! slopes until they are broken); one undo step per drag. A slope that would carry the curve
//! outside the port's range between keys is refused with the reason in the status line.

use eframe::egui::{self, Color32, Pos2, Rect, Sense, Stroke, Vec2, WidgetInfo, WidgetType};
use pyrograph_frontend::core::ParamValue;
use pyrograph_frontend::core::anim::Track;

use crate::app::EditorApp;
use crate::key_ui::CurveView;
use crate::keys::KeyList;
use crate::state::{AnimParam, value_text};

/// Screen distance from a key to its tangent handles.
const REACH: f32 = 38.0;
/// Frames over which an automatic slope is measured on each side of a key.
const STEP: f64 = 1e-3;

/// The slopes (value per frame) arriving at and leaving key `index` of `p`: the written ones of a
/// `tangent(…)` key, else the curve's own, measured on each side.
fn slopes(p: &AnimParam, list: &KeyList, index: usize) -> Option<(f64, f64)> {
    let key = list.keys.get(index)?;
    if let Some(ParamValue::Call(name, arg)) = &key.interp
        && name == "tangent"
    {
        let number = |v: &ParamValue| match v {
            ParamValue::Float(x) => Some(*x),
            ParamValue::Int(i) => Some(*i as f64),
            _ => None,
        };
        return match arg.as_ref() {
            ParamValue::List(two) if two.len() == 2 => Some((number(&two[0])?, number(&two[1])?)),
            one => number(one).map(|s| (s, s)),
        };
    }
    let Some(Track::Keys(c)) = p.animated.tracks().first() else { return None };
    let f = key.frame;
    Some(((c.sample(f) - c.sample(f - STEP)) / STEP, (c.sample(f + STEP) - c.sample(f)) / STEP))
}

/// The screen offset from a key to the handle of a slope, `REACH` pixels along it (forward in time).
fn handle_offset(view: &CurveView, slope: f64) -> Vec2 {
    let px_frame = view.rect.width() as f64 / (view.frames.1 - view.frames.0);
    let px_value = view.rect.height() as f64 / (view.values.1 - view.values.0);
    let d = Vec2::new(px_frame as f32, (-slope * px_value) as f32);
    if d.length() > 0.0 && d.is_finite() { d.normalized() * REACH } else { Vec2::new(REACH, 0.0) }
}

/// The slope of the line from (`frame`, `value`) to the pointer at `p`, rounded to four
/// significant digits (`None` where the pointer is on the key's frame).
pub fn slope_to(view: &CurveView, frame: f64, value: f64, p: Pos2) -> Option<f64> {
    let (f, v) = view.from_screen(p);
    let df = f - frame;
    if df.abs() < 1e-3 * (view.frames.1 - view.frames.0) {
        return None;
    }
    let s = (v - value) / df;
    format!("{s:.3e}").parse().ok()
}

impl EditorApp {
    /// The tangent handles of the one selected key, if it is on a shown keyed curve.
    pub(crate) fn tangent_handles(&mut self, ui: &mut egui::Ui, node: &str, shown: &[(usize, AnimParam)], view: &CurveView) {
        let dragging = self.key_ui.tangent_drag.clone();
        if dragging.is_some() && !ui.input(|i| i.pointer.primary_down()) {
            self.key_ui.tangent_drag = None;
            self.editor.seal();
        }
        let [(param, frame)] = self.key_ui.selected() else { return };
        let (param, frame) = (param.clone(), *frame);
        let Some((_, p)) = shown.iter().find(|(_, p)| p.port.name == param) else { return };
        let Some(list) = p.keys() else { return };
        let Some(index) = list.find(frame) else { return };
        let Some((s_in, s_out)) = slopes(p, &list, index) else { return };
        let key = &list.keys[index];
        let at = view.to_screen(key.frame, key.value);
        let painter = ui.painter_at(view.rect.expand(REACH));
        for (side, end) in [("in", at - handle_offset(view, s_in)), ("out", at + handle_offset(view, s_out))] {
            let id = egui::Id::new(("tangent", node, &param, side));
            let resp = ui.interact(Rect::from_center_size(end, Vec2::splat(11.0)), id, Sense::drag());
            let label = format!("tangent {side} of key {} of {param}", index + 1);
            resp.widget_info(|| WidgetInfo::labeled(WidgetType::Button, true, label.clone()));
            let color = if resp.hovered() || resp.dragged() { Color32::WHITE } else { Color32::from_gray(190) };
            painter.line_segment([at, end], Stroke::new(1.0, color));
            painter.circle(end, 4.0, Color32::from_gray(30), Stroke::new(1.5, color));
            if resp.drag_started() {
                self.key_ui.tangent_drag = Some((param.clone(), index));
            }
            if resp.dragged()
                && let Some(pointer) = ui.input(|i| i.pointer.latest_pos())
                && let Some(slope) = slope_to(view, key.frame, key.value, pointer)
            {
                // Errors (a slope leaving the port's range) go to the status line.
                let _ = self.editor.set_key_tangent(node, &param, index, slope);
            }
            resp.on_hover_text(format!("{param}: drag to set the slope at this key (tangent({}))", value_text(s_out)));
        }
    }
}
