//! Keyframing in the inspector and under the preview: the key toggle beside Float, Int, Bool,
//! Vec2, Vec3 and Color parameters (filled diamond: a key at the current frame; hollow: animated, no key here; dim
//! hollow: constant), the row of an animated parameter (its value at the current frame and its
//! keys or expression as text), and the strip of key ticks under the frame scrubber.

use std::collections::BTreeMap;

use eframe::egui::{self, Color32, Pos2, Rect, RichText, Sense, Stroke, Vec2, WidgetInfo, WidgetType};
use pyrograph_frontend::core::value::animated_param;
use pyrograph_frontend::core::{ParamValue, PortDesc, PortType, Value, anim::Track};

use crate::app::EditorApp;
use crate::keys::{KeyList, frame_text};
use crate::param_widgets::buffered_text;
use crate::state::value_text;
use crate::state::vector_keys::{all_keyed_at, components};

/// The key colour.
pub const KEY_COLOR: Color32 = Color32::from_rgb(240, 190, 60);

/// What the key toggle of a parameter shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum KeyState {
    /// A constant: a dim hollow diamond.
    Constant,
    /// Animated, with no key at the current frame: a hollow diamond.
    Animated,
    /// A key at the current frame: a filled diamond.
    KeyHere,
}

impl KeyState {
    /// The state of a parameter holding `value`, at `frame`.
    pub fn of(value: Option<&ParamValue>, frame: f64) -> KeyState {
        match value {
            Some(v) if KeyList::read(v).is_some_and(|l| l.find(frame).is_some()) => KeyState::KeyHere,
            Some(v) if v.is_animated() => KeyState::Animated,
            _ => KeyState::Constant,
        }
    }

    /// The state of a Vec2, Vec3 or Color parameter of `n` components holding `value`: a key
    /// here when every component has one at `frame`.
    pub fn of_vector(value: Option<&ParamValue>, n: usize, frame: f64) -> KeyState {
        match value {
            Some(v) if all_keyed_at(v, n, frame) => KeyState::KeyHere,
            Some(v) if v.is_animated() => KeyState::Animated,
            _ => KeyState::Constant,
        }
    }
}

/// A diamond centred on `c` with half-diagonal `r`.
pub fn diamond(painter: &egui::Painter, c: Pos2, r: f32, fill: Color32, stroke: Stroke) {
    let pts = vec![c + Vec2::new(0.0, -r), c + Vec2::new(r, 0.0), c + Vec2::new(0.0, r), c + Vec2::new(-r, 0.0)];
    painter.add(egui::Shape::convex_polygon(pts, fill, stroke));
}

/// The key toggle of parameter `param`: a diamond, accessible as "key PARAM" (a checkbox,
/// checked when a key is at the current frame).
pub fn key_toggle(ui: &mut egui::Ui, state: KeyState, param: &str, frame: f64) -> egui::Response {
    let (rect, resp) = ui.allocate_exact_size(Vec2::splat(ui.spacing().interact_size.y), Sense::click());
    resp.widget_info(|| WidgetInfo::selected(WidgetType::Checkbox, true, state == KeyState::KeyHere, format!("key {param}")));
    let r = if resp.hovered() { 6.0 } else { 5.0 };
    let (fill, stroke) = match state {
        KeyState::KeyHere => (KEY_COLOR, Stroke::new(1.0, KEY_COLOR)),
        KeyState::Animated => (Color32::TRANSPARENT, Stroke::new(1.5, KEY_COLOR)),
        KeyState::Constant => {
            (Color32::TRANSPARENT, Stroke::new(1.0, Color32::from_gray(if resp.hovered() { 170 } else { 100 })))
        }
    };
    diamond(ui.painter(), rect.center(), r, fill, stroke);
    let f = frame_text(frame);
    resp.on_hover_text(match state {
        KeyState::KeyHere => format!("{param} has a key at frame {f}: click to delete it (right-click for more)"),
        KeyState::Animated => format!("{param} is animated, no key at frame {f}: click to set one (right-click for more)"),
        KeyState::Constant => format!("{param} is constant: click to set a key at frame {f} (right-click for more)"),
    })
}

/// A value sampled from an animation, for display.
pub fn value_summary(v: &Value) -> String {
    let join = |xs: &[f64]| xs.iter().map(|x| value_text(*x)).collect::<Vec<_>>().join(", ");
    match v {
        Value::Float(x) => value_text(*x),
        Value::Int(i) => i.to_string(),
        Value::Bool(b) => b.to_string(),
        Value::Vec2(c) => format!("({})", join(c)),
        Value::Vec3(c) => format!("({})", join(c)),
        Value::Color(c) => format!("({})", join(&c.map(f64::from))),
        other => format!("{other:?}"),
    }
}

/// The row of an animated parameter: its value at `frame` and the text of its keys or
/// expression (committed on Enter or when the field loses focus). Returns a new value typed in.
pub fn animated_row(
    ui: &mut egui::Ui,
    id: egui::Id,
    port: &PortDesc,
    value: &ParamValue,
    frame: f64,
    fps: f64,
) -> Option<ParamValue> {
    let sampled = animated_param(value, &port.ty).and_then(|a| match a {
        Some(a) => a.sample_in(frame, fps, port.range),
        None => Err("not animated".into()),
    });
    let mut out = None;
    ui.horizontal(|ui| {
        match &sampled {
            Ok(v) => {
                ui.label(RichText::new(value_summary(v)).monospace().color(KEY_COLOR)).on_hover_text(format!(
                    "{} at frame {}",
                    port.name,
                    frame_text(frame)
                ));
            }
            Err(e) => {
                ui.label(RichText::new("⚠").color(Color32::from_rgb(255, 120, 120))).on_hover_text(e);
            }
        }
        out = buffered_text(ui, id.with("anim-text"), &value.to_string(), false).map(|t| ParamValue::parse_cli(&t));
    });
    out
}

/// One tick of the key strip: every key of the node at one frame.
struct Tick {
    frame: f64,
    /// `param @ frame = value` for each key there.
    lines: Vec<String>,
    /// The (parameter, frame) of each Float or Int key there (the ones Delete deletes).
    scalar: Vec<(String, f64)>,
}

impl EditorApp {
    /// The key toggle of `port` on `node` in the inspector, with its right-click menu.
    pub(crate) fn key_toggle_cell(&mut self, ui: &mut egui::Ui, node: &str, port: &PortDesc, value: Option<&ParamValue>) {
        let frame = self.editor.frame() as f64;
        let vector = components(&port.ty);
        let state = match vector {
            Some(n) => KeyState::of_vector(value, n, frame),
            None => KeyState::of(value, frame),
        };
        let resp = key_toggle(ui, state, &port.name, frame);
        self.key_ui.toggle_rects.insert(port.name.clone(), resp.rect);
        let toggle = |app: &mut EditorApp| {
            // Errors go to the status line.
            let _ = match vector {
                Some(_) => app.editor.toggle_vector_key(node, &port.name, frame),
                None => app.editor.toggle_key(node, &port.name, frame),
            };
            app.editor.seal();
        };
        if resp.clicked() {
            toggle(self);
        }
        resp.context_menu(|ui| {
            if ui.button(if state == KeyState::KeyHere { "Delete key" } else { "Set key" }).clicked() {
                toggle(self);
                ui.close();
            }
            if vector.is_some() {
                return;
            }
            let sampled = self.editor.scalar_at(node, port, frame).ok();
            let sampled = sampled.map(|v| if matches!(port.ty, PortType::Int | PortType::Bool) { v.round() } else { v });
            if state == KeyState::Constant {
                if ui.button("Animate with an expression").clicked() {
                    let text = sampled.map_or("0".into(), value_text);
                    let _ = self.editor.set_param(
                        node,
                        &port.name,
                        ParamValue::Call("expr".into(), Box::new(ParamValue::String(text))),
                    );
                    self.editor.seal();
                    ui.close();
                }
            } else if let Some(v) = sampled
                && ui.button(format!("Stop animating (keep {} from frame {})", value_text(v), frame_text(frame))).clicked()
            {
                let constant = match port.ty {
                    PortType::Int => ParamValue::Int(v as i64),
                    PortType::Bool => ParamValue::Bool(v > 0.5),
                    _ => ParamValue::Float(v),
                };
                let _ = self.editor.set_param(node, &port.name, constant);
                self.editor.seal();
                ui.close();
            }
        });
    }

    /// The strip of key ticks under the frame scrubber (`slider`, over frames `0..len`): a tick
    /// per frame holding keys of the previewed node; hovering lists them, clicking moves the
    /// playhead there and selects them (Delete deletes them).
    pub(crate) fn key_strip(&mut self, ui: &mut egui::Ui, node: &str, slider: Rect, len: usize) {
        let params = self.editor.animated_params(node);
        if params.is_empty() {
            return;
        }
        let mut ticks: BTreeMap<i64, Tick> = BTreeMap::new();
        for p in &params {
            let comps = p.animated.tracks().len();
            for (c, track) in p.animated.tracks().iter().enumerate() {
                let Track::Keys(channel) = track else { continue };
                let name =
                    if comps > 1 { format!("{}.{}", p.port.name, ["x", "y", "z", "w"][c.min(3)]) } else { p.port.name.clone() };
                for k in channel.keys() {
                    let t = ticks.entry((k.frame * 1000.0).round() as i64).or_insert(Tick {
                        frame: k.frame,
                        lines: Vec::new(),
                        scalar: Vec::new(),
                    });
                    t.lines.push(format!("{name} @ {} = {}", frame_text(k.frame), value_text(k.value)));
                    if p.is_scalar() || p.port.ty == PortType::Bool {
                        t.scalar.push((p.port.name.clone(), k.frame));
                    }
                }
            }
        }
        let h = 14.0;
        let (strip, _) = ui.allocate_exact_size(egui::vec2(ui.available_width(), h), Sense::hover());
        let range = slider.x_range().shrink(slider.height() / 2.5);
        let max = len.saturating_sub(1) as f64;
        let last = max.max(1.0);
        let painter = ui.painter_at(strip.expand(2.0));
        painter.hline(range, strip.center().y, Stroke::new(1.0, Color32::from_gray(70)));
        let now = self.editor.frame() as f64;
        for (bits, tick) in ticks {
            if tick.frame < 0.0 || tick.frame > max + 1e-9 {
                continue;
            }
            let x = range.min + (tick.frame / last) as f32 * range.span();
            let rect = Rect::from_center_size(egui::pos2(x, strip.center().y), egui::vec2(9.0, h));
            let resp = ui.interact(rect, egui::Id::new(("key-tick", node, bits)), Sense::click());
            let label = tick.lines.join("\n");
            resp.widget_info(|| WidgetInfo::labeled(WidgetType::Button, true, &label));
            let selected = !tick.scalar.is_empty() && tick.scalar.iter().all(|k| self.key_ui.is_selected(&k.0, k.1));
            let here = (tick.frame - now).abs() < 1e-6;
            let fill = if selected { Color32::WHITE } else { KEY_COLOR };
            let stroke = Stroke::new(if here { 2.0 } else { 1.0 }, if here { Color32::WHITE } else { fill });
            diamond(&painter, rect.center(), if resp.hovered() { 5.5 } else { 4.5 }, fill, stroke);
            let clicked = resp.clicked();
            let shift = ui.input(|i| i.modifiers.shift);
            resp.on_hover_text(&label);
            if clicked {
                self.playback.set_playing(false);
                self.editor.set_frame(tick.frame.round().clamp(0.0, max) as usize);
                self.key_ui.select(tick.scalar, shift);
            }
        }
    }
}
