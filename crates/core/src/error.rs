//! Errors raised while cooking a node and problems found while loading a graph.

use std::fmt;
use std::path::PathBuf;

/// Why a node could not produce its outputs.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum NodeError {
    /// A problem with one input port or parameter.
    #[error("port '{port}': {message}")]
    Port {
        /// The port's name.
        port: String,
        /// What is wrong with it.
        message: String,
    },
    /// A problem that is not tied to one port.
    #[error("{0}")]
    Message(String),
    /// A failure while computing one frame of a clip.
    #[error("frame {frame}: {source}")]
    Frame {
        /// Frame index within the clip.
        frame: usize,
        /// The underlying error.
        source: Box<NodeError>,
    },
    /// The cook was cancelled.
    #[error("cancelled")]
    Cancelled,
    /// An input could not be cooked because the node that feeds it failed.
    #[error("not cooked: upstream node '{0}' failed")]
    Upstream(String),
    /// An error raised inside a named node (added by the evaluator).
    #[error("node '{node}' ({type_name}): {source}")]
    InNode {
        /// The node's id in the graph.
        node: String,
        /// The node's type name.
        type_name: String,
        /// The underlying error.
        source: Box<NodeError>,
    },
}

impl NodeError {
    /// An error about `port`.
    pub fn port(port: impl Into<String>, message: impl Into<String>) -> Self {
        NodeError::Port { port: port.into(), message: message.into() }
    }

    /// An error not tied to one port.
    pub fn msg(message: impl Into<String>) -> Self {
        NodeError::Message(message.into())
    }

    /// Whether this error (or the one it wraps) is a cancellation.
    pub fn is_cancelled(&self) -> bool {
        match self {
            NodeError::Cancelled => true,
            NodeError::Frame { source, .. } | NodeError::InNode { source, .. } => source.is_cancelled(),
            _ => false,
        }
    }
}

/// Names the port an algorithm's message concerns, in a cook:
/// `finite3(self.center).at_port(port!(Roots, center))?`. Algorithms say what is wrong with a
/// value (they know values, not ports); the node that called them knows which port it came from.
/// Implemented for plain messages only, never for a [`NodeError`]: a cancelled cook must stay
/// [`NodeError::Cancelled`], not become a message on a port. An algorithm with an error type of
/// its own maps it with an `impl From<ThatError> for NodeError` that names a port per variant.
pub trait AtPort<T> {
    /// The message as a [`NodeError::Port`] on `port`.
    fn at_port(self, port: &str) -> Result<T, NodeError>;
}

impl<T> AtPort<T> for Result<T, String> {
    fn at_port(self, port: &str) -> Result<T, NodeError> {
        self.map_err(|e| NodeError::port(port, e))
    }
}

impl<T> AtPort<T> for Result<T, &str> {
    fn at_port(self, port: &str) -> Result<T, NodeError> {
        self.map_err(|e| NodeError::port(port, e))
    }
}

/// Where in a graph file a problem was found.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Location {
    /// The file as a whole.
    File,
    /// A text position (1-based line and column), for syntax errors.
    Text {
        /// 1-based line.
        line: usize,
        /// 1-based column.
        column: usize,
    },
    /// A node.
    Node(String),
    /// A port or parameter of a node.
    Port {
        /// The node's id.
        node: String,
        /// The port's name.
        port: String,
    },
    /// An edge, by its position in the `edges` list and its text.
    Edge {
        /// 0-based index in the `edges` list.
        index: usize,
        /// `"from.port -> to.port"`.
        text: String,
    },
    /// A group (frame) of the canvas, by its position in the `groups` list and its title.
    Group {
        /// 0-based index in the `groups` list.
        index: usize,
        /// The group's title.
        title: String,
    },
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Location::File => write!(f, "file"),
            Location::Text { line, column } => write!(f, "line {line}, column {column}"),
            Location::Node(n) => write!(f, "node '{n}'"),
            Location::Port { node, port } => write!(f, "node '{node}', port '{port}'"),
            Location::Edge { index, text } => write!(f, "edge #{index} ({text})"),
            Location::Group { index, title } => write!(f, "group #{index} ({title:?})"),
        }
    }
}

/// The kind of a load-time problem, for tools that sort or filter them.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum DiagnosticKind {
    /// The file could not be read.
    Io,
    /// The text is not valid RON for a graph document.
    Syntax,
    /// The document's version is unknown.
    Version,
    /// No node type of that name is registered.
    UnknownNodeType,
    /// The node type has no port of that name.
    UnknownPort,
    /// Two ids name the same node.
    DuplicateNode,
    /// An edge names a node that does not exist.
    MissingNode,
    /// An edge endpoint is not of the form `node.port`.
    MalformedEdge,
    /// An input has two incoming edges.
    DuplicateEdge,
    /// An edge connects ports of incompatible types.
    TypeMismatch,
    /// The edges form a cycle.
    Cycle,
    /// A required input is neither connected nor set.
    MissingInput,
    /// A parameter value has the wrong kind (a string where a number is needed, …).
    WrongKind,
    /// A parameter value lies outside the port's range or options.
    OutOfRange,
    /// `${NAME}` names an unset environment variable.
    UnsetVariable,
    /// A sub-graph include failed (missing file, include cycle, bad interface).
    Include,
    /// A writer path that leaves the output folder (`--out`, else the graph's folder).
    OutsideOutput,
    /// A file the graph reads that lies outside the folders reads are confined to (`--read-root`).
    OutsideReadRoots,
    /// A node id that cannot be used (empty, or holding the include separator `/`).
    BadId,
    /// An animated parameter that is malformed (keys out of order, an expression that does not
    /// parse) or set where nothing samples it over time.
    Animation,
    /// A bypassed node with an output that none of its inputs can stand in for.
    Bypass,
}

/// One problem found while loading or validating a graph, with its location.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Diagnostic {
    /// The graph file, when the graph came from one.
    pub file: Option<PathBuf>,
    /// Where in the document.
    pub location: Location,
    /// What kind of problem.
    pub kind: DiagnosticKind,
    /// A sentence saying what is wrong and, when possible, how to fix it.
    pub message: String,
}

impl Diagnostic {
    /// A new diagnostic without a file (the loader fills it in).
    pub fn new(kind: DiagnosticKind, location: Location, message: impl Into<String>) -> Self {
        Diagnostic { file: None, location, kind, message: message.into() }
    }
}

impl fmt::Display for Diagnostic {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if let Some(file) = &self.file {
            write!(f, "{}: ", file.display())?;
        }
        write!(f, "{}: {}", self.location, self.message)
    }
}

/// Every problem found in a graph, reported together.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Diagnostics(pub Vec<Diagnostic>);

impl fmt::Display for Diagnostics {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, d) in self.0.iter().enumerate() {
            if i > 0 {
                writeln!(f)?;
            }
            write!(f, "error: {d}")?;
        }
        Ok(())
    }
}

impl std::error::Error for Diagnostics {}

impl Diagnostics {
    /// A single diagnostic.
    pub fn one(d: Diagnostic) -> Self {
        Diagnostics(vec![d])
    }

    /// Sets the file on every diagnostic that has none.
    pub fn in_file(mut self, file: &std::path::Path) -> Self {
        for d in &mut self.0 {
            d.file.get_or_insert_with(|| file.to_path_buf());
        }
        self
    }
}

/// A value as an error quotes it: whole when short, else its start and its length (a value
/// pasted by mistake, or a hostile one, can be megabytes).
pub fn shortened(text: &str) -> String {
    const SHOWN: usize = 80;
    match text.char_indices().nth(SHOWN) {
        None => text.to_string(),
        Some((cut, _)) => format!("{}… ({} characters)", &text[..cut], text.chars().count()),
    }
}
