//! The curve editor's state, apart from the panel that draws it (`curves`): the app holds it as a
//! field, and keeping it here leaves the app and the panel without a file-level import cycle.

use std::collections::{BTreeMap, BTreeSet};

use eframe::egui::{self, Pos2, Rect, Vec2};

use crate::keys::SAME_FRAME;

/// The editor's keyframing state: the selected keys, the curve view, a key being dragged.
pub struct KeyUi {
    /// Whether the curve editor is shown (when the current node has animated numbers).
    pub show_curves: bool,
    pub(crate) node: Option<String>,
    pub(crate) selected: Vec<(String, f64)>,
    pub(crate) view: Option<CurveView>,
    pub(crate) hidden: BTreeSet<String>,
    pub(crate) drag: Option<KeyDrag>,
    /// The key whose tangent handle is being dragged: (parameter, key index).
    pub(crate) tangent_drag: Option<(String, usize)>,
    pub(crate) fit: bool,
    pub(crate) copied_from: Option<String>,
    /// Where the panel was drawn last frame (F over it frames the curves, not the canvas).
    pub(crate) panel_rect: Option<Rect>,
    /// Where each key toggle of the inspector was drawn this frame (for the state dump).
    pub(crate) toggle_rects: BTreeMap<String, Rect>,
}

/// A key being dragged: which, and where the pointer holds it.
#[derive(Clone, Debug)]
pub(crate) struct KeyDrag {
    pub(crate) param: String,
    pub(crate) index: usize,
    pub(crate) grab: Vec2,
}

/// What the plot shows: a frame span and a value span over a screen rectangle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CurveView {
    /// First and last frame shown.
    pub frames: (f64, f64),
    /// Lowest and highest value shown.
    pub values: (f64, f64),
    /// The plot's rectangle on screen.
    pub rect: Rect,
}

impl CurveView {
    /// Where (`frame`, `value`) is on screen.
    pub fn to_screen(&self, frame: f64, value: f64) -> Pos2 {
        let x = (frame - self.frames.0) / (self.frames.1 - self.frames.0);
        let y = (value - self.values.0) / (self.values.1 - self.values.0);
        Pos2::new(self.rect.left() + x as f32 * self.rect.width(), self.rect.bottom() - y as f32 * self.rect.height())
    }

    /// The (frame, value) at screen point `p`.
    pub fn from_screen(&self, p: Pos2) -> (f64, f64) {
        let x = f64::from((p.x - self.rect.left()) / self.rect.width().max(1.0));
        let y = f64::from((self.rect.bottom() - p.y) / self.rect.height().max(1.0));
        (self.frames.0 + x * (self.frames.1 - self.frames.0), self.values.0 + y * (self.values.1 - self.values.0))
    }
}

impl Default for KeyUi {
    fn default() -> Self {
        KeyUi {
            show_curves: true,
            node: None,
            selected: Vec::new(),
            view: None,
            hidden: BTreeSet::new(),
            drag: None,
            tangent_drag: None,
            fit: false,
            copied_from: None,
            panel_rect: None,
            toggle_rects: BTreeMap::new(),
        }
    }
}

impl KeyUi {
    /// The selected keys, as (parameter, frame) of the current node.
    pub fn selected(&self) -> &[(String, f64)] {
        &self.selected
    }

    /// The curve view as last drawn.
    pub fn view(&self) -> Option<CurveView> {
        self.view
    }

    pub(crate) fn is_selected(&self, param: &str, frame: f64) -> bool {
        self.selected.iter().any(|(p, f)| p == param && (f - frame).abs() < SAME_FRAME)
    }

    /// Selects `keys`, or with `add` toggles them in the selection.
    pub(crate) fn select(&mut self, keys: Vec<(String, f64)>, add: bool) {
        if !add {
            self.selected = keys;
            return;
        }
        for (p, f) in keys {
            match self.selected.iter().position(|(q, g)| *q == p && (g - f).abs() < SAME_FRAME) {
                Some(i) => {
                    self.selected.remove(i);
                }
                None => self.selected.push((p, f)),
            }
        }
    }

    /// Forgets the selected keys.
    pub fn clear_selection(&mut self) {
        self.selected.clear();
    }

    /// Follows the current node: another node starts with no selection and a fitted view.
    pub(crate) fn sync(&mut self, node: Option<&str>) {
        if self.node.as_deref() != node {
            *self = KeyUi { show_curves: self.show_curves, node: node.map(str::to_string), ..KeyUi::default() };
        }
    }

    /// Asks for the view to be fitted to the keys on the next frame.
    pub fn request_fit(&mut self) {
        self.fit = true;
    }

    /// Whether the pointer is over the curve editor.
    pub(crate) fn hovered(&self, ctx: &egui::Context) -> bool {
        let p = ctx.input(|i| i.pointer.hover_pos());
        matches!((self.panel_rect, p), (Some(r), Some(p)) if r.contains(p))
    }
}
