//! Placement helpers: automatic layout for nodes without positions, and relative paths.

use std::collections::HashMap;
use std::path::Path;

use pyrograph_frontend::core::GraphDoc;
use pyrograph_frontend::core::document::split_endpoint;

/// `file` relative to `base` when it lies inside it, else absolute.
pub fn relative_path(file: &Path, base: &Path) -> String {
    let file_abs = std::fs::canonicalize(file).unwrap_or_else(|_| file.to_path_buf());
    let base_abs = std::fs::canonicalize(base).unwrap_or_else(|_| base.to_path_buf());
    match file_abs.strip_prefix(&base_abs) {
        Ok(rel) => rel.display().to_string(),
        Err(_) => file_abs.display().to_string(),
    }
}

/// Positions for nodes that have none: columns by depth along the edges.
pub fn auto_layout(doc: &GraphDoc) -> Layout {
    let mut depth: HashMap<&str, usize> = doc.nodes.0.iter().map(|(id, _)| (id.as_str(), 0)).collect();
    // Longest-path depth by relaxation (bounded, so cycles in a broken file cannot loop forever).
    for _ in 0..doc.nodes.0.len().min(64) {
        let mut changed = false;
        for (a, b) in &doc.edges {
            if let (Some((na, _)), Some((nb, _))) = (split_endpoint(a), split_endpoint(b))
                && let (Some(&da), Some(&db)) = (depth.get(na), depth.get(nb))
                && db < da + 1
            {
                depth.insert(nb, da + 1);
                changed = true;
            }
        }
        if !changed {
            break;
        }
    }
    let mut rows: HashMap<usize, usize> = HashMap::new();
    let mut out = HashMap::new();
    for (id, _) in &doc.nodes.0 {
        let d = depth.get(id.as_str()).copied().unwrap_or(0);
        let r = rows.entry(d).or_insert(0);
        out.insert(id.clone(), (40.0 + d as f32 * 280.0, 40.0 + *r as f32 * 180.0));
        *r += 1;
    }
    out
}

/// Node id → canvas position (x, y).
pub type Layout = HashMap<String, (f32, f32)>;

/// A generated graph of `n` nodes for stress tests and benchmarks of the canvas: chains of
/// `value.float → math.add → math.multiply` laid out on a grid, every node positioned, every
/// chain wired, so a large graph looks like a large hand-made one.
pub fn generated_graph(n: usize) -> GraphDoc {
    let mut doc = GraphDoc::new();
    let kinds = ["value.float", "math.add", "math.multiply"];
    let per_row = 12;
    for i in 0..n {
        let mut nd = pyrograph_frontend::core::NodeDoc::new(kinds[i % 3]);
        nd.pos = Some(((i % per_row) as f32 * 260.0, (i / per_row) as f32 * 170.0));
        doc.add_node(&format!("n{i}"), nd);
        if i % 3 != 0 {
            doc.connect(&format!("n{}.value", i - 1), &format!("n{i}.a"));
        }
    }
    doc
}
