//! What `pyrograph check` and Python's `Graph.check()` report: load-time diagnostics, then
//! the source nodes cooked so a missing or corrupt input file shows up without rendering, and
//! (for `check`) warnings that can be known without cooking the rest.

use std::path::PathBuf;

use crate::core::graph::InputSource;
use crate::core::{CookCtx, Diagnostic, Diagnostics, Evaluator, Graph, Location, NodeError, TimeDep};

/// One problem found in a graph, located as precisely as it is known.
#[derive(Clone, Debug, PartialEq)]
pub struct Problem {
    /// The graph file, when the graph came from one.
    pub file: Option<PathBuf>,
    /// The node at fault, if the problem is tied to one.
    pub node: Option<String>,
    /// The port or parameter at fault, if the problem is tied to one.
    pub port: Option<String>,
    /// Where, as text (`node 'blur', port 'sigma'`, `line 3, column 7`).
    pub location: String,
    /// The kind (`Syntax`, `UnknownType`, `TypeMismatch`, … or `Cook` for a source that failed).
    pub kind: String,
    /// What is wrong.
    pub message: String,
}

impl Problem {
    /// A load-time diagnostic as a problem.
    pub fn from_diagnostic(d: &Diagnostic) -> Problem {
        let (node, port) = match &d.location {
            Location::Node(n) => (Some(n.clone()), None),
            Location::Port { node, port } => (Some(node.clone()), Some(port.clone())),
            _ => (None, None),
        };
        Problem {
            file: d.file.clone(),
            node,
            port,
            location: d.location.to_string(),
            kind: format!("{:?}", d.kind),
            message: d.message.clone(),
        }
    }

    /// A cook failure of node `node` as a problem.
    pub fn from_cook(file: Option<PathBuf>, node: &str, e: &NodeError) -> Problem {
        let port = error_port(e).map(str::to_string);
        let location = match &port {
            Some(p) => format!("node '{node}', port '{p}'"),
            None => format!("node '{node}'"),
        };
        Problem { file, node: Some(node.to_string()), port, location, kind: "Cook".into(), message: explain(node, e) }
    }
}

impl std::fmt::Display for Problem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if let Some(file) = &self.file {
            write!(f, "{}: ", file.display())?;
        }
        if self.kind == "Cook" { f.write_str(&self.message) } else { write!(f, "{}: {}", self.location, self.message) }
    }
}

/// The port a cook error is about, looking through the frame and node wrappers.
pub fn error_port(e: &NodeError) -> Option<&str> {
    match e {
        NodeError::Port { port, .. } => Some(port),
        NodeError::Frame { source, .. } | NodeError::InNode { source, .. } => error_port(source),
        _ => None,
    }
}

/// A cook error as one sentence that names its node (the evaluator's wrapper already does).
pub fn explain(node: &str, e: &NodeError) -> String {
    match e {
        NodeError::InNode { .. } => e.to_string(),
        other => format!("node '{node}': {other}"),
    }
}

/// Load-time diagnostics as problems.
pub fn diagnostics(d: &Diagnostics) -> Vec<Problem> {
    d.0.iter().map(Problem::from_diagnostic).collect()
}

/// Cooks the source nodes (loaders), which open and probe their files, and reports those that
/// failed.
pub fn probe_sources(graph: &Graph) -> Vec<Problem> {
    probe_with(graph, &CookCtx::new())
}

/// What `check` finds in a graph that built: its sources' failures (errors) and what can be
/// warned about without cooking the rest (warnings, kind `Warning`): the sources' own warnings,
/// and nodes wired so that an assumption of theirs cannot hold.
pub fn check_graph(graph: &Graph) -> (Vec<Problem>, Vec<Problem>) {
    let ctx = CookCtx::new();
    let errors = probe_with(graph, &ctx);
    let mut warnings: Vec<Problem> =
        ctx.warnings().into_iter().map(|w| warning(graph, w.node.as_deref().unwrap_or("?"), w.message)).collect();
    warnings.extend(unframed_fits(graph));
    (errors, warnings)
}

fn warning(graph: &Graph, node: &str, message: String) -> Problem {
    Problem {
        file: graph.file.clone(),
        node: Some(node.to_string()),
        port: None,
        location: format!("node '{node}'"),
        kind: "Warning".into(),
        message,
    }
}

/// `flame_model.fit` nodes fed straight from a loader: they fit the whole frame, while the model
/// (Learning Flames §3) describes one whole flame framed in the picture — the mistake behind
/// "orange smears filling the top of the frame" on a new plate.
fn unframed_fits(graph: &Graph) -> Vec<Problem> {
    let mut out = Vec::new();
    for &i in graph.topo_order() {
        let n = graph.node(i);
        let desc = n.node.desc();
        if desc.type_name != "flame_model.fit" {
            continue;
        }
        let Some(clip) = desc.inputs.iter().position(|p| p.name == "clip") else { continue };
        let Some(InputSource::Edge { from, .. }) = n.inputs.get(clip) else { continue };
        let up = graph.node(*from);
        if up.node.desc().time == TimeDep::Source {
            out.push(warning(
                graph,
                &n.id,
                format!(
                    "fits the whole frame of '{}' ({}): the flame model needs one whole flame framed in the picture; put \
                     imaging.auto_crop (its mask from imaging.hsv_auto_mask) before it, as graphs/learning-flames-candle.ron \
                     does, unless the footage is framed already",
                    up.id,
                    up.node.desc().type_name
                ),
            ));
        }
    }
    out
}

fn probe_with(graph: &Graph, ctx: &CookCtx) -> Vec<Problem> {
    let sources: Vec<String> = graph
        .topo_order()
        .iter()
        .map(|i| graph.node(*i))
        .filter(|n| n.node.desc().time == TimeDep::Source)
        .map(|n| n.id.to_string())
        .collect();
    let refs: Vec<&str> = sources.iter().map(String::as_str).collect();
    match Evaluator::new().cook(graph, &refs, ctx) {
        Ok(res) => res.root_errors().into_iter().map(|(n, e)| Problem::from_cook(graph.file.clone(), n, e)).collect(),
        Err(e) => vec![Problem {
            file: graph.file.clone(),
            node: None,
            port: None,
            location: "file".into(),
            kind: "Cook".into(),
            message: e.to_string(),
        }],
    }
}

/// Every problem of a graph that may not have built: its diagnostics, or its sources' failures.
pub fn problems(built: Result<&Graph, &Diagnostics>) -> Vec<Problem> {
    match built {
        Ok(g) => probe_sources(g),
        Err(d) => diagnostics(d),
    }
}

/// [`problems`] and the warnings of a graph that built (none for one that did not).
pub fn problems_and_warnings(built: Result<&Graph, &Diagnostics>) -> (Vec<Problem>, Vec<Problem>) {
    match built {
        Ok(g) => check_graph(g),
        Err(d) => (diagnostics(d), Vec::new()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ports_are_found_through_wrappers() {
        let inner = NodeError::port("sigma", "must be above 0");
        let e = NodeError::InNode {
            node: "blur".into(),
            type_name: "imaging.blur".into(),
            source: Box::new(NodeError::Frame { frame: 3, source: Box::new(inner) }),
        };
        assert_eq!(error_port(&e), Some("sigma"));
        let p = Problem::from_cook(None, "blur", &e);
        assert_eq!((p.node.as_deref(), p.port.as_deref()), (Some("blur"), Some("sigma")));
        assert_eq!(p.location, "node 'blur', port 'sigma'");
        assert!(p.message.starts_with("node 'blur' (imaging.blur): frame 3: port 'sigma'"), "{}", p.message);
        assert_eq!(error_port(&NodeError::msg("no port")), None);
    }
}
