//! Input paths of a graph moved between folders: which parameters are paths read relative to the
//! graph file, which stored paths stay as they are (`${VAR}`, absolute), and rewriting the rest
//! against another folder. The clipboard (copy and paste between graphs), stepping into a preset
//! and unpacking a subgraph all move nodes between folders; this module sits below all three.

use std::path::Path;

use pyrograph_frontend::core::builtin::{INCLUDE_PATH, INCLUDE_TYPE};
use pyrograph_frontend::core::{GraphDoc, ParamValue, PathRole, Registry};

use crate::layout::relative_path;

/// The names of the parameters of `type_name` that are paths read relative to the graph file.
pub(crate) fn input_path_params(registry: &Registry, type_name: &str) -> Vec<String> {
    if type_name == INCLUDE_TYPE {
        return vec![INCLUDE_PATH.to_string()];
    }
    registry
        .get(type_name)
        .map(|n| n.desc().inputs.iter().filter(|p| p.path_role == Some(PathRole::Input)).map(|p| p.name.clone()).collect())
        .unwrap_or_default()
}

/// Whether a stored path is left alone when moved between folders (`${VAR}` or absolute).
pub(crate) fn is_anchored(path: &str) -> bool {
    path.contains("${") || Path::new(path).is_absolute()
}

/// Rewrites the relative input paths of `doc` and of its local subgraphs, written against
/// folder `from`, to resolve the same against folder `to` (absolute when they leave it).
pub(crate) fn rebase_paths(doc: &mut GraphDoc, registry: &Registry, from: &Path, to: &Path) {
    map_paths(doc, registry, |p| {
        if !is_anchored(p) {
            *p = relative_path(&from.join(&*p), to);
        }
    });
}

/// Calls `f` on every input path parameter of `doc` and of its local subgraphs. Walked with a
/// stack: local subgraphs nest as deep as the file's includes.
pub(crate) fn map_paths(doc: &mut GraphDoc, registry: &Registry, mut f: impl FnMut(&mut String)) {
    let mut stack = vec![doc];
    while let Some(g) = stack.pop() {
        for (_, nd) in &mut g.nodes.0 {
            for name in input_path_params(registry, &nd.type_name) {
                if let Some(ParamValue::String(p)) = nd.params.get_mut(&name) {
                    f(p);
                }
            }
        }
        stack.extend(g.subgraphs.values_mut());
    }
}
