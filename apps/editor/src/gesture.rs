//! Pointer gestures on the canvas: what a press lands on, and what click, Shift-click and
//! rectangle selection make of the selection.
//!
//! egui-snarl selects only with Shift held and pans on any drag of empty canvas. Node editors
//! (Houdini, Nuke, Graphite) select on a plain click and draw a selection rectangle when a drag
//! starts on empty canvas, so the canvas runs its own gestures: it classifies each press here,
//! keeps the snarl from panning while a rectangle is drawn, and turns the release into a new
//! selection with the functions below. They are plain functions so tests can check the rules
//! without a window.

use eframe::egui::{Modifiers, Pos2, Rect};

/// A press moves this far (points) before it counts as a drag, as egui's own threshold.
pub const DRAG_THRESHOLD: f32 = 6.0;

/// What a primary press landed on.
#[derive(Clone, Debug, PartialEq)]
pub enum Target {
    /// A node (its frame, header, body or one of its pins).
    Node(String),
    /// The title bar of the group with this index.
    GroupBar(usize),
    /// The comment with this index.
    Comment(usize),
    /// Empty canvas.
    Empty,
}

/// A primary-button gesture from press to release.
#[derive(Clone, Debug)]
pub struct Gesture {
    /// Screen position of the press.
    pub origin: Pos2,
    /// Latest screen position.
    pub current: Pos2,
    /// Screen position at the previous frame (group and comment drags move by the difference).
    pub last: Pos2,
    /// What the press landed on.
    pub target: Target,
    /// Modifiers held at the press.
    pub mods: Modifiers,
    /// Whether the pointer has moved past [`DRAG_THRESHOLD`].
    pub dragging: bool,
    /// Whether the drag already set the selection (a drag of an unselected node selects it).
    pub selected_on_drag: bool,
}

impl Gesture {
    /// A gesture pressed at `origin` on `target`.
    pub fn new(origin: Pos2, target: Target, mods: Modifiers) -> Self {
        Gesture { origin, current: origin, last: origin, target, mods, dragging: false, selected_on_drag: false }
    }

    /// Follows the pointer.
    pub fn update(&mut self, pos: Pos2) {
        self.last = self.current;
        self.current = pos;
        if self.origin.distance(pos) > DRAG_THRESHOLD {
            self.dragging = true;
        }
    }

    /// Whether the view must stay put during this gesture: a rectangle on empty canvas (Alt
    /// held pans instead), or a group or comment being dragged.
    pub fn holds_view(&self) -> bool {
        match self.target {
            Target::Empty => !self.mods.alt,
            Target::GroupBar(_) | Target::Comment(_) => true,
            Target::Node(_) => false,
        }
    }

    /// The selection rectangle in screen space, once dragging on empty canvas.
    pub fn rect(&self) -> Option<Rect> {
        (self.target == Target::Empty && self.dragging && !self.mods.alt).then(|| Rect::from_two_pos(self.origin, self.current))
    }
}

/// Whether the modifiers extend a selection (Shift) or toggle within it (Ctrl / Cmd).
fn extends(mods: Modifiers) -> bool {
    mods.shift || mods.command
}

/// The selection after a click on `node`, or on empty canvas when `None`.
///
/// - plain click: just that node (empty canvas: nothing);
/// - Shift-click or Ctrl-click: toggles that node, the rest stays (empty canvas: unchanged).
///
/// The node clicked last is the last element: the inspector and preview follow it.
pub fn after_click(current: &[String], node: Option<&str>, mods: Modifiers) -> Vec<String> {
    match (node, extends(mods)) {
        (None, false) => Vec::new(),
        (None, true) => current.to_vec(),
        (Some(n), false) => vec![n.to_string()],
        (Some(n), true) => {
            let mut out: Vec<String> = current.iter().filter(|c| *c != n).cloned().collect();
            if out.len() == current.len() {
                out.push(n.to_string());
            }
            out
        }
    }
}

/// The selection after a rectangle that touched `hits` (in document order).
///
/// - plain: exactly the hits;
/// - Shift: the current selection plus the hits;
/// - Ctrl / Cmd: the current selection minus the hits.
pub fn after_rect(current: &[String], hits: &[String], mods: Modifiers) -> Vec<String> {
    if mods.command {
        return current.iter().filter(|c| !hits.contains(c)).cloned().collect();
    }
    let mut out = if mods.shift { current.to_vec() } else { Vec::new() };
    for h in hits {
        if !out.contains(h) {
            out.push(h.clone());
        }
    }
    out
}

/// The selection when a drag of `node` starts: a selected node drags the whole selection, an
/// unselected one becomes the selection (or joins it with Shift).
pub fn on_node_drag(current: &[String], node: &str, mods: Modifiers) -> Vec<String> {
    if current.iter().any(|c| c == node) {
        current.to_vec()
    } else if extends(mods) {
        let mut out = current.to_vec();
        out.push(node.to_string());
        out
    } else {
        vec![node.to_string()]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn s(v: &[&str]) -> Vec<String> {
        v.iter().map(|x| x.to_string()).collect()
    }

    #[test]
    fn a_plain_click_selects_one_node_and_empty_canvas_clears() {
        assert_eq!(after_click(&s(&["a", "b"]), Some("c"), Modifiers::NONE), s(&["c"]));
        assert_eq!(after_click(&s(&["a", "b"]), None, Modifiers::NONE), s(&[]));
    }

    #[test]
    fn shift_click_toggles_and_keeps_the_rest() {
        assert_eq!(after_click(&s(&["a"]), Some("b"), Modifiers::SHIFT), s(&["a", "b"]));
        assert_eq!(after_click(&s(&["a", "b"]), Some("a"), Modifiers::SHIFT), s(&["b"]));
        assert_eq!(after_click(&s(&["a"]), None, Modifiers::SHIFT), s(&["a"]));
        assert_eq!(after_click(&s(&["a"]), Some("b"), Modifiers::COMMAND), s(&["a", "b"]));
    }

    #[test]
    fn rectangles_replace_add_or_remove() {
        let cur = s(&["a", "b"]);
        assert_eq!(after_rect(&cur, &s(&["c", "d"]), Modifiers::NONE), s(&["c", "d"]));
        assert_eq!(after_rect(&cur, &s(&["b", "c"]), Modifiers::SHIFT), s(&["a", "b", "c"]));
        assert_eq!(after_rect(&cur, &s(&["b", "c"]), Modifiers::COMMAND), s(&["a"]));
    }

    #[test]
    fn dragging_a_selected_node_keeps_the_selection() {
        assert_eq!(on_node_drag(&s(&["a", "b"]), "b", Modifiers::NONE), s(&["a", "b"]));
        assert_eq!(on_node_drag(&s(&["a", "b"]), "c", Modifiers::NONE), s(&["c"]));
        assert_eq!(on_node_drag(&s(&["a"]), "c", Modifiers::SHIFT), s(&["a", "c"]));
    }

    #[test]
    fn a_press_becomes_a_drag_past_the_threshold_and_alt_pans() {
        let mut g = Gesture::new(Pos2::new(10.0, 10.0), Target::Empty, Modifiers::NONE);
        g.update(Pos2::new(13.0, 12.0));
        assert!(!g.dragging && g.rect().is_none());
        g.update(Pos2::new(40.0, 50.0));
        assert!(g.dragging);
        assert_eq!(g.rect(), Some(Rect::from_min_max(Pos2::new(10.0, 10.0), Pos2::new(40.0, 50.0))));
        assert!(g.holds_view());
        let alt = Gesture::new(Pos2::ZERO, Target::Empty, Modifiers::ALT);
        assert!(!alt.holds_view(), "Alt-drag on empty canvas pans");
        assert!(!Gesture::new(Pos2::ZERO, Target::Node("a".into()), Modifiers::NONE).holds_view());
    }
}
