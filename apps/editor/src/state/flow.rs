//! Flow edits on the canvas: bypassing nodes (Houdini's bypass flag, Nuke's disable), a wire
//! dragged from a pin into empty space, which offers the node types that can take it and wires
//! the one picked (as Houdini, Blender and ComfyUI do), and a node dropped onto a wire, which is
//! spliced into it (as in Nuke and Houdini).

use std::collections::HashSet;

use pyrograph_frontend::core::document::split_endpoint;
use pyrograph_frontend::core::{BuildOptions, DiagnosticKind, Graph, GraphDoc, NodeDesc, PortType, TimeDep};

use super::{Editor, PaletteItem};

/// The pin a wire dropped on empty canvas was dragged from.
#[derive(Clone, Debug, PartialEq)]
pub enum WireEnd {
    /// An output: the new node takes it on one of its inputs.
    Output {
        /// Node id.
        node: String,
        /// Output name.
        port: String,
        /// What the wire carries (a clip after lifting).
        ty: PortType,
    },
    /// An input: one of the new node's outputs feeds it.
    Input {
        /// Node id.
        node: String,
        /// Input name.
        port: String,
        /// What the input takes.
        ty: PortType,
    },
}

/// The port of a node of `desc` that `wire` would connect to: the first input that takes the
/// wire's type (a clip into a per-frame node's input of its frames, as the graph lifts it), or
/// the first output of exactly the input's type.
pub fn wire_port(desc: &NodeDesc, wire: &WireEnd) -> Option<String> {
    match wire {
        WireEnd::Output { ty, .. } => desc
            .inputs
            .iter()
            .find(|p| p.ty == *ty || (ty.clip_element() == Some(&p.ty) && desc.time == TimeDep::PerFrame))
            .map(|p| p.name.clone()),
        WireEnd::Input { ty, .. } => desc.outputs.iter().find(|p| p.ty == *ty).map(|p| p.name.clone()),
    }
}

impl Editor {
    /// Whether node `id` is bypassed.
    pub fn is_bypassed(&self, id: &str) -> bool {
        self.node_doc(id).is_some_and(|n| n.bypass)
    }

    /// Bypasses `ids`, or, when every one of them is bypassed already, turns bypass off for all
    /// of them (the B key, as in Houdini's network editor). One undo step.
    pub fn toggle_bypass(&mut self, ids: &[String]) {
        let on = !ids.iter().all(|id| self.is_bypassed(id));
        self.edit(None, |doc| {
            for id in ids {
                if let Some(n) = doc.node_mut(id) {
                    n.bypass = on;
                }
            }
        });
        self.seal();
        let what = if on { "bypassed" } else { "bypass off:" };
        if !ids.is_empty() {
            self.set_status(format!("{what} {}", ids.join(", ")), false);
        }
    }
}

impl Editor {
    /// Node types matching `query` that can take `wire` (presets are left out: each would be
    /// built to learn its ports, on every keystroke).
    pub fn wire_palette(&self, query: &str, wire: &WireEnd) -> Vec<PaletteItem> {
        self.palette(query)
            .into_iter()
            .filter(|item| item.preset.is_none())
            .filter(|item| self.registry().get(&item.type_name).is_some_and(|n| wire_port(n.desc(), wire).is_some()))
            .collect()
    }

    /// Why the type checker refuses `cand` (a type mismatch, a cycle or a doubled input that the
    /// current document does not already have), or `None` when it takes it.
    pub(super) fn refusal(&self, cand: &GraphDoc) -> Option<String> {
        let before: HashSet<(String, String)> =
            self.validation.diagnostics.iter().map(|d| (d.location.to_string(), d.message.clone())).collect();
        let after = Graph::build(cand, &self.registry, &self.base_dir(), &BuildOptions::default()).err()?.0;
        let refusing = [DiagnosticKind::TypeMismatch, DiagnosticKind::Cycle, DiagnosticKind::DuplicateEdge];
        after
            .into_iter()
            .filter(|d| refusing.contains(&d.kind))
            .find(|d| !before.contains(&(d.location.to_string(), d.message.clone())))
            .map(|d| d.message)
    }

    /// Splices `node` into the wire `from -> to` (both `node.port`): the wire's source into the
    /// node's first input that takes it, and the node's first output the wire's target takes into
    /// the target. With `join`, the splice and the edit before it (the drag that dropped the node
    /// there) are one undo step. Refused, with the reason, when no ports fit or the node is wired.
    pub fn insert_on_wire(&mut self, node: &str, from: &str, to: &str, join: bool) -> Result<(), String> {
        let ((src, _), (dst, _)) = split_endpoint(from).zip(split_endpoint(to)).ok_or("not a wire")?;
        if self.doc.edges.iter().any(|(a, b)| a.starts_with(&format!("{node}.")) || b.starts_with(&format!("{node}."))) {
            return Err(format!("'{node}' is wired already; only a node without wires drops onto a wire"));
        }
        if node == src || node == dst || !self.doc.edges.contains(&(from.to_string(), to.to_string())) {
            return Err(format!("no wire {from} -> {to} to drop '{node}' onto"));
        }
        let desc = self.desc(node).cloned().ok_or_else(|| format!("'{node}' has no known ports"))?;
        // Data inputs (images, clips) before parameters a wire could also feed.
        let data = desc.inputs.iter().filter(|p| !p.ty.is_parameter());
        for input in data.chain(desc.inputs.iter().filter(|p| p.ty.is_parameter())) {
            for output in &desc.outputs {
                let mut cand = self.doc.clone();
                cand.edges.retain(|e| *e != (from.to_string(), to.to_string()));
                cand.edges.push((from.to_string(), format!("{node}.{}", input.name)));
                cand.edges.push((format!("{node}.{}", output.name), to.to_string()));
                if self.refusal(&cand).is_none() {
                    self.edit(None, |d| *d = cand);
                    if join {
                        self.history.join_last_two();
                    }
                    self.seal();
                    self.set_status(format!("inserted {node} into {from} -> {to}"), false);
                    return Ok(());
                }
            }
        }
        let why = format!("'{node}' has no input that takes {from} and output that {to} takes");
        self.set_status(why.clone(), true);
        Err(why)
    }

    /// Adds a node of `type_name` at `pos` wired to `wire`, as one undo step; returns its id.
    pub fn add_wired(&mut self, type_name: &str, pos: (f32, f32), wire: &WireEnd) -> Result<String, String> {
        let desc = self.registry().get(type_name).map(|n| n.desc().clone()).ok_or(format!("unknown node type '{type_name}'"))?;
        let port = wire_port(&desc, wire).ok_or_else(|| format!("'{type_name}' has no port that takes this wire"))?;
        let id = self.add_node(type_name, pos)?;
        let wired = match wire {
            WireEnd::Output { node, port: from, .. } => self.connect(node, from, &id, &port),
            WireEnd::Input { node, port: to, .. } => self.connect(&id, &port, node, to),
        };
        match wired {
            Ok(()) => {
                self.history.join_last_two();
                self.set_status(format!("added {id} ({type_name}), wired"), false);
                self.select(&id);
                Ok(id)
            }
            Err(e) => {
                // Take the unwired node back out; the reason stays in the status bar.
                self.undo();
                self.set_status(e.clone(), true);
                Err(e)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use pyrograph_frontend::core::{GraphDoc, NodeDoc, ParamValue, PortType};

    use crate::Editor;

    #[test]
    fn toggling_bypass_is_one_undo_step_back_to_the_same_document() {
        let mut ed = Editor::with_default_registry();
        ed.auto_cook = false;
        let mut doc = GraphDoc::new();
        doc.add_node("a", NodeDoc::new("math.add").param("b", ParamValue::Float(1.0)));
        doc.add_node("b", NodeDoc::new("math.add"));
        ed.edit(None, |d| *d = doc.clone());
        ed.seal();
        let before = ed.doc().to_ron();
        let both = ["a".to_string(), "b".to_string()];
        ed.toggle_bypass(&both[..1]);
        assert!(ed.is_bypassed("a") && !ed.is_bypassed("b"));
        // Not all bypassed: the toggle turns both on; then both off.
        ed.toggle_bypass(&both);
        assert!(ed.is_bypassed("a") && ed.is_bypassed("b"));
        ed.toggle_bypass(&both);
        assert!(!ed.is_bypassed("a") && !ed.is_bypassed("b"));
        assert!(ed.undo() && ed.undo());
        assert!(ed.is_bypassed("a") && !ed.is_bypassed("b"));
        assert!(ed.undo());
        assert_eq!(ed.doc().to_ron(), before, "undone byte for byte");
    }

    #[test]
    fn a_wire_dropped_in_empty_space_offers_only_nodes_that_take_it_and_wires_the_pick_in_one_step() {
        use super::WireEnd;
        let mut ed = Editor::with_default_registry();
        ed.auto_cook = false;
        let color = ed.add_node("imaging.constant_color", (0.0, 0.0)).unwrap();
        ed.seal();
        let before = ed.doc().to_ron();
        let ty = ed.desc(&color).unwrap().outputs[0].ty.clone();
        let wire = WireEnd::Output { node: color.clone(), port: "image".into(), ty };
        let offered = ed.wire_palette("", &wire);
        let names: Vec<&str> = offered.iter().map(|i| i.type_name.as_str()).collect();
        assert!(names.contains(&"imaging.bloom") && names.contains(&"imaging.to_gray"), "{names:?}");
        assert!(!names.contains(&"math.add") && !names.contains(&"value.float"), "nothing that cannot take an image: {names:?}");
        assert!(offered.iter().all(|i| i.preset.is_none()));
        assert_eq!(ed.wire_palette("bloom", &wire).first().map(|i| i.type_name.as_str()), Some("imaging.bloom"));
        let id = ed.add_wired("imaging.bloom", (200.0, 0.0), &wire).unwrap();
        assert!(ed.doc().edges.contains(&(format!("{color}.image"), format!("{id}.image"))), "{:?}", ed.doc().edges);
        assert_eq!(ed.current(), Some(id.as_str()));
        assert!(ed.undo());
        assert_eq!(ed.doc().to_ron(), before, "one undo step takes node and wire back");

        // From an input: the offered nodes have an output of its type.
        let add = ed.add_node("math.add", (0.0, 200.0)).unwrap();
        let want = WireEnd::Input { node: add.clone(), port: "a".into(), ty: PortType::Float };
        let offered: Vec<String> = ed.wire_palette("", &want).into_iter().map(|i| i.type_name).collect();
        assert!(offered.contains(&"value.float".to_string()) && !offered.contains(&"imaging.bloom".to_string()), "{offered:?}");
        let v = ed.add_wired("value.float", (-200.0, 200.0), &want).unwrap();
        assert!(ed.doc().edges.contains(&(format!("{v}.value"), format!("{add}.a"))));
        // A type that cannot take the wire is refused, and nothing is added.
        let n = ed.doc().nodes.0.len();
        assert!(ed.add_wired("imaging.bloom", (0.0, 0.0), &want).is_err());
        assert_eq!(ed.doc().nodes.0.len(), n);
    }
}
