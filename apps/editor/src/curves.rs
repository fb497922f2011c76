//! The curve editor: a panel under the canvas plotting the current node's animated Float and
//! Int parameters over frames, painted with egui's painter. Keys are handles (accessible as
//! "key 2 of strength"): dragging one moves it in frame (snapped to whole frames) and value, one
//! undo step per drag; a click selects it (Shift adds) and Delete deletes the selection. The
//! playhead is a vertical line; a click or drag on the background scrubs it. "Frame" (or F with
//! the pointer over the panel) fits the view to the keys; the wheel zooms frames, Ctrl+wheel
//! values, a right or middle drag pans. Expressions are drawn dashed, without handles. A single
//! selected key shows its tangent handles (`tangents`).

use std::collections::BTreeSet;

use eframe::egui::{self, Color32, PointerButton, Pos2, Rect, Response, RichText, Sense, Stroke, Vec2, WidgetInfo, WidgetType};
use pyrograph_frontend::core::anim::Track;
use pyrograph_frontend::core::{ParamValue, PortType, Value};

use crate::app::EditorApp;
use crate::key_ui::{CurveView, KeyDrag};
use crate::keying::diamond;
use crate::keys::{KeyList, SAME_FRAME, frame_text};
use crate::state::{AnimParam, value_text};

/// Colour of the `i`-th curve.
pub fn channel_color(i: usize) -> Color32 {
    const C: [Color32; 6] = [
        Color32::from_rgb(255, 140, 70),
        Color32::from_rgb(110, 190, 255),
        Color32::from_rgb(140, 220, 120),
        Color32::from_rgb(230, 120, 220),
        Color32::from_rgb(240, 220, 90),
        Color32::from_rgb(120, 220, 210),
    ];
    C[i % C.len()]
}

/// A round step near `raw`: 1, 2 or 5 times a power of ten.
fn nice_step(raw: f64) -> f64 {
    if !(raw.is_finite() && raw > 0.0) {
        return 1.0;
    }
    let e = 10f64.powf(raw.log10().floor());
    [1.0, 2.0, 5.0, 10.0].into_iter().map(|m| m * e).find(|s| *s >= raw).unwrap_or(10.0 * e)
}

/// A sample as a number.
fn number(v: &Value) -> Option<f64> {
    match v {
        Value::Float(x) => Some(*x),
        Value::Int(i) => Some(*i as f64),
        _ => None,
    }
}

/// The view fitting the keys of `params` (expressions: their values over `frames`).
fn fit_view(params: &[&AnimParam], frames: (f64, f64), fps: f64, rect: Rect) -> CurveView {
    let (mut f, mut v) = ((f64::INFINITY, f64::NEG_INFINITY), (f64::INFINITY, f64::NEG_INFINITY));
    let grow = |r: &mut (f64, f64), x: f64| {
        if x.is_finite() {
            *r = (r.0.min(x), r.1.max(x));
        }
    };
    for p in params {
        match p.animated.tracks().first() {
            Some(Track::Keys(c)) => {
                for k in c.keys() {
                    grow(&mut f, k.frame);
                }
                let (lo, hi) = c.value_bounds();
                grow(&mut v, lo);
                grow(&mut v, hi);
            }
            _ => {
                grow(&mut f, frames.0);
                grow(&mut f, frames.1);
                let n = (frames.1 - frames.0).clamp(1.0, 2000.0) as usize;
                for i in 0..=n {
                    let frame = frames.0 + (frames.1 - frames.0) * i as f64 / n as f64;
                    if let Some(x) = p.animated.sample(frame, fps).ok().as_ref().and_then(number) {
                        grow(&mut v, x);
                    }
                }
            }
        }
    }
    // No keys, or one frame of keys: show the clip around them.
    if !f.0.is_finite() || f.1 - f.0 < 1.0 {
        f = if f.0.is_finite() { (f.0.min(frames.0), f.1.max(frames.1)) } else { frames };
    }
    if !v.0.is_finite() {
        v = (0.0, 1.0);
    }
    let fpad = ((f.1 - f.0) * 0.06).max(2.0);
    let span = v.1 - v.0;
    let vpad = if span < 1e-9 { (v.0.abs() * 0.1).max(0.1) } else { span * 0.12 };
    CurveView { frames: (f.0 - fpad, f.1 + fpad), values: (v.0 - vpad, v.1 + vpad), rect }
}

impl EditorApp {
    /// Whether the curve editor has something to show: the current node has animated numbers.
    pub(crate) fn curves_wanted(&self) -> bool {
        self.key_ui.show_curves
            && self.editor.current().is_some_and(|n| self.editor.animated_params(n).iter().any(AnimParam::is_scalar))
    }

    fn scalar_params(&self, node: &str) -> Vec<AnimParam> {
        self.editor.animated_params(node).into_iter().filter(AnimParam::is_scalar).collect()
    }

    /// The curve editor panel.
    pub(crate) fn curves_ui(&mut self, ui: &mut egui::Ui) {
        let Some(node) = self.editor.current().map(str::to_string) else { return };
        self.key_ui.panel_rect = Some(ui.max_rect());
        let params = self.scalar_params(&node);
        self.curves_header(ui, &node, &params);
        let (rect, bg) = ui.allocate_exact_size(ui.available_size().max(Vec2::new(100.0, 60.0)), Sense::click_and_drag());
        let plot = Rect::from_min_max(rect.min + Vec2::new(52.0, 4.0), rect.max - Vec2::new(10.0, 18.0));
        let clip_frames = self.editor.preview().and_then(|p| p.clip_len).filter(|n| *n > 0);
        let frames = (0.0, clip_frames.map_or(48.0, |n| (n - 1) as f64));
        let visible = |ps: &[AnimParam], hidden: &BTreeSet<String>| -> Vec<(usize, AnimParam)> {
            ps.iter().enumerate().filter(|(_, p)| !hidden.contains(&p.port.name)).map(|(i, p)| (i, p.clone())).collect()
        };
        let shown = visible(&params, &self.key_ui.hidden);
        if self.key_ui.fit || self.key_ui.view.is_none() {
            let refs: Vec<&AnimParam> = shown.iter().map(|(_, p)| p).collect();
            self.key_ui.view = Some(fit_view(&refs, frames, self.editor.fps(), plot));
            self.key_ui.fit = false;
        }
        if let Some(v) = &mut self.key_ui.view {
            v.rect = plot;
        }
        self.curve_navigation(ui, &bg, clip_frames);
        self.drag_key(ui, &node);
        // The drag may have changed the keys: read them again for drawing.
        let shown = visible(&self.scalar_params(&node), &self.key_ui.hidden);
        let Some(view) = self.key_ui.view else { return };
        let painter = ui.painter_at(rect);
        painter.rect_filled(plot, 2.0, Color32::from_gray(22));
        self.paint_grid(&painter, &view, rect);
        let plot_painter = ui.painter_at(plot);
        let fps = self.editor.fps();
        for (ci, p) in &shown {
            paint_curve(&plot_painter, &view, p, fps, channel_color(*ci));
        }
        let x = view.to_screen(self.editor.frame() as f64, 0.0).x;
        if plot.x_range().contains(x) {
            plot_painter.vline(x, plot.y_range(), Stroke::new(1.5, Color32::from_rgb(235, 235, 235)));
            let text = frame_text(self.editor.frame() as f64);
            painter.text(
                Pos2::new(x + 3.0, plot.top() + 2.0),
                egui::Align2::LEFT_TOP,
                text,
                egui::FontId::monospace(11.0),
                Color32::WHITE,
            );
        }
        if shown.is_empty() {
            painter.text(
                plot.center(),
                egui::Align2::CENTER_CENTER,
                "every curve is hidden",
                egui::FontId::proportional(13.0),
                Color32::GRAY,
            );
        }
        self.key_handles(ui, &node, &shown, &view);
        self.tangent_handles(ui, &node, &shown, &view);
    }

    fn curves_header(&mut self, ui: &mut egui::Ui, node: &str, params: &[AnimParam]) {
        ui.horizontal(|ui| {
            ui.label(RichText::new(format!("Curves · {node}")).strong());
            for (i, p) in params.iter().enumerate() {
                let name = &p.port.name;
                let shown = !self.key_ui.hidden.contains(name);
                let color = if shown { channel_color(i) } else { Color32::GRAY };
                let tip = if KeyList::read(&p.value).is_some() {
                    "show or hide this curve"
                } else {
                    "an expression (dashed): edit it in the inspector"
                };
                let mut on = shown;
                if ui.checkbox(&mut on, RichText::new(name).color(color)).on_hover_text(tip).changed() {
                    if shown {
                        self.key_ui.hidden.insert(name.clone());
                    } else {
                        self.key_ui.hidden.remove(name);
                    }
                }
            }
            ui.separator();
            if ui.button("Frame").on_hover_text("Fit the view to the keys (F with the pointer over the curves)").clicked() {
                self.key_ui.fit = true;
            }
            let first = self.key_ui.selected.first().map(|(p, _)| p.clone());
            if ui
                .add_enabled(first.is_some(), egui::Button::new("Copy keys"))
                .on_hover_text("Copy the selected keys of one curve")
                .clicked()
                && let Some(param) = first.clone()
            {
                let indices: Vec<usize> = params
                    .iter()
                    .find(|p| p.port.name == param)
                    .and_then(AnimParam::keys)
                    .map(|l| self.key_ui.selected.iter().filter(|(p, _)| *p == param).filter_map(|(_, f)| l.find(*f)).collect())
                    .unwrap_or_default();
                self.editor.copy_keys(node, &param, &indices);
                self.key_ui.copied_from = Some(param);
            }
            let target = first.or_else(|| self.key_ui.copied_from.clone()).filter(|t| params.iter().any(|p| p.port.name == *t));
            let can_paste = target.is_some() && !self.editor.copied_keys().is_empty();
            let tip = "Paste the copied keys at the playhead, into the selected key's curve";
            if ui.add_enabled(can_paste, egui::Button::new("Paste keys")).on_hover_text(tip).clicked()
                && let Some(param) = target
            {
                let _ = self.editor.paste_keys(node, &param, self.editor.frame() as f64);
                self.editor.seal();
            }
            ui.weak("drag a key · Del deletes · click scrubs · wheel / Ctrl+wheel zoom · right-drag pans");
        });
    }

    /// Zoom (wheel: frames, Ctrl+wheel: values), pan (right or middle drag) and scrubbing (a click or
    /// drag on the background moves the playhead).
    fn curve_navigation(&mut self, ui: &egui::Ui, bg: &Response, clip_frames: Option<usize>) {
        let Some(view) = &mut self.key_ui.view else { return };
        if bg.hovered() {
            let (scroll, zoom, pointer) = ui.input(|i| (i.smooth_scroll_delta, i.zoom_delta(), i.pointer.hover_pos()));
            if let Some(p) = pointer {
                let (fp, vp) = view.from_screen(p);
                let s = f64::from(scroll.x + scroll.y);
                if s != 0.0 {
                    let k = (-s * 0.004).exp();
                    let span = ((view.frames.1 - view.frames.0) * k).clamp(2.0, 1e6) / (view.frames.1 - view.frames.0);
                    view.frames = (fp - (fp - view.frames.0) * span, fp + (view.frames.1 - fp) * span);
                }
                if zoom != 1.0 {
                    let k = 1.0 / f64::from(zoom);
                    view.values = (vp - (vp - view.values.0) * k, vp + (view.values.1 - vp) * k);
                }
            }
        }
        if bg.dragged_by(PointerButton::Secondary) || bg.dragged_by(PointerButton::Middle) {
            let d = bg.drag_delta();
            let fs = (view.frames.1 - view.frames.0) / f64::from(view.rect.width().max(1.0));
            let vs = (view.values.1 - view.values.0) / f64::from(view.rect.height().max(1.0));
            let (df, dv) = (-f64::from(d.x) * fs, f64::from(d.y) * vs);
            view.frames = (view.frames.0 + df, view.frames.1 + df);
            view.values = (view.values.0 + dv, view.values.1 + dv);
        }
        let scrub = bg.clicked() || bg.dragged_by(PointerButton::Primary);
        if scrub
            && self.key_ui.drag.is_none()
            && let Some(p) = bg.interact_pointer_pos()
        {
            let last = clip_frames.map_or(f64::MAX, |n| (n - 1) as f64);
            let frame = view.from_screen(p).0.round().clamp(0.0, last);
            self.playback.set_playing(false);
            self.editor.set_frame(frame as usize);
        }
        if bg.clicked() {
            self.key_ui.clear_selection();
        }
    }

    /// Moves the dragged key to the pointer: whole frames (a frame another key holds keeps the
    /// key's frame), the value rounded to about a pixel and kept in the port's range.
    fn drag_key(&mut self, ui: &egui::Ui, node: &str) {
        let (Some(mut drag), Some(view)) = (self.key_ui.drag.clone(), self.key_ui.view) else { return };
        let (down, pos) = ui.input(|i| (i.pointer.primary_down(), i.pointer.latest_pos()));
        if !down {
            self.key_ui.drag = None;
            self.editor.seal();
            return;
        }
        let Some(pos) = pos else { return };
        let port = self.editor.scalar_port(node, &drag.param).ok();
        let list = self.editor.doc().node(node).and_then(|n| n.params.get(&drag.param)).and_then(KeyList::read);
        let (Some(port), Some(list)) = (port, list) else {
            self.key_ui.drag = None;
            return;
        };
        let Some(key) = list.keys.get(drag.index).cloned() else {
            self.key_ui.drag = None;
            return;
        };
        let (f, v) = view.from_screen(pos - drag.grab);
        let mut frame = f.round().max(0.0);
        let mut value = if port.ty == PortType::Int {
            v.round()
        } else {
            let pixel = (view.values.1 - view.values.0) / f64::from(view.rect.height().max(1.0));
            let decimals = (-pixel.log10().floor()).clamp(0.0, 12.0) as usize;
            format!("{v:.decimals$}").parse().unwrap_or(v)
        };
        if let Some((lo, hi)) = port.range {
            value = value.clamp(lo, hi);
        }
        if list.find(frame).is_some_and(|j| j != drag.index) {
            frame = key.frame;
        }
        if (frame - key.frame).abs() < SAME_FRAME && value == key.value {
            return;
        }
        if let Ok(i) = self.editor.move_key(node, &drag.param, drag.index, frame, value) {
            drag.index = i;
            self.key_ui.selected = vec![(drag.param.clone(), frame)];
            self.key_ui.drag = Some(drag);
        }
    }

    fn paint_grid(&self, painter: &egui::Painter, view: &CurveView, rect: Rect) {
        let plot = view.rect;
        let line = Stroke::new(1.0, Color32::from_gray(42));
        let font = egui::FontId::monospace(10.0);
        let label = Color32::from_gray(150);
        let fstep = nice_step((view.frames.1 - view.frames.0) / f64::from((plot.width() / 70.0).max(1.0))).max(1.0);
        let mut f = (view.frames.0 / fstep).ceil() * fstep;
        while f <= view.frames.1 {
            let x = view.to_screen(f, 0.0).x;
            painter.vline(x, plot.y_range(), line);
            painter.text(Pos2::new(x, plot.bottom() + 2.0), egui::Align2::CENTER_TOP, frame_text(f), font.clone(), label);
            f += fstep;
        }
        let vstep = nice_step((view.values.1 - view.values.0) / f64::from((plot.height() / 28.0).max(1.0)));
        let mut v = (view.values.0 / vstep).ceil() * vstep;
        while v <= view.values.1 {
            let y = view.to_screen(0.0, v).y;
            painter.hline(plot.x_range(), y, line);
            let text = value_text((v / vstep).round() * vstep);
            painter.text(Pos2::new(rect.left() + 48.0, y), egui::Align2::RIGHT_CENTER, text, font.clone(), label);
            v += vstep;
        }
        painter.rect_stroke(plot, 2.0, Stroke::new(1.0, Color32::from_gray(60)), egui::StrokeKind::Inside);
    }

    /// A handle per key of the shown keyed curves.
    fn key_handles(&mut self, ui: &mut egui::Ui, node: &str, shown: &[(usize, AnimParam)], view: &CurveView) {
        let painter = ui.painter_at(view.rect.expand(7.0));
        let shift = ui.input(|i| i.modifiers.shift);
        for (ci, p) in shown {
            let Some(list) = p.keys() else { continue };
            let name = p.port.name.clone();
            for (i, k) in list.keys.iter().enumerate() {
                let pos = view.to_screen(k.frame, k.value);
                if !view.rect.expand(6.0).contains(pos) {
                    continue;
                }
                let rect = Rect::from_center_size(pos, Vec2::splat(13.0));
                let resp = ui.interact(rect, egui::Id::new(("curve-key", node, &name, i)), Sense::click_and_drag());
                resp.widget_info(|| WidgetInfo::labeled(WidgetType::Button, true, format!("key {} of {name}", i + 1)));
                let selected = self.key_ui.is_selected(&name, k.frame);
                let fill = if selected { Color32::WHITE } else { channel_color(*ci) };
                let r = if resp.hovered() || selected { 6.0 } else { 5.0 };
                diamond(&painter, pos, r, fill, Stroke::new(1.0, Color32::from_gray(15)));
                if resp.drag_started_by(PointerButton::Primary) {
                    let origin = ui.input(|i| i.pointer.press_origin()).unwrap_or(pos);
                    self.key_ui.drag = Some(KeyDrag { param: name.clone(), index: i, grab: origin - pos });
                    if !selected {
                        self.key_ui.select(vec![(name.clone(), k.frame)], false);
                    }
                } else if resp.clicked() {
                    self.key_ui.select(vec![(name.clone(), k.frame)], shift);
                }
                let interp = match &k.interp {
                    Some(ParamValue::String(name)) => format!(" ({name})"),
                    Some(other) => format!(" ({other})"),
                    None => String::new(),
                };
                resp.on_hover_text(format!(
                    "{name} @ {} = {}{interp}\ndrag to move it (whole frames); Del deletes the selected keys",
                    frame_text(k.frame),
                    value_text(k.value)
                ));
            }
        }
    }
}

/// The curve of `p` over the view (dashed for an expression).
fn paint_curve(painter: &egui::Painter, view: &CurveView, p: &AnimParam, fps: f64, color: Color32) {
    let plot = view.rect;
    let mut pts = Vec::with_capacity(plot.width() as usize / 2 + 2);
    let mut x = plot.left();
    while x <= plot.right() + 1.0 {
        let (frame, _) = view.from_screen(Pos2::new(x, plot.top()));
        if let Some(v) = p.animated.sample(frame, fps).ok().as_ref().and_then(number) {
            let y = view.to_screen(frame, v).y.clamp(plot.top() - 1e4, plot.bottom() + 1e4);
            pts.push(Pos2::new(x, y));
        }
        x += 2.0;
    }
    if pts.len() < 2 {
        return;
    }
    if KeyList::read(&p.value).is_some() {
        painter.add(egui::Shape::line(pts, Stroke::new(2.0, color)));
    } else {
        painter.extend(egui::Shape::dashed_line(&pts, Stroke::new(1.5, color), 6.0, 4.0));
    }
}
