//! The canvas's egui-snarl viewer: node titles and pins (coloured by port type), menus, the
//! selection outline, groups and comments under the nodes, and framing of the view.

use std::collections::{HashMap, HashSet};

use eframe::egui::{self, Color32, Pos2, Rect, Ui, emath::TSTransform};
use egui_snarl::ui::{AnyPins, BackgroundPattern, PinInfo, PinShape, SnarlStyle, SnarlViewer};
use egui_snarl::{InPin, InPinId, NodeId, OutPin, OutPinId, Snarl};
use pyrograph_frontend::core::PortType;

use crate::action::Action;
use crate::annotate::Annotation;
use crate::overlay::{AnnotationRects, paint_annotations};
use crate::palette::{category_color, palette_ui, search_list_ui};
use crate::state::Editor;
use crate::state::flow::WireEnd;

/// Badge and text colour of warnings (amber: the node cooked, but look at this).
const WARNING: Color32 = Color32::from_rgb(255, 190, 70);
/// Header of a bypassed node.
const BYPASSED: Color32 = Color32::from_rgb(110, 92, 30);

/// The smallest zoom (the view can show 10 times more canvas than at 1:1).
pub const MIN_SCALE: f32 = 0.1;
/// The largest zoom.
pub const MAX_SCALE: f32 = 2.0;

/// The outline of selected nodes (Houdini's yellow).
pub const SELECTED: Color32 = Color32::from_rgb(255, 200, 80);

/// A colour per port type, shared by pins and wires.
pub fn type_color(ty: &PortType) -> Color32 {
    match ty {
        PortType::Float => Color32::from_rgb(120, 200, 120),
        PortType::Int => Color32::from_rgb(80, 170, 170),
        PortType::Bool => Color32::from_rgb(220, 110, 110),
        PortType::Color | PortType::Ramp(_) => Color32::from_rgb(235, 200, 80),
        PortType::Vec2 | PortType::Vec3 | PortType::Points => Color32::from_rgb(170, 130, 220),
        PortType::String | PortType::Path | PortType::Enum => Color32::from_rgb(160, 160, 160),
        PortType::Image => Color32::from_rgb(240, 140, 60),
        PortType::Mask => Color32::from_rgb(235, 235, 235),
        PortType::Contours => Color32::from_rgb(80, 210, 240),
        PortType::Custom(info) => Color32::from_rgb(info.color[0], info.color[1], info.color[2]),
        PortType::Clip(inner) => type_color(inner),
    }
}

/// Which description ports a node shows as pins, in pin order.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct NodePins {
    /// Input indices in the node description.
    pub inputs: Vec<usize>,
    /// Output indices in the node description.
    pub outputs: Vec<usize>,
}

/// Where "frame" moves the view.
#[derive(Clone, Copy, Debug)]
pub(crate) enum FrameTarget {
    /// Every node, group and comment.
    All,
    /// A canvas rectangle.
    Rect(Rect),
    /// Centre on a canvas point, keeping the zoom.
    Center(Pos2),
}

fn pin_info(ty: &PortType) -> PinInfo {
    let shape = if ty.clip_element().is_some() { PinShape::Square } else { PinShape::Circle };
    PinInfo::default().with_shape(shape).with_fill(type_color(ty)).with_wire_color(type_color(ty))
}

/// The canvas's answers to egui-snarl: titles, pins, menus, frames, and the view transform.
pub(crate) struct Viewer<'a> {
    pub editor: &'a Editor,
    pub pins: &'a HashMap<String, NodePins>,
    pub actions: &'a mut Vec<Action>,
    pub query: &'a mut String,
    pub pending: &'a mut Option<FrameTarget>,
    pub to_global: &'a mut TSTransform,
    pub node_rects: &'a mut HashMap<String, Rect>,
    /// The height (canvas units) of each drawn pin's row: (node, port, is output) → y.
    pub pin_rows: &'a mut HashMap<(String, String, bool), f32>,
    /// Whether to record pin rows this frame: they are wanted only for dropping a dragged node
    /// onto a wire, so only while a button is down.
    pub record_pins: bool,
    pub rect: Rect,
    /// Nodes drawn as selected.
    pub selected: &'a HashSet<String>,
    /// While a gesture holds the view (a selection rectangle), the transform stays this one.
    pub hold: Option<TSTransform>,
    /// Group frames and comments drawn under the nodes, and where they landed.
    pub annotation: Option<Annotation>,
    pub comment_at: Option<(usize, Pos2)>,
    pub annotation_rects: &'a mut AnnotationRects,
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
            .and_then(|g| g.output_type(id, idx).cloned())
            .unwrap_or_else(|| port.ty.clone());
        Some((id.clone(), port.name.clone(), ty, port.doc.clone()))
    }
}

impl SnarlViewer<String> for Viewer<'_> {
    fn title(&mut self, node: &String) -> String {
        node.clone()
    }

    fn draw_background(
        &mut self,
        background: Option<&BackgroundPattern>,
        viewport: &Rect,
        snarl_style: &SnarlStyle,
        style: &egui::Style,
        painter: &egui::Painter,
        _snarl: &Snarl<String>,
    ) {
        if let Some(bg) = background {
            bg.draw(viewport, snarl_style, style, painter);
        }
        *self.annotation_rects = paint_annotations(painter, self.editor.doc(), self.node_rects, self.annotation, self.comment_at);
    }

    fn header_frame(
        &mut self,
        default: egui::Frame,
        node: NodeId,
        _inputs: &[InPin],
        _outputs: &[OutPin],
        snarl: &Snarl<String>,
    ) -> egui::Frame {
        let id = snarl.get_node(node);
        let cat = id.and_then(|id| self.editor.desc(id)).map(|d| d.category.clone()).unwrap_or_default();
        match id.is_some_and(|id| self.editor.is_bypassed(id)) {
            // Bypassed: Houdini's yellow flag, as a dim amber header whatever the category.
            true => default.fill(BYPASSED),
            false => default.fill(category_color(&cat)),
        }
    }

    fn show_header(&mut self, node: NodeId, _inputs: &[InPin], _outputs: &[OutPin], ui: &mut Ui, snarl: &mut Snarl<String>) {
        let Some(id) = snarl.get_node(node).cloned() else { return };
        let type_name = self.editor.node_doc(&id).map(|n| n.type_name.clone()).unwrap_or_default();
        let problems = self.editor.node_problems(&id);
        let warnings = self.editor.node_warnings(&id);
        ui.horizontal(|ui| {
            if !problems.is_empty() {
                ui.label(egui::RichText::new("⚠").color(Color32::from_rgb(255, 80, 80)).strong())
                    .on_hover_text(problems.join("\n"));
            } else if !warnings.is_empty() {
                ui.label(egui::RichText::new("⚠").color(WARNING).strong()).on_hover_text(warnings.join("\n"));
            }
            ui.label(egui::RichText::new(&id).strong().color(Color32::WHITE)).on_hover_text(
                self.editor.desc(&id).map(|d| format!("{type_name}\n{}", d.doc)).unwrap_or_else(|| type_name.clone()),
            );
            ui.label(egui::RichText::new(type_name.rsplit('.').next().unwrap_or("")).small().color(Color32::from_gray(200)));
            if self.editor.is_bypassed(&id) {
                ui.label(egui::RichText::new("bypassed").small().strong().color(Color32::from_rgb(255, 220, 90)))
                    .on_hover_text("B toggles; the first input of each output's type passes through");
            }
            if self.editor.is_local(&id) {
                ui.label(egui::RichText::new("local").small().strong().color(Color32::from_rgb(120, 200, 255)))
                    .on_hover_text("its graph is a copy kept in this file (double-click to step inside)");
            }
        });
        // Double-clicking an include's header steps inside it (Houdini's dive in). Read from the
        // pointer, so the header's drag still moves the node; the header is laid out in canvas
        // units, the pointer is on screen.
        let header = self.to_global.mul_rect(ui.min_rect().expand(4.0));
        if type_name == pyrograph_frontend::core::builtin::INCLUDE_TYPE
            && ui.input(|i| i.pointer.button_double_clicked(egui::PointerButton::Primary))
            && ui.input(|i| i.pointer.interact_pos()).is_some_and(|p| header.contains(p))
        {
            self.actions.push(Action::StepInto(id));
        }
    }

    fn inputs(&mut self, node: &String) -> usize {
        self.pins.get(node).map_or(0, |p| p.inputs.len())
    }

    fn outputs(&mut self, node: &String) -> usize {
        self.pins.get(node).map_or(0, |p| p.outputs.len())
    }

    #[allow(refining_impl_trait)]
    fn show_input(&mut self, pin: &InPin, ui: &mut Ui, snarl: &mut Snarl<String>) -> PinInfo {
        let Some((id, name, ty, doc)) = self.in_port(snarl, pin.id) else { return PinInfo::default() };
        if self.record_pins {
            self.pin_rows.insert((id, name.clone(), false), ui.max_rect().center().y);
        }
        let text = egui::RichText::new(&name).small();
        let text = if ty.is_parameter() { text.italics() } else { text };
        ui.label(text).on_hover_text(format!("{name}: {ty}\n{doc}"));
        pin_info(&ty)
    }

    #[allow(refining_impl_trait)]
    fn show_output(&mut self, pin: &OutPin, ui: &mut Ui, snarl: &mut Snarl<String>) -> PinInfo {
        let Some((id, name, ty, doc)) = self.out_port(snarl, pin.id) else { return PinInfo::default() };
        if self.record_pins {
            self.pin_rows.insert((id, name.clone(), true), ui.max_rect().center().y);
        }
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

    fn has_dropped_wire_menu(&mut self, src_pins: AnyPins, _snarl: &mut Snarl<String>) -> bool {
        matches!(src_pins, AnyPins::Out([_]) | AnyPins::In([_]))
    }

    fn show_dropped_wire_menu(&mut self, pos: Pos2, ui: &mut Ui, src_pins: AnyPins, snarl: &mut Snarl<String>) {
        let wire = match src_pins {
            AnyPins::Out([pin]) => self.out_port(snarl, *pin).map(|(node, port, ty, _)| WireEnd::Output { node, port, ty }),
            AnyPins::In([pin]) => self.in_port(snarl, *pin).map(|(node, port, ty, _)| WireEnd::Input { node, port, ty }),
            _ => None,
        };
        let Some(wire) = wire else {
            ui.close();
            return;
        };
        let title = match &wire {
            WireEnd::Output { node, port, ty } => format!("Add a node taking {node}.{port} ({ty})"),
            WireEnd::Input { node, port, ty } => format!("Add a node feeding {node}.{port} ({ty})"),
        };
        ui.set_min_width(320.0);
        ui.label(egui::RichText::new(title).strong());
        let editor = self.editor;
        if let Some(item) = search_list_ui(ui, self.query, true, |q| editor.wire_palette(q, &wire)) {
            self.actions.push(Action::AddWired(item.type_name, pos, wire));
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
        let bypass = if self.editor.is_bypassed(&id) { "Turn bypass off (B)" } else { "Bypass (B)" };
        if ui
            .button(bypass)
            .on_hover_text("pass the first input of each output's type through; a writer writes nothing")
            .clicked()
        {
            self.actions.push(Action::Bypass(vec![id.clone()]));
            ui.close();
        }
        let include = self.editor.node_doc(&id).is_some_and(|n| n.type_name == pyrograph_frontend::core::builtin::INCLUDE_TYPE);
        if include && ui.button("Step inside (I)").on_hover_text("show and edit its graph; the breadcrumb leads back").clicked() {
            self.actions.push(Action::StepInto(id.clone()));
            ui.close();
        }
        if include
            && ui.button("Unpack").on_hover_text("replace this include by the nodes of its graph, wired as it was").clicked()
        {
            self.actions.push(Action::Unpack(id.clone()));
            ui.close();
        }
        let selected = self.editor.selection();
        let chosen = if selected.contains(&id) { selected.to_vec() } else { vec![id.clone()] };
        if ui
            .button(format!("Collapse {} into a subgraph (Ctrl+Shift+G)", if chosen.len() > 1 { "selection" } else { "node" }))
            .on_hover_text("move the nodes into a new include kept in this file; wires in and out become its ports")
            .clicked()
        {
            self.actions.push(Action::Collapse(chosen));
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
        !self.editor.node_problems(node).is_empty() || !self.editor.node_warnings(node).is_empty()
    }

    fn show_on_hover_popup(&mut self, node: NodeId, _i: &[InPin], _o: &[OutPin], ui: &mut Ui, snarl: &mut Snarl<String>) {
        if let Some(id) = snarl.get_node(node) {
            for p in self.editor.node_problems(id) {
                ui.colored_label(Color32::from_rgb(255, 120, 120), p);
            }
            for w in self.editor.node_warnings(id) {
                ui.colored_label(WARNING, w);
            }
        }
    }

    fn final_node_rect(&mut self, node: NodeId, rect: Rect, ui: &mut Ui, snarl: &mut Snarl<String>) {
        if let Some(id) = snarl.get_node(node) {
            self.node_rects.insert(id.clone(), rect);
            // The selection outline is painted around the frame, not part of it, so selecting
            // a node does not change its size.
            if self.selected.contains(id) {
                ui.painter().rect_stroke(rect, 6.0, egui::Stroke::new(2.5, SELECTED), egui::StrokeKind::Outside);
            }
        }
    }

    fn current_transform(&mut self, to_global: &mut TSTransform, snarl: &mut Snarl<String>) {
        if let Some(hold) = self.hold {
            *to_global = hold;
        }
        if let Some(FrameTarget::Center(p)) = *self.pending {
            *self.pending = None;
            if self.rect.is_finite() {
                to_global.translation = self.rect.center().to_vec2() - p.to_vec2() * to_global.scaling;
            }
        }
        if let Some(target) = self.pending.take() {
            let bb = match target {
                FrameTarget::Center(_) => Rect::NOTHING,
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
                    bb.union(self.annotation_rects.bounds()).expand(60.0)
                }
            };
            if bb.is_finite() && bb.width() > 0.0 && bb.height() > 0.0 && self.rect.is_finite() {
                let s = (self.rect.width() / bb.width()).min(self.rect.height() / bb.height()).clamp(MIN_SCALE, 1.5);
                *to_global = TSTransform::new(self.rect.center().to_vec2() - bb.center().to_vec2() * s, s);
            }
        }
        *self.to_global = *to_global;
    }
}
