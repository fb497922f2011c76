//! The node canvas: an egui-snarl view kept in sync with the document.
//!
//! The [`Editor`]'s document owns the graph. The snarl is rebuilt incrementally from it whenever
//! the document changes, and every user gesture on the canvas (connect, disconnect, delete, add
//! from the palette, move, select) comes back as an [`Action`] that the app applies through the
//! editor, where the core type checker decides about connections. The selection lives in the
//! editor; the canvas's own gestures ([`crate::gesture`]) change it, not egui-snarl's.

use std::collections::{HashMap, HashSet};
use std::sync::Arc;

use eframe::egui::{self, Color32, Modifiers, Pos2, Rect, Ui, emath::TSTransform};
use egui_snarl::ui::{SnarlStyle, SnarlWidget};
use egui_snarl::{InPinId, NodeId, OutPinId, Snarl};
use pyrograph_frontend::core::GraphDoc;
use pyrograph_frontend::core::document::split_endpoint;

use crate::annotate::Annotation;
use crate::culling::{CULL_ABOVE, Positions, held};
use crate::gesture::{Gesture, Target, after_click, after_rect, on_node_drag};
use crate::overlay::{AnnotationRects, MINIMAP_SIZE, annotation_colors, minimap};
use crate::state::Editor;
use crate::viewer::{FrameTarget, SELECTED, Viewer};

// Part of the canvas's interface, defined below it because its viewer uses them too (the viewer
// emits actions, shows the pins and frames the view within the zoom limits).
use crate::action::Action;
use crate::viewer::{MAX_SCALE, MIN_SCALE, NodePins};

/// The state of the canvas view.
pub struct Canvas {
    snarl: Snarl<String>,
    ids: HashMap<String, NodeId>,
    pins: HashMap<String, NodePins>,
    shown_pos: HashMap<String, Pos2>,
    synced: u64,
    /// Nodes that show every parameter as a pin.
    pub param_pins: HashSet<String>,
    pins_changed: bool,
    pending_transform: Option<FrameTarget>,
    /// Frames left during which "frame all" is re-applied (node sizes settle over the first frames).
    frame_all_frames: u8,
    to_global: TSTransform,
    rect: Rect,
    node_rects: HashMap<String, Rect>,
    pin_rows: HashMap<(String, String, bool), f32>,
    /// The search text of the canvas palette.
    pub palette_query: String,
    gesture: Option<Gesture>,
    annotation_rects: AnnotationRects,
    /// The selected group or comment.
    pub annotation: Option<Annotation>,
    /// Whether the minimap is shown (M toggles it).
    pub show_minimap: bool,
    minimap_rect: Option<Rect>,
    /// Every node's position, for culling and the minimap of a big graph.
    positions: Arc<Positions>,
    /// The region (canvas units) a culled canvas chose its nodes for.
    held_region: Option<Rect>,
    /// When the canvas is culled: how many nodes it holds, of how many.
    pub culled: Option<(usize, usize)>,
}

impl Default for Canvas {
    fn default() -> Self {
        Canvas::new()
    }
}

/// The widget id of the canvas (selection lives in egui memory under it).
pub fn canvas_id() -> egui::Id {
    egui::Id::new("pyrograph-canvas")
}

impl Canvas {
    /// An empty canvas.
    pub fn new() -> Self {
        Canvas {
            snarl: Snarl::new(),
            ids: HashMap::new(),
            pins: HashMap::new(),
            shown_pos: HashMap::new(),
            synced: 0,
            param_pins: HashSet::new(),
            pins_changed: false,
            pending_transform: None,
            frame_all_frames: 0,
            to_global: TSTransform::IDENTITY,
            rect: Rect::NOTHING,
            node_rects: HashMap::new(),
            pin_rows: HashMap::new(),
            palette_query: String::new(),
            gesture: None,
            annotation_rects: AnnotationRects::default(),
            annotation: None,
            show_minimap: true,
            minimap_rect: None,
            positions: Arc::new(Positions::default()),
            held_region: None,
            culled: None,
        }
    }

    /// Where the minimap is on screen, when shown.
    pub fn minimap_rect(&self) -> Option<Rect> {
        self.minimap_rect
    }

    /// Frames the nodes `ids` (every node when none is given), as F does.
    pub fn frame_nodes(&mut self, ids: &[String]) {
        let bb = ids.iter().filter_map(|id| self.node_rects.get(id)).fold(Rect::NOTHING, |a, r| a.union(*r));
        if bb.is_finite() {
            self.pending_transform = Some(FrameTarget::Rect(bb.expand(60.0)));
        } else {
            self.frame_all();
        }
    }

    /// The view's transform from canvas to screen (as of the last frame).
    pub fn transform(&self) -> TSTransform {
        self.to_global
    }

    /// Where node `id` is on screen (as of the last frame).
    pub fn node_screen_rect(&self, id: &str) -> Option<Rect> {
        self.node_rects.get(id).map(|r| self.to_global.mul_rect(*r))
    }

    /// Where group `i`'s title bar and comment `i` are on screen (as of the last frame).
    pub fn annotation_screen_rect(&self, which: Annotation) -> Option<Rect> {
        let r = match which {
            Annotation::Group(i) => self.annotation_rects.group_bar(i)?,
            Annotation::Comment(i) => *self.annotation_rects.comments.get(i)?,
        };
        Some(self.to_global.mul_rect(r))
    }

    /// Frames every node on the next frame.
    pub fn frame_all(&mut self) {
        self.pending_transform = Some(FrameTarget::All);
        self.frame_all_frames = 3;
    }

    /// Whether screen position `p` lies on the canvas.
    pub fn rect_contains(&self, p: Pos2) -> bool {
        self.rect.contains(p)
    }

    /// The visible part of the canvas, in canvas units.
    pub fn visible(&self) -> Rect {
        self.to_global.inverse().mul_rect(self.rect)
    }

    /// Centres the view on node `id`.
    pub fn focus_node(&mut self, id: &str) {
        if let Some(r) = self.node_rects.get(id) {
            self.pending_transform = Some(FrameTarget::Rect(r.expand(250.0)));
        }
    }

    /// The canvas position under a screen position.
    pub fn to_graph(&self, screen: Pos2) -> Pos2 {
        self.to_global.inverse() * screen
    }

    /// The canvas position at the centre of the view.
    pub fn view_center(&self) -> Pos2 {
        if self.rect.is_finite() { self.to_graph(self.rect.center()) } else { Pos2::new(100.0, 100.0) }
    }

    /// The pins shown for node `id`.
    pub fn pins(&self, id: &str) -> Option<&NodePins> {
        self.pins.get(id)
    }

    /// Number of wires drawn (tests compare it with the document's edges).
    pub fn wire_count(&self) -> usize {
        self.snarl.wires().count()
    }

    /// The wire (a document edge, `node.port` to `node.port`) that passes through node `id`'s
    /// frame, the one nearest its centre; wires of `id` itself are not counted. Wires are traced
    /// as egui-snarl draws them: a cubic from the output pin to the input pin with horizontal
    /// tangents.
    pub fn wire_through(&self, doc: &GraphDoc, id: &str) -> Option<(String, String)> {
        let rect = *self.node_rects.get(id)?;
        let mut best: Option<(f32, (String, String))> = None;
        for (from, to) in &doc.edges {
            let (Some((a_node, a_port)), Some((b_node, b_port))) = (split_endpoint(from), split_endpoint(to)) else { continue };
            if a_node == id || b_node == id {
                continue;
            }
            let ends = (self.node_rects.get(a_node), self.node_rects.get(b_node));
            let rows = (
                self.pin_rows.get(&(a_node.to_string(), a_port.to_string(), true)),
                self.pin_rows.get(&(b_node.to_string(), b_port.to_string(), false)),
            );
            let ((Some(ra), Some(rb)), (Some(&ya), Some(&yb))) = (ends, rows) else { continue };
            let nearest = wire_points(egui::pos2(ra.right(), ya), egui::pos2(rb.left(), yb))
                .filter(|p| rect.contains(*p))
                .map(|p| p.distance(rect.center()))
                .fold(f32::INFINITY, f32::min);
            if nearest.is_finite() && best.as_ref().is_none_or(|(d, _)| nearest < *d) {
                best = Some((nearest, (from.clone(), to.clone())));
            }
        }
        best.map(|(_, wire)| wire)
    }

    /// Node ids shown on the canvas.
    pub fn node_ids(&self) -> Vec<String> {
        self.snarl.nodes().cloned().collect()
    }

    /// Brings the snarl in line with the document (for a big one, the part near the view).
    pub fn sync(&mut self, editor: &Editor) {
        let doc = editor.doc();
        let culling = doc.nodes.0.len() > CULL_ABOVE;
        let view = self.visible();
        let left_region = culling && !self.held_region.is_some_and(|r| !view.is_finite() || r.contains_rect(view));
        if self.synced == editor.revision() && !self.pins_changed && !left_region {
            return;
        }
        self.synced = editor.revision();
        self.pins_changed = false;
        if !self.positions.is_of(editor.revision()) {
            self.positions = editor.prepared_positions().unwrap_or_else(|| Arc::new(Positions::build(doc, editor.revision())));
        }
        let positions = self.positions.clone();
        let (kept, region) = if culling {
            let (kept, region) = held(&positions, view, editor.selection());
            (kept, Some(region))
        } else {
            (positions.all.iter().map(|(id, p)| (id.as_str(), *p)).collect(), None)
        };
        self.held_region = region;
        self.culled = culling.then_some((kept.len(), doc.nodes.0.len()));
        let present: HashSet<&str> = kept.iter().map(|(id, _)| *id).collect();
        let stale: Vec<String> = self.ids.keys().filter(|k| !present.contains(k.as_str())).cloned().collect();
        for id in stale {
            if let Some(nid) = self.ids.remove(&id)
                && self.snarl.get_node(nid).is_some()
            {
                self.snarl.remove_node(nid);
            }
            self.shown_pos.remove(&id);
            self.pins.remove(&id);
            self.node_rects.remove(&id);
            self.pin_rows.retain(|(n, _, _), _| *n != id);
        }
        self.param_pins.retain(|id| editor.node_doc(id).is_some());
        for &(id, pos) in &kept {
            self.hold_node(editor, id, pos);
        }
        let want = if culling { self.wires_between(editor, &kept) } else { self.wires(editor) };
        let have: Vec<(OutPinId, InPinId)> = self.snarl.wires().collect();
        for w in &have {
            if !want.contains(w) {
                self.snarl.disconnect(w.0, w.1);
            }
        }
        for w in want {
            self.snarl.connect(w.0, w.1);
        }
    }

    /// Puts node `id` in the snarl at `pos` (or moves it there) with the pins it shows.
    fn hold_node(&mut self, editor: &Editor, id: &str, pos: Pos2) {
        match self.ids.get(id) {
            Some(&nid) => {
                if self.shown_pos.get(id) != Some(&pos)
                    && let Some(info) = self.snarl.get_node_info_mut(nid)
                {
                    info.pos = pos;
                }
            }
            None => {
                let nid = self.snarl.insert_node(pos, id.to_string());
                self.ids.insert(id.to_string(), nid);
            }
        }
        self.shown_pos.insert(id.to_string(), pos);
        // Pins: data inputs always, parameters when connected or asked for.
        let pins = match editor.desc(id) {
            Some(desc) => NodePins {
                inputs: desc
                    .inputs
                    .iter()
                    .enumerate()
                    .filter(|(_, p)| {
                        !p.ty.is_parameter() || self.param_pins.contains(id) || editor.incoming(id, &p.name).is_some()
                    })
                    .map(|(i, _)| i)
                    .collect(),
                outputs: (0..desc.outputs.len()).collect(),
            },
            None => NodePins::default(),
        };
        self.pins.insert(id.to_string(), pins);
    }

    /// The wire of edge `a` → `b`, when both ends are held and show the pins.
    fn wire(&self, editor: &Editor, a: &str, b: &str) -> Option<(OutPinId, InPinId)> {
        let ((na, pa), (nb, pb)) = (split_endpoint(a)?, split_endpoint(b)?);
        let (ia, ib) = (*self.ids.get(na)?, *self.ids.get(nb)?);
        let (oa, ob) = (editor.desc(na)?.output_index(pa)?, editor.desc(nb)?.input_index(pb)?);
        let out = self.pins.get(na)?.outputs.iter().position(|&i| i == oa)?;
        let inp = self.pins.get(nb)?.inputs.iter().position(|&i| i == ob)?;
        Some((OutPinId { node: ia, output: out }, InPinId { node: ib, input: inp }))
    }

    /// Every edge's wire.
    fn wires(&self, editor: &Editor) -> HashSet<(OutPinId, InPinId)> {
        editor.doc().edges.iter().filter_map(|(a, b)| self.wire(editor, a, b)).collect()
    }

    /// The wires between held nodes, found from their inputs (a culled canvas must not walk
    /// every edge of a big graph each time the view moves).
    fn wires_between(&self, editor: &Editor, kept: &[(&str, Pos2)]) -> HashSet<(OutPinId, InPinId)> {
        let mut out = HashSet::new();
        for (id, _) in kept {
            let Some(desc) = editor.desc(id) else { continue };
            for port in &desc.inputs {
                if let Some(src) = editor.incoming(id, &port.name)
                    && let Some(w) = self.wire(editor, src, &format!("{id}.{}", port.name))
                {
                    out.insert(w);
                }
            }
        }
        out
    }

    /// Shows the canvas; returns the gestures to apply.
    pub fn show(&mut self, ui: &mut Ui, editor: &Editor) -> Vec<Action> {
        self.sync(editor);
        self.rect = ui.available_rect_before_wrap();
        if self.frame_all_frames > 0 {
            self.frame_all_frames -= 1;
            self.pending_transform = Some(FrameTarget::All);
        }
        // A culled canvas holds only some nodes: "all" is every node's position.
        if self.culled.is_some() && matches!(self.pending_transform, Some(FrameTarget::All)) {
            self.pending_transform = Some(FrameTarget::Rect(self.positions.bounds.expand(60.0)));
        }
        let ctx = ui.ctx().clone();
        let mut actions = Vec::new();
        self.begin_gesture(&ctx, editor);
        let hold = self.gesture.as_ref().is_some_and(Gesture::holds_view).then_some(self.to_global);
        let comment_at = self.dragged_comment();
        let before: Vec<(NodeId, Pos2)> = self.snarl.nodes_pos_ids().map(|(id, pos, _)| (id, pos)).collect();
        let selected: HashSet<String> = editor.selection().iter().cloned().collect();
        let mut viewer = Viewer {
            editor,
            pins: &self.pins,
            actions: &mut actions,
            query: &mut self.palette_query,
            pending: &mut self.pending_transform,
            to_global: &mut self.to_global,
            node_rects: &mut self.node_rects,
            pin_rows: &mut self.pin_rows,
            record_pins: ctx.input(|i| i.pointer.any_down()),
            rect: self.rect,
            selected: &selected,
            hold,
            annotation: self.annotation,
            comment_at,
            annotation_rects: &mut self.annotation_rects,
        };
        let style = SnarlStyle {
            collapsible: Some(true),
            centering: Some(true),
            min_scale: Some(MIN_SCALE),
            max_scale: Some(MAX_SCALE),
            // The canvas draws its own selection; egui-snarl's (Shift-based) stays empty.
            select_fill: Some(Color32::TRANSPARENT),
            select_stoke: Some(egui::Stroke::NONE),
            ..SnarlStyle::new()
        };
        // egui-snarl reads Shift and Ctrl for its own selection, which the canvas replaces: it
        // sees the frame without modifiers (scroll zoom is computed before, so it still works).
        let mods = ctx.input_mut(|i| std::mem::take(&mut i.modifiers));
        SnarlWidget::new().id(canvas_id()).style(style).show(&mut self.snarl, &mut viewer, ui);
        ctx.input_mut(|i| i.modifiers = mods);
        self.follow_node_drag(&before, editor, &mut actions);
        self.end_gesture(&ctx, editor, &mut actions);
        self.show_minimap_ui(&ctx, &selected, editor.doc());
        if let Some((held, total)) = self.culled {
            let at = self.rect.left_top() + egui::vec2(12.0, 10.0);
            let text = format!("showing the {held} nodes nearest the view of {total}: pan or zoom to see others");
            ui.painter().text(at, egui::Align2::LEFT_TOP, text, egui::FontId::proportional(13.0), Color32::from_gray(200));
        }
        actions
    }

    /// Starts a gesture on a primary press that lands on the canvas (not on a window, menu or
    /// the minimap above it).
    fn begin_gesture(&mut self, ctx: &egui::Context, editor: &Editor) {
        // Where the button went down, not where the pointer is now: a real mouse can deliver a
        // press with the first moves of a drag, or with its release, in one frame.
        let press = ctx.input(|i| {
            i.events.iter().find_map(|e| match e {
                egui::Event::PointerButton { pos, button: egui::PointerButton::Primary, pressed: true, modifiers } => {
                    Some((*pos, *modifiers | i.modifiers))
                }
                _ => None,
            })
        });
        let Some((pos, mods)) = press else { return };
        if !self.rect.contains(pos) {
            return;
        }
        // Windows, menus and the minimap sit above the canvas (tooltips never take clicks).
        if ctx.layer_id_at(pos).is_some_and(|l| !matches!(l.order, egui::Order::Background | egui::Order::Tooltip)) {
            return;
        }
        let target = self.hit(editor, pos);
        self.gesture = Some(Gesture::new(pos, target, mods));
    }

    /// What a press at screen position `pos` lands on: a node (pins stick out of its frame, so
    /// the frame counts a little wider), a comment, a group's title bar, or empty canvas.
    fn hit(&self, editor: &Editor, pos: Pos2) -> Target {
        let p = self.to_graph(pos);
        // Later nodes in the document are drawn later, so they win where nodes overlap.
        for (id, _) in editor.doc().nodes.0.iter().rev() {
            if self.node_rects.get(id).is_some_and(|r| r.expand2(egui::vec2(12.0, 2.0)).contains(p)) {
                return Target::Node(id.clone());
            }
        }
        match self.annotation_rects.hit(p) {
            Some(Annotation::Comment(i)) => Target::Comment(i),
            Some(Annotation::Group(i)) => Target::GroupBar(i),
            None => Target::Empty,
        }
    }

    /// The comment being dragged and where it is now (canvas units).
    fn dragged_comment(&self) -> Option<(usize, Pos2)> {
        let g = self.gesture.as_ref()?;
        let Target::Comment(i) = g.target else { return None };
        let start = self.annotation_rects.comments.get(i)?.min;
        g.dragging.then(|| (i, start + (g.current - g.origin) / self.to_global.scaling))
    }

    /// egui-snarl moves the one node being dragged; the rest of the selection follows it, and
    /// dragging an unselected node selects it first.
    fn follow_node_drag(&mut self, before: &[(NodeId, Pos2)], editor: &Editor, actions: &mut Vec<Action>) {
        let moved = before.iter().find_map(|&(nid, p)| {
            let info = self.snarl.get_node_info(nid)?;
            (info.pos != p).then(|| (info.value.clone(), info.pos - p))
        });
        let Some((id, delta)) = moved else { return };
        let mods = self.gesture.as_ref().map_or(Modifiers::NONE, |g| g.mods);
        let selection = match self.gesture.as_mut() {
            Some(g) if !g.selected_on_drag => {
                g.selected_on_drag = true;
                let sel = on_node_drag(editor.selection(), &id, mods);
                if sel != editor.selection() {
                    actions.push(Action::Select(sel.clone()));
                }
                sel
            }
            _ => editor.selection().to_vec(),
        };
        for other in selection.iter().filter(|s| **s != id) {
            if let Some(&nid) = self.ids.get(other)
                && let Some(info) = self.snarl.get_node_info_mut(nid)
            {
                info.pos += delta;
            }
        }
    }

    /// Follows the pointer and, on release, turns the gesture into a selection (or a group or
    /// comment move).
    fn end_gesture(&mut self, ctx: &egui::Context, editor: &Editor, actions: &mut Vec<Action>) {
        let Some(g) = self.gesture.as_mut() else { return };
        let (pos, down) = ctx.input(|i| (i.pointer.interact_pos(), i.pointer.primary_down()));
        if let Some(p) = pos {
            g.update(p);
        }
        let g = g.clone();
        if let (Target::GroupBar(i), true) = (&g.target, g.dragging) {
            // Moving a group moves its nodes (one undo step with the rest of the drag).
            let delta = (g.current - g.last) / self.to_global.scaling;
            for id in editor.doc().groups.get(*i).map(|gr| gr.nodes.clone()).unwrap_or_default() {
                if let Some(&nid) = self.ids.get(&id)
                    && let Some(info) = self.snarl.get_node_info_mut(nid)
                {
                    info.pos += delta;
                }
            }
        }
        if let Some(r) = g.rect() {
            let painter = ctx.layer_painter(egui::LayerId::new(egui::Order::Foreground, canvas_id().with("rect")));
            let painter = painter.with_clip_rect(self.rect);
            painter.rect_filled(r, 2.0, SELECTED.gamma_multiply(0.12));
            painter.rect_stroke(r, 2.0, egui::Stroke::new(1.0, SELECTED), egui::StrokeKind::Inside);
        }
        if down {
            if g.dragging {
                ctx.request_repaint();
            }
            return;
        }
        let comment_at = self.dragged_comment();
        self.gesture = None;
        let current = editor.selection();
        match (&g.target, g.dragging) {
            (Target::Node(id), false) => {
                actions.push(Action::Select(after_click(current, Some(id), g.mods)));
                actions.push(Action::SelectAnnotation(None));
            }
            (Target::Empty, false) => {
                actions.push(Action::Select(after_click(current, None, g.mods)));
                actions.push(Action::SelectAnnotation(None));
            }
            (Target::Empty, true) if !g.mods.alt => {
                let r = self.to_global.inverse().mul_rect(Rect::from_two_pos(g.origin, g.current));
                let hits: Vec<String> = editor
                    .doc()
                    .nodes
                    .0
                    .iter()
                    .filter(|(id, _)| self.node_rects.get(id).is_some_and(|n| n.intersects(r)))
                    .map(|(id, _)| id.clone())
                    .collect();
                actions.push(Action::Select(after_rect(current, &hits, g.mods)));
            }
            (Target::GroupBar(i), _) => actions.push(Action::SelectAnnotation(Some(Annotation::Group(*i)))),
            (Target::Comment(i), dragged) => {
                actions.push(Action::SelectAnnotation(Some(Annotation::Comment(*i))));
                if dragged && let Some((_, p)) = comment_at {
                    actions.push(Action::MoveComment(*i, p));
                }
            }
            _ => {}
        }
    }

    fn show_minimap_ui(&mut self, ctx: &egui::Context, selected: &HashSet<String>, doc: &GraphDoc) {
        self.minimap_rect = None;
        if !self.show_minimap || !self.rect.is_finite() || self.rect.width() < 2.0 * MINIMAP_SIZE.x {
            return;
        }
        let nodes: Vec<(Rect, bool)> = if self.culled.is_some() {
            self.positions.cells.iter().map(|r| (*r, false)).collect()
        } else {
            self.node_rects.iter().map(|(id, r)| (*r, selected.contains(id))).collect()
        };
        let at = Rect::from_min_size(self.rect.max - MINIMAP_SIZE - egui::vec2(12.0, 12.0), MINIMAP_SIZE);
        self.minimap_rect = Some(at);
        let (group_colors, comment_colors) = annotation_colors(doc);
        let rects = &self.annotation_rects;
        let boxes: Vec<(Rect, Color32)> = (rects.groups.iter().zip(group_colors))
            .filter_map(|(r, c)| r.map(|r| (r, c)))
            .chain(rects.comments.iter().copied().zip(comment_colors))
            .collect();
        if let Some(p) = minimap(ctx, at, &nodes, &boxes, self.visible()) {
            self.pending_transform = Some(FrameTarget::Center(p));
            ctx.request_repaint();
        }
    }

    /// Node positions the user changed by dragging: `(id, new position)`. Call when no drag is
    /// in progress, so a whole drag becomes one edit.
    pub fn moved_nodes(&mut self) -> Vec<(String, Pos2)> {
        let mut out = Vec::new();
        for (id, &nid) in &self.ids {
            if let Some(info) = self.snarl.get_node_info(nid)
                && self.shown_pos.get(id) != Some(&info.pos)
            {
                out.push((id.clone(), info.pos));
                self.shown_pos.insert(id.clone(), info.pos);
            }
        }
        out
    }

    /// Toggles the parameter pins of node `id`.
    pub fn toggle_param_pins(&mut self, id: &str) {
        if !self.param_pins.remove(id) {
            self.param_pins.insert(id.to_string());
        }
        self.pins_changed = true;
    }
}

/// Points along a wire from `a` to `b` as egui-snarl draws it (a cubic with horizontal tangents),
/// 33 samples.
fn wire_points(a: Pos2, b: Pos2) -> impl Iterator<Item = Pos2> {
    let k = ((b.x - a.x).abs() * 0.5).max(30.0);
    let (c1, c2) = (a + egui::vec2(k, 0.0), b - egui::vec2(k, 0.0));
    (0..=32).map(move |i| {
        let t = i as f32 / 32.0;
        let u = 1.0 - t;
        let v = a.to_vec2() * (u * u * u)
            + c1.to_vec2() * (3.0 * u * u * t)
            + c2.to_vec2() * (3.0 * u * t * t)
            + b.to_vec2() * (t * t * t);
        v.to_pos2()
    })
}
