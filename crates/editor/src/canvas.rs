//! The node canvas: an egui-snarl view kept in sync with the document.
//!
//! The [`Editor`]'s document owns the graph. The snarl is rebuilt incrementally from it whenever
//! the document changes, and every user gesture on the canvas (connect, disconnect, delete, add
//! from the palette, move) comes back as an [`Action`] that the app applies through the editor,
//! where the core type checker decides about connections.

use std::collections::{HashMap, HashSet};

use eframe::egui::{self, Color32, Pos2, Rect, Ui, emath::TSTransform};
use egui_snarl::ui::{PinInfo, PinShape, SnarlStyle, SnarlViewer, SnarlWidget};
use egui_snarl::{InPin, InPinId, NodeId, OutPin, OutPinId, Snarl};
use pyrograph::core::PortType;
use pyrograph::core::document::split_endpoint;

use crate::state::{Editor, PaletteItem, auto_layout};

/// A gesture on the canvas, applied after the frame's canvas pass.
#[derive(Clone, Debug, PartialEq)]
pub enum Action {
    /// Connect `(node, output)` to `(node, input)` (port names).
    Connect {
        /// Source node and output.
        from: (String, String),
        /// Target node and input.
        to: (String, String),
    },
    /// Remove the edge between two ports (`node.port`).
    Disconnect {
        /// `node.output`.
        from: String,
        /// `node.input`.
        to: String,
    },
    /// Remove every edge into an input.
    DropInput(String, String),
    /// Remove every edge out of an output.
    DropOutput(String, String),
    /// Add a palette item at a canvas position.
    Add(PaletteItem, Pos2),
    /// Delete nodes.
    Remove(Vec<String>),
    /// Duplicate nodes.
    Duplicate(Vec<String>),
    /// Toggle showing every parameter as a pin.
    ToggleParamPins(String),
    /// Preview a node.
    Preview(String),
}

/// Which description ports a node shows as pins, in pin order.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct NodePins {
    /// Input indices in the node description.
    pub inputs: Vec<usize>,
    /// Output indices in the node description.
    pub outputs: Vec<usize>,
}

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
    last_selection: Vec<String>,
    /// The search text of the canvas palette.
    pub palette_query: String,
}

#[derive(Clone, Copy, Debug)]
enum FrameTarget {
    All,
    Rect(Rect),
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
            last_selection: Vec::new(),
            palette_query: String::new(),
        }
    }

    /// Frames every node on the next frame.
    pub fn frame_all(&mut self) {
        self.pending_transform = Some(FrameTarget::All);
        self.frame_all_frames = 3;
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

    /// Node ids shown on the canvas.
    pub fn node_ids(&self) -> Vec<String> {
        self.snarl.nodes().cloned().collect()
    }

    /// Brings the snarl in line with the document.
    pub fn sync(&mut self, editor: &Editor) {
        if self.synced == editor.revision() && !self.pins_changed {
            return;
        }
        self.synced = editor.revision();
        self.pins_changed = false;
        let doc = editor.doc();
        let layout = auto_layout(doc);
        let present: HashSet<&str> = doc.nodes.0.iter().map(|(id, _)| id.as_str()).collect();
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
        }
        self.param_pins.retain(|id| present.contains(id.as_str()));
        for (id, nd) in &doc.nodes.0 {
            let (x, y) = nd.pos.or_else(|| layout.get(id).copied()).unwrap_or((0.0, 0.0));
            let pos = Pos2::new(x, y);
            match self.ids.get(id) {
                Some(&nid) => {
                    if self.shown_pos.get(id) != Some(&pos)
                        && let Some(info) = self.snarl.get_node_info_mut(nid)
                    {
                        info.pos = pos;
                    }
                }
                None => {
                    let nid = self.snarl.insert_node(pos, id.clone());
                    self.ids.insert(id.clone(), nid);
                }
            }
            self.shown_pos.insert(id.clone(), pos);
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
            self.pins.insert(id.clone(), pins);
        }
        // Wires.
        let mut want: HashSet<(OutPinId, InPinId)> = HashSet::new();
        for (a, b) in &doc.edges {
            let (Some((na, pa)), Some((nb, pb))) = (split_endpoint(a), split_endpoint(b)) else { continue };
            let (Some(&ia), Some(&ib)) = (self.ids.get(na), self.ids.get(nb)) else { continue };
            let (Some(da), Some(db)) = (editor.desc(na), editor.desc(nb)) else { continue };
            let (Some(oa), Some(ob)) = (da.output_index(pa), db.input_index(pb)) else { continue };
            let (Some(pa), Some(pb)) = (self.pins.get(na), self.pins.get(nb)) else { continue };
            let (Some(out), Some(inp)) = (pa.outputs.iter().position(|&i| i == oa), pb.inputs.iter().position(|&i| i == ob))
            else {
                continue;
            };
            want.insert((OutPinId { node: ia, output: out }, InPinId { node: ib, input: inp }));
        }
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

    /// Shows the canvas; returns the gestures to apply.
    pub fn show(&mut self, ui: &mut Ui, editor: &Editor) -> Vec<Action> {
        self.sync(editor);
        self.rect = ui.available_rect_before_wrap();
        if self.frame_all_frames > 0 {
            self.frame_all_frames -= 1;
            self.pending_transform = Some(FrameTarget::All);
        }
        let mut actions = Vec::new();
        let mut viewer = Viewer {
            editor,
            pins: &self.pins,
            actions: &mut actions,
            query: &mut self.palette_query,
            pending: &mut self.pending_transform,
            to_global: &mut self.to_global,
            node_rects: &mut self.node_rects,
            rect: self.rect,
        };
        let style = SnarlStyle {
            collapsible: Some(true),
            centering: Some(true),
            min_scale: Some(0.1),
            max_scale: Some(2.0),
            ..SnarlStyle::new()
        };
        SnarlWidget::new().id(canvas_id()).style(style).show(&mut self.snarl, &mut viewer, ui);
        actions
    }

    /// Node ids selected on the canvas, when the selection changed since the last call.
    pub fn selection_change(&mut self, ctx: &egui::Context) -> Option<Vec<String>> {
        let sel: Vec<String> = egui_snarl::ui::get_selected_nodes(canvas_id(), ctx)
            .into_iter()
            .filter_map(|n| self.snarl.get_node(n).cloned())
            .collect();
        if sel != self.last_selection {
            self.last_selection = sel.clone();
            Some(sel)
        } else {
            None
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

/// A colour per port type, shared by pins and wires.
pub fn type_color(ty: &PortType) -> Color32 {
    match ty {
        PortType::Float => Color32::from_rgb(120, 200, 120),
        PortType::Int => Color32::from_rgb(80, 170, 170),
        PortType::Bool => Color32::from_rgb(220, 110, 110),
        PortType::Color => Color32::from_rgb(235, 200, 80),
        PortType::Vec2 | PortType::Vec3 => Color32::from_rgb(170, 130, 220),
        PortType::String | PortType::Path | PortType::Enum => Color32::from_rgb(160, 160, 160),
        PortType::Image => Color32::from_rgb(240, 140, 60),
        PortType::Mask => Color32::from_rgb(235, 235, 235),
        PortType::Contours => Color32::from_rgb(80, 210, 240),
        PortType::WindField => Color32::from_rgb(120, 160, 250),
        PortType::Particles => Color32::from_rgb(245, 110, 180),
        PortType::Basis | PortType::Weights | PortType::FrameList => Color32::from_rgb(200, 180, 140),
        PortType::ParamSeries | PortType::ArModel | PortType::FlameModel => Color32::from_rgb(230, 150, 200),
        PortType::Mesh | PortType::SpreadState => Color32::from_rgb(150, 200, 150),
        PortType::Clip(inner) => type_color(inner),
        #[allow(unreachable_patterns)]
        _ => Color32::GRAY,
    }
}

/// A header colour per palette category.
pub fn category_color(category: &str) -> Color32 {
    let h = category.bytes().fold(2166136261u32, |h, b| (h ^ b as u32).wrapping_mul(16777619));
    let hue = (h % 360) as f32 / 360.0;
    let c = egui::ecolor::Hsva::new(hue, 0.55, 0.38, 1.0);
    Color32::from(c)
}

fn pin_info(ty: &PortType) -> PinInfo {
    let shape = if ty.clip_element().is_some() { PinShape::Square } else { PinShape::Circle };
    PinInfo::default().with_shape(shape).with_fill(type_color(ty)).with_wire_color(type_color(ty))
}

struct Viewer<'a> {
    editor: &'a Editor,
    pins: &'a HashMap<String, NodePins>,
    actions: &'a mut Vec<Action>,
    query: &'a mut String,
    pending: &'a mut Option<FrameTarget>,
    to_global: &'a mut TSTransform,
    node_rects: &'a mut HashMap<String, Rect>,
    rect: Rect,
}

impl Viewer<'_> {
    fn in_port(&self, snarl: &Snarl<String>, pin: InPinId) -> Option<(String, String, PortType, String)> {
        let id = snarl.get_node(pin.node)?;
        let desc = self.editor.desc(id)?;
        let idx = *self.pins.get(id)?.inputs.get(pin.input)?;
        let port = desc.inputs.get(idx)?;
        Some((id.clone(), port.name.clone(), port.ty.clone(), port.doc.clone()))
    }

    fn out_port(&self, snarl: &Snarl<String>, pin: OutPinId) -> Option<(String, String, PortType, String)> {
        let id = snarl.get_node(pin.node)?;
        let desc = self.editor.desc(id)?;
        let idx = *self.pins.get(id)?.outputs.get(pin.output)?;
        let port = desc.outputs.get(idx)?;
        // After lifting, an output may be a clip: show the type the graph really carries.
        let ty = self
            .editor
            .validation()
            .graph
            .as_ref()
            .and_then(|g| g.index(id).and_then(|i| g.node(i).out_types.get(idx).cloned()))
            .unwrap_or_else(|| port.ty.clone());
        Some((id.clone(), port.name.clone(), ty, port.doc.clone()))
    }
}

/// The node palette: a search field and the matching node types and presets. Returns the item
/// the user picked (click, or Enter for the first match).
pub fn palette_ui(ui: &mut Ui, editor: &Editor, query: &mut String, focus: bool) -> Option<PaletteItem> {
    let resp =
        ui.add(egui::TextEdit::singleline(query).hint_text("search nodes (name, category, doc)…").id_salt("palette-search"));
    if focus {
        resp.request_focus();
    }
    let items = editor.palette(query);
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

impl SnarlViewer<String> for Viewer<'_> {
    fn title(&mut self, node: &String) -> String {
        node.clone()
    }

    fn header_frame(
        &mut self,
        default: egui::Frame,
        node: NodeId,
        _inputs: &[InPin],
        _outputs: &[OutPin],
        snarl: &Snarl<String>,
    ) -> egui::Frame {
        let cat = snarl.get_node(node).and_then(|id| self.editor.desc(id)).map(|d| d.category.clone()).unwrap_or_default();
        default.fill(category_color(&cat))
    }

    fn show_header(&mut self, node: NodeId, _inputs: &[InPin], _outputs: &[OutPin], ui: &mut Ui, snarl: &mut Snarl<String>) {
        let Some(id) = snarl.get_node(node).cloned() else { return };
        let type_name = self.editor.doc().node(&id).map(|n| n.type_name.clone()).unwrap_or_default();
        let problems = self.editor.node_problems(&id);
        ui.horizontal(|ui| {
            if !problems.is_empty() {
                ui.label(egui::RichText::new("⚠").color(Color32::from_rgb(255, 80, 80)).strong())
                    .on_hover_text(problems.join("\n"));
            }
            ui.label(egui::RichText::new(&id).strong().color(Color32::WHITE)).on_hover_text(
                self.editor.desc(&id).map(|d| format!("{type_name}\n{}", d.doc)).unwrap_or_else(|| type_name.clone()),
            );
            ui.label(egui::RichText::new(type_name.rsplit('.').next().unwrap_or("")).small().color(Color32::from_gray(200)));
        });
    }

    fn inputs(&mut self, node: &String) -> usize {
        self.pins.get(node).map_or(0, |p| p.inputs.len())
    }

    fn outputs(&mut self, node: &String) -> usize {
        self.pins.get(node).map_or(0, |p| p.outputs.len())
    }

    #[allow(refining_impl_trait)]
    fn show_input(&mut self, pin: &InPin, ui: &mut Ui, snarl: &mut Snarl<String>) -> PinInfo {
        let Some((_, name, ty, doc)) = self.in_port(snarl, pin.id) else { return PinInfo::default() };
        let text = egui::RichText::new(&name).small();
        let text = if ty.is_parameter() { text.italics() } else { text };
        ui.label(text).on_hover_text(format!("{name}: {ty}\n{doc}"));
        pin_info(&ty)
    }

    #[allow(refining_impl_trait)]
    fn show_output(&mut self, pin: &OutPin, ui: &mut Ui, snarl: &mut Snarl<String>) -> PinInfo {
        let Some((_, name, ty, doc)) = self.out_port(snarl, pin.id) else { return PinInfo::default() };
        ui.label(egui::RichText::new(&name).small()).on_hover_text(format!("{name}: {ty}\n{doc}"));
        pin_info(&ty)
    }

    fn connect(&mut self, from: &OutPin, to: &InPin, snarl: &mut Snarl<String>) {
        if let (Some(a), Some(b)) = (self.out_port(snarl, from.id), self.in_port(snarl, to.id)) {
            self.actions.push(Action::Connect { from: (a.0, a.1), to: (b.0, b.1) });
        }
    }

    fn disconnect(&mut self, from: &OutPin, to: &InPin, snarl: &mut Snarl<String>) {
        if let (Some(a), Some(b)) = (self.out_port(snarl, from.id), self.in_port(snarl, to.id)) {
            self.actions.push(Action::Disconnect { from: format!("{}.{}", a.0, a.1), to: format!("{}.{}", b.0, b.1) });
        }
    }

    fn drop_outputs(&mut self, pin: &OutPin, snarl: &mut Snarl<String>) {
        if let Some(a) = self.out_port(snarl, pin.id) {
            self.actions.push(Action::DropOutput(a.0, a.1));
        }
    }

    fn drop_inputs(&mut self, pin: &InPin, snarl: &mut Snarl<String>) {
        if let Some(b) = self.in_port(snarl, pin.id) {
            self.actions.push(Action::DropInput(b.0, b.1));
        }
    }

    fn has_graph_menu(&mut self, _pos: Pos2, _snarl: &mut Snarl<String>) -> bool {
        true
    }

    fn show_graph_menu(&mut self, pos: Pos2, ui: &mut Ui, _snarl: &mut Snarl<String>) {
        ui.set_min_width(320.0);
        ui.label(egui::RichText::new("Add node").strong());
        if let Some(item) = palette_ui(ui, self.editor, self.query, true) {
            self.actions.push(Action::Add(item, pos));
            self.query.clear();
            ui.close();
        }
    }

    fn has_node_menu(&mut self, _node: &String) -> bool {
        true
    }

    fn show_node_menu(&mut self, node: NodeId, _inputs: &[InPin], _outputs: &[OutPin], ui: &mut Ui, snarl: &mut Snarl<String>) {
        let Some(id) = snarl.get_node(node).cloned() else { return };
        ui.label(egui::RichText::new(&id).strong());
        if ui.button("Preview").clicked() {
            self.actions.push(Action::Preview(id.clone()));
            ui.close();
        }
        if ui.button("Duplicate").clicked() {
            self.actions.push(Action::Duplicate(vec![id.clone()]));
            ui.close();
        }
        if ui.button("Show/hide parameter pins").clicked() {
            self.actions.push(Action::ToggleParamPins(id.clone()));
            ui.close();
        }
        if ui.button("Delete").clicked() {
            self.actions.push(Action::Remove(vec![id]));
            ui.close();
        }
    }

    fn has_on_hover_popup(&mut self, node: &String) -> bool {
        !self.editor.node_problems(node).is_empty()
    }

    fn show_on_hover_popup(&mut self, node: NodeId, _i: &[InPin], _o: &[OutPin], ui: &mut Ui, snarl: &mut Snarl<String>) {
        if let Some(id) = snarl.get_node(node) {
            for p in self.editor.node_problems(id) {
                ui.colored_label(Color32::from_rgb(255, 120, 120), p);
            }
        }
    }

    fn final_node_rect(&mut self, node: NodeId, rect: Rect, _ui: &mut Ui, snarl: &mut Snarl<String>) {
        if let Some(id) = snarl.get_node(node) {
            self.node_rects.insert(id.clone(), rect);
        }
    }

    fn current_transform(&mut self, to_global: &mut TSTransform, snarl: &mut Snarl<String>) {
        if let Some(target) = self.pending.take() {
            let bb = match target {
                FrameTarget::Rect(r) => r,
                FrameTarget::All => {
                    let mut bb = Rect::NOTHING;
                    for (nid, info) in snarl.nodes_ids_data() {
                        let _ = nid;
                        let r = self
                            .node_rects
                            .get(&info.value)
                            .copied()
                            .unwrap_or_else(|| Rect::from_min_size(info.pos, egui::vec2(200.0, 120.0)));
                        bb = bb.union(r);
                    }
                    bb.expand(60.0)
                }
            };
            if bb.is_finite() && bb.width() > 0.0 && bb.height() > 0.0 && self.rect.is_finite() {
                let s = (self.rect.width() / bb.width()).min(self.rect.height() / bb.height()).clamp(0.1, 1.5);
                *to_global = TSTransform::new(self.rect.center().to_vec2() - bb.center().to_vec2() * s, s);
            }
        }
        *self.to_global = *to_global;
    }
}
