//! What a gesture on the canvas asks of the app: the canvas and its viewer collect [`Action`]s
//! during the frame's canvas pass, and the app applies them through the editor afterwards.

use eframe::egui::Pos2;

use crate::annotate::Annotation;
use crate::state::PaletteItem;
use crate::state::flow::WireEnd;

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
    /// Add a node of a type at a canvas position, wired to the pin a wire was dragged from.
    AddWired(String, Pos2, WireEnd),
    /// Delete nodes.
    Remove(Vec<String>),
    /// Duplicate nodes.
    Duplicate(Vec<String>),
    /// Bypass nodes, or turn their bypass off when all of them are bypassed.
    Bypass(Vec<String>),
    /// Replace an include by the nodes of its graph.
    Unpack(String),
    /// Show the graph of an include in place of this level's.
    StepInto(String),
    /// Go up to this many levels inside (0: the top level).
    StepTo(usize),
    /// Move nodes into a new local subgraph.
    Collapse(Vec<String>),
    /// Toggle showing every parameter as a pin.
    ToggleParamPins(String),
    /// Preview a node.
    Preview(String),
    /// Replace the node selection (the last id is the node the inspector shows).
    Select(Vec<String>),
    /// Select a group or a comment (or neither).
    SelectAnnotation(Option<Annotation>),
    /// A comment was dragged to a canvas position.
    MoveComment(usize, Pos2),
}
