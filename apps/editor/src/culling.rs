//! What a big graph's canvas holds: egui-snarl lays out and draws every node it holds, every
//! frame (300 nodes cost 9 ms), so above [`CULL_ABOVE`] nodes the canvas holds only those near
//! the view, at most [`MAX_HELD`], the nearest to its centre first, and the minimap shows where
//! the others are as a density of cells instead of one rectangle a node.

use std::collections::{HashMap, HashSet};

use eframe::egui::{Pos2, Rect, vec2};
use pyrograph_frontend::core::GraphDoc;

use crate::layout::auto_layout;

/// Documents with more nodes than this are culled.
pub const CULL_ABOVE: usize = 1500;
/// Most nodes a culled canvas holds at once.
pub const MAX_HELD: usize = 600;
/// Cells across the minimap's density grid.
const CELLS: usize = 96;

/// Where every node of a document is drawn (its own position, else the automatic layout's),
/// computed once per revision.
pub struct Positions {
    revision: Option<u64>,
    /// (node id, position), in document order.
    pub all: Vec<(String, Pos2)>,
    /// The box around every position.
    pub bounds: Rect,
    /// Occupied cells of the density grid, for the minimap (canvas units).
    pub cells: Vec<Rect>,
}

impl Default for Positions {
    fn default() -> Self {
        Positions { revision: None, all: Vec::new(), bounds: Rect::NOTHING, cells: Vec::new() }
    }
}

impl Positions {
    /// Where every node of `doc` (as of `revision`) is drawn.
    pub fn build(doc: &GraphDoc, revision: u64) -> Positions {
        // The layout is only needed for nodes without a position of their own.
        let layout = if doc.nodes.0.iter().any(|(_, nd)| nd.pos.is_none()) { auto_layout(doc) } else { HashMap::new() };
        let all: Vec<(String, Pos2)> = doc
            .nodes
            .0
            .iter()
            .map(|(id, nd)| {
                let (x, y) = nd.pos.or_else(|| layout.get(id).copied()).unwrap_or((0.0, 0.0));
                (id.clone(), Pos2::new(x, y))
            })
            .collect();
        let bounds = all.iter().fold(Rect::NOTHING, |b, (_, p)| b.union(Rect::from_min_size(*p, vec2(200.0, 120.0))));
        let cells = density(&all, bounds);
        Positions { revision: Some(revision), all, bounds, cells }
    }

    /// The positions, declared to be of `revision` (built on a loader thread before the
    /// document was adopted).
    pub fn at(mut self, revision: u64) -> Positions {
        self.revision = Some(revision);
        self
    }

    /// Whether these are the positions of `revision`.
    pub fn is_of(&self, revision: u64) -> bool {
        self.revision == Some(revision)
    }

    /// The position of node `id` (a scan: for a few nodes, such as a selection).
    pub fn of(&self, id: &str) -> Option<Pos2> {
        self.all.iter().find(|(k, _)| k == id).map(|(_, p)| *p)
    }
}

/// The nodes a culled canvas holds for the view `view` (canvas units): those within it and a
/// margin around it, the nearest [`MAX_HELD`] to its centre, plus the selected ones still
/// within the margin. Returns them and the region they were chosen for (the canvas chooses
/// again when the view leaves it).
pub fn held<'a>(positions: &'a Positions, view: Rect, selected: &[String]) -> (Vec<(&'a str, Pos2)>, Rect) {
    let view = if view.is_finite() && view.area() > 0.0 {
        view
    } else {
        // Before the first frame: around the first node.
        let start = positions.all.first().map_or(Pos2::ZERO, |(_, p)| *p);
        Rect::from_min_size(start - vec2(100.0, 100.0), vec2(3200.0, 2000.0))
    };
    let region = view.expand2(view.size() * 0.5);
    let centre = view.center();
    let mut near: Vec<(f32, &str, Pos2)> = positions
        .all
        .iter()
        .filter(|(_, p)| region.intersects(Rect::from_min_size(*p, vec2(200.0, 120.0))))
        .map(|(id, p)| (p.distance_sq(centre), id.as_str(), *p))
        .collect();
    if near.len() > MAX_HELD {
        near.select_nth_unstable_by(MAX_HELD, |a, b| a.0.total_cmp(&b.0));
        near.truncate(MAX_HELD);
    }
    let mut seen: HashSet<&str> = near.iter().map(|(_, id, _)| *id).collect();
    let mut out: Vec<(&str, Pos2)> = near.into_iter().map(|(_, id, p)| (id, p)).collect();
    let wanted: HashSet<&str> = selected.iter().take(MAX_HELD).map(String::as_str).collect();
    if !wanted.is_empty() {
        for (id, p) in &positions.all {
            if wanted.contains(id.as_str()) && region.contains(*p) && seen.insert(id.as_str()) {
                out.push((id.as_str(), *p));
            }
        }
    }
    (out, region)
}

/// The cells of a `CELLS`-wide grid over `bounds` that hold at least one position.
fn density(all: &[(String, Pos2)], bounds: Rect) -> Vec<Rect> {
    if !bounds.is_finite() || all.is_empty() {
        return Vec::new();
    }
    let cell = (bounds.width().max(bounds.height()) / CELLS as f32).max(1.0);
    let mut seen = HashSet::new();
    for (_, p) in all {
        seen.insert((((p.x - bounds.min.x) / cell) as i64, ((p.y - bounds.min.y) / cell) as i64));
    }
    let mut cells: Vec<Rect> = seen
        .into_iter()
        .map(|(i, j)| Rect::from_min_size(bounds.min + vec2(i as f32 * cell, j as f32 * cell), vec2(cell, cell)))
        .collect();
    cells.sort_by(|a, b| a.min.x.total_cmp(&b.min.x).then(a.min.y.total_cmp(&b.min.y)));
    cells
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::layout::generated_graph;

    #[test]
    fn a_culled_view_holds_at_most_max_held_nodes_nearest_its_centre() {
        let doc = generated_graph(20_000);
        let p = Positions::build(&doc, 1);
        assert!(p.is_of(1) && !p.is_of(2));
        assert_eq!(p.all.len(), 20_000);
        // A view over the whole graph: capped, and the nearest to the centre are kept.
        let (held_all, _) = held(&p, p.bounds, &[]);
        assert_eq!(held_all.len(), MAX_HELD);
        let centre = p.bounds.center();
        let far = p.all.iter().map(|(_, q)| q.distance(centre)).fold(0.0, f32::max);
        assert!(held_all.iter().all(|(id, q)| p.of(id) == Some(*q) && q.distance(centre) < far / 2.0));
        // A small view: only the nodes there, and a selected node near it.
        let view = Rect::from_min_size(Pos2::new(0.0, 0.0), vec2(1000.0, 600.0));
        let (few, region) = held(&p, view, &["n100".into(), "n19999".into()]);
        let ids: HashSet<&str> = few.iter().map(|(id, _)| *id).collect();
        assert!(few.len() < 60 && ids.contains("n0") && !ids.contains("n19999"), "{}", few.len());
        assert!(region.contains_rect(view));
        assert!(p.cells.len() > 10 && p.cells.len() <= CELLS * CELLS);
    }
}
