//! Node descriptions (ports, defaults, ranges, docs) and the trait every node type implements.

use std::path::PathBuf;

use crate::ctx::CookCtx;
use crate::error::NodeError;
use crate::value::{PortType, Value};

/// How a node relates to time; decides lifting and caching.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum TimeDep {
    /// Produces values from parameters alone (a loader, a constant).
    Source,
    /// Works on one frame at a time; a `Clip<T>` into a `T` input lifts it over time.
    PerFrame,
    /// Needs whole clips at once (training, transitions).
    WholeClip,
    /// A deterministic simulation stepped frame by frame.
    Simulation,
    /// Writes files; cooked only when asked (render), never served from the cache.
    Sink,
}

impl TimeDep {
    /// Lower-case name for listings.
    pub fn name(self) -> &'static str {
        match self {
            TimeDep::Source => "source",
            TimeDep::PerFrame => "per-frame",
            TimeDep::WholeClip => "whole-clip",
            TimeDep::Simulation => "simulation",
            TimeDep::Sink => "sink",
        }
    }
}

/// Whether a `Path` parameter names something read or something written.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum PathRole {
    /// Read: resolves against the graph file's folder.
    Input,
    /// Written: resolves against the render's output folder (`--out`), else the graph file's folder.
    Output,
}

/// One input or output port.
#[derive(Clone, Debug)]
pub struct PortDesc {
    /// Stable name, used in graph files (`node.port`).
    pub name: String,
    /// The type it carries.
    pub ty: PortType,
    /// The constant used when the port is neither connected nor set; `None` makes it required.
    pub default: Option<Value>,
    /// Inclusive numeric range for `Float`/`Int` parameters.
    pub range: Option<(f64, f64)>,
    /// Allowed names for `Enum` parameters.
    pub options: Vec<String>,
    /// For `Path` parameters, how the path resolves.
    pub path_role: Option<PathRole>,
    /// The node samples this parameter itself, at every step of its simulation (a field of type
    /// `Anim`, declared in the `declare` module). Other parameters are sampled by the evaluator at the frame a
    /// per-frame node cooks, and cannot be animated on a node that cooks once for the whole clip.
    pub sampled_by_node: bool,
    /// One line of help for tooltips and the node reference.
    pub doc: String,
}

impl PortDesc {
    /// A port of type `ty` with no default (a required input, or any output).
    pub fn new(name: &str, ty: PortType, doc: &str) -> Self {
        PortDesc {
            name: name.to_string(),
            ty,
            default: None,
            range: None,
            options: Vec::new(),
            path_role: None,
            sampled_by_node: false,
            doc: doc.to_string(),
        }
    }

    /// A Float parameter with default and inclusive range.
    pub fn float(name: &str, default: f64, range: (f64, f64), doc: &str) -> Self {
        PortDesc { default: Some(Value::Float(default)), range: Some(range), ..Self::new(name, PortType::Float, doc) }
    }

    /// An Int parameter with default and inclusive range.
    pub fn int(name: &str, default: i64, range: (i64, i64), doc: &str) -> Self {
        let range = Some((range.0 as f64, range.1 as f64));
        PortDesc { default: Some(Value::Int(default)), range, ..Self::new(name, PortType::Int, doc) }
    }

    /// A Bool parameter.
    pub fn bool(name: &str, default: bool, doc: &str) -> Self {
        PortDesc { default: Some(Value::Bool(default)), ..Self::new(name, PortType::Bool, doc) }
    }

    /// A Color parameter (linear RGBA).
    pub fn color(name: &str, default: [f32; 4], doc: &str) -> Self {
        PortDesc { default: Some(Value::Color(default)), ..Self::new(name, PortType::Color, doc) }
    }

    /// A Vec3 parameter.
    pub fn vec3(name: &str, default: [f64; 3], doc: &str) -> Self {
        PortDesc { default: Some(Value::Vec3(default)), ..Self::new(name, PortType::Vec3, doc) }
    }

    /// A String parameter.
    pub fn string(name: &str, default: &str, doc: &str) -> Self {
        PortDesc { default: Some(Value::String(default.to_string())), ..Self::new(name, PortType::String, doc) }
    }

    /// An Enum parameter; the first option is the default unless `default` names another.
    pub fn choice(name: &str, options: &[&str], default: &str, doc: &str) -> Self {
        PortDesc {
            default: Some(Value::Enum(default.to_string())),
            options: options.iter().map(|s| s.to_string()).collect(),
            ..Self::new(name, PortType::Enum, doc)
        }
    }

    /// A Path parameter; `default` of `None` makes it required.
    pub fn path(name: &str, role: PathRole, default: Option<&str>, doc: &str) -> Self {
        PortDesc {
            default: default.map(|d| Value::Path(PathBuf::from(d))),
            path_role: Some(role),
            ..Self::new(name, PortType::Path, doc)
        }
    }

    /// Whether the port must be connected or set.
    pub fn is_required(&self) -> bool {
        self.default.is_none()
    }
}

/// The static description of a node type.
#[derive(Clone, Debug)]
pub struct NodeDesc {
    /// Stable type name, `family.name` (`imaging.to_gray`).
    pub type_name: String,
    /// Palette category.
    pub category: String,
    /// What the node does and which paper section it implements (first line is the summary).
    pub doc: String,
    /// Inputs and parameters, in order.
    pub inputs: Vec<PortDesc>,
    /// Outputs, in order.
    pub outputs: Vec<PortDesc>,
    /// Relation to time.
    pub time: TimeDep,
}

impl NodeDesc {
    /// A description without ports.
    pub fn new(type_name: &str, category: &str, time: TimeDep, doc: &str) -> Self {
        NodeDesc {
            type_name: type_name.to_string(),
            category: category.to_string(),
            doc: doc.to_string(),
            inputs: Vec::new(),
            outputs: Vec::new(),
            time,
        }
    }

    /// Adds an input port.
    pub fn input(mut self, port: PortDesc) -> Self {
        self.inputs.push(port);
        self
    }

    /// Adds an output port.
    pub fn output(mut self, name: &str, ty: PortType, doc: &str) -> Self {
        self.outputs.push(PortDesc::new(name, ty, doc));
        self
    }

    /// Index of the input named `name`.
    pub fn input_index(&self, name: &str) -> Option<usize> {
        self.inputs.iter().position(|p| p.name == name)
    }

    /// Index of the output named `name`.
    pub fn output_index(&self, name: &str) -> Option<usize> {
        self.outputs.iter().position(|p| p.name == name)
    }

    /// First line of the doc.
    pub fn summary(&self) -> &str {
        self.doc.lines().next().unwrap_or("")
    }
}

/// A node type: a description plus the function that cooks it. Node types are declared with
/// `node!` and an `impl Cook` beside it (see `params`), which implements this trait.
pub trait Node: Send + Sync {
    /// The static description.
    fn desc(&self) -> &NodeDesc;
    /// Computes the outputs (in `desc().outputs` order) from the inputs.
    fn cook(&self, inputs: &Inputs<'_>, ctx: &CookCtx) -> Result<Vec<Value>, NodeError>;
    /// Extra state the outputs depend on beyond the inputs (an included file's content), mixed
    /// into the cache fingerprint.
    fn fingerprint_salt(&self) -> u64 {
        0
    }
}

/// The input values of one cook, in `desc.inputs` order, with their description. A node reads
/// them through its declared fields (`Declared::read`, made by `node!`): typed, with errors
/// that name the port, so no node reads a port by a string name.
pub struct Inputs<'a> {
    desc: &'a NodeDesc,
    values: &'a [Value],
}

impl<'a> Inputs<'a> {
    /// Pairs values (in `desc.inputs` order) with their description.
    pub fn new(desc: &'a NodeDesc, values: &'a [Value]) -> Self {
        Inputs { desc, values }
    }

    /// Every input value, in `desc().inputs` order: for nodes whose ports are known only at run
    /// time (a Python plugin), which cannot declare typed fields.
    pub fn values(&self) -> &'a [Value] {
        self.values
    }

    /// The description the values belong to.
    pub fn desc(&self) -> &'a NodeDesc {
        self.desc
    }

    /// The value of input `i` (in `desc.inputs` order).
    pub(crate) fn value(&self, i: usize) -> Option<&'a Value> {
        self.values.get(i)
    }

    /// The raw value of port `name` with the port's description (one lookup for both); the
    /// typed field readers of `params` build on it.
    pub(crate) fn get_port(&self, name: &str) -> Result<(&'a Value, &'a PortDesc), NodeError> {
        self.desc
            .input_index(name)
            .and_then(|i| Some((self.values.get(i)?, &self.desc.inputs[i])))
            .ok_or_else(|| NodeError::port(name, "no such input on this node"))
    }
}
