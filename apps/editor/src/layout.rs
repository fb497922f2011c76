//! Placement helpers: automatic layout for nodes without positions, and relative paths.

use std::collections::HashMap;
use std::path::Path;

use pyrograph_frontend::core::GraphDoc;
use pyrograph_frontend::core::document::split_endpoint;

/// `file` relative to `base`: below it when it lies inside, else climbing with `..` out of
/// `base` as far as the folder both are in, when that folder is a project's (two or more levels
/// below the root: `/home/me/fire/shots` and `/home/me/fire/presets/torch.ron` give
/// `../presets/torch.ron`), so a graph and its presets can move together, to a farm's share
/// too. Files that share only a top-level folder with `base` (`/tmp`, `/mnt`, `/home`) or
/// nothing, or are on another Windows drive, stay absolute.
pub fn relative_path(file: &Path, base: &Path) -> String {
    use std::path::Component;
    let file_abs = std::fs::canonicalize(file).unwrap_or_else(|_| file.to_path_buf());
    let base_abs = std::fs::canonicalize(base).unwrap_or_else(|_| base.to_path_buf());
    if let Ok(rel) = file_abs.strip_prefix(&base_abs) {
        return rel.display().to_string();
    }
    let (f, b): (Vec<Component>, Vec<Component>) = (file_abs.components().collect(), base_abs.components().collect());
    let common = f.iter().zip(&b).take_while(|(x, y)| x == y).count();
    let named = f[..common].iter().filter(|c| matches!(c, Component::Normal(_))).count();
    // `..` only climbs real folders: not out of a path that still holds `.` or `..` parts.
    let plain = b[common..].iter().all(|c| matches!(c, Component::Normal(_)));
    if named < 2 || !plain || !file_abs.is_absolute() {
        return file_abs.display().to_string();
    }
    let mut rel = std::path::PathBuf::new();
    for _ in common..b.len() {
        rel.push("..");
    }
    rel.extend(&f[common..]);
    rel.display().to_string()
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

#[cfg(test)]
mod tests {
    use std::path::Path;

    use super::relative_path;

    #[test]
    fn paths_climb_out_of_the_graphs_folder_within_a_project_and_stay_absolute_across_roots() {
        let rel = |f: &str, b: &str| relative_path(Path::new(f), Path::new(b));
        assert_eq!(rel("/nowhere/me/fire/shots/a/torch.ron", "/nowhere/me/fire/shots"), "a/torch.ron");
        assert_eq!(rel("/nowhere/me/fire/presets/torch.ron", "/nowhere/me/fire/shots"), "../presets/torch.ron");
        assert_eq!(rel("/nowhere/me/lib/torch.ron", "/nowhere/me/fire/shots/s1"), "../../../lib/torch.ron");
        assert_eq!(rel("/nowhere/other/torch.ron", "/nowhere/me/fire"), "/nowhere/other/torch.ron", "only `/nowhere` shared");
        assert_eq!(rel("/opt/presets/torch.ron", "/nowhere/me/fire"), "/opt/presets/torch.ron");
        // A real project on disk: symlinks resolved, `..` between its folders.
        let dir = tempfile::tempdir().unwrap();
        let root = std::fs::canonicalize(dir.path()).unwrap();
        std::fs::create_dir_all(root.join("proj/shots")).unwrap();
        std::fs::create_dir_all(root.join("proj/presets")).unwrap();
        std::fs::write(root.join("proj/presets/p.ron"), "()").unwrap();
        let got = relative_path(&root.join("proj/presets/p.ron"), &root.join("proj/shots"));
        assert_eq!(got, "../presets/p.ron");
        assert!(root.join("proj/shots").join(&got).exists());
    }
}
