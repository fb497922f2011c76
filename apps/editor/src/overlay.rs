//! What the canvas draws besides nodes and wires: group frames and sticky comments under the
//! nodes, and the minimap over the canvas corner.

use std::collections::HashMap;

use eframe::egui::{self, Color32, FontId, Painter, Pos2, Rect, Stroke, Vec2};
use pyrograph_frontend::core::GraphDoc;

use crate::annotate::{Annotation, COMMENT_COLOR, GROUP_COLOR, hex_rgb};

/// Height of a group's title bar (canvas units).
pub const GROUP_BAR: f32 = 26.0;
/// Space between a group's frame and its nodes.
const GROUP_PAD: f32 = 16.0;
/// Width at which comment text wraps.
const COMMENT_WRAP: f32 = 240.0;
/// The minimap's size on screen.
pub const MINIMAP_SIZE: Vec2 = Vec2::new(220.0, 150.0);

fn color_of(hex: Option<&str>, fallback: &str) -> Color32 {
    let [r, g, b] = hex.and_then(hex_rgb).or_else(|| hex_rgb(fallback)).unwrap_or([128, 128, 128]);
    Color32::from_rgb(r, g, b)
}

/// Where groups and comments are, in canvas units (for hit tests and "frame all").
#[derive(Clone, Debug, Default)]
pub struct AnnotationRects {
    /// Per group: its whole frame (bar included), or `None` when it has no node on the canvas.
    pub groups: Vec<Option<Rect>>,
    /// Per comment: its note.
    pub comments: Vec<Rect>,
}

impl AnnotationRects {
    /// The title bar of group `i`.
    pub fn group_bar(&self, i: usize) -> Option<Rect> {
        let r = (*self.groups.get(i)?)?;
        Some(Rect::from_min_size(r.min, egui::vec2(r.width(), GROUP_BAR)))
    }

    /// The topmost comment or group bar under `p` (canvas units).
    pub fn hit(&self, p: Pos2) -> Option<Annotation> {
        if let Some(i) = self.comments.iter().rposition(|r| r.contains(p)) {
            return Some(Annotation::Comment(i));
        }
        (0..self.groups.len()).rev().find(|&i| self.group_bar(i).is_some_and(|r| r.contains(p))).map(Annotation::Group)
    }

    /// Everything the annotations cover.
    pub fn bounds(&self) -> Rect {
        self.groups.iter().flatten().chain(&self.comments).fold(Rect::NOTHING, |a, r| a.union(*r))
    }
}

/// Draws groups and comments (canvas units, under the nodes); `comment_at` overrides the
/// position of a comment being dragged.
pub fn paint_annotations(
    painter: &Painter,
    doc: &GraphDoc,
    node_rects: &HashMap<String, Rect>,
    selected: Option<Annotation>,
    comment_at: Option<(usize, Pos2)>,
) -> AnnotationRects {
    let mut out = AnnotationRects::default();
    for (i, g) in doc.groups.iter().enumerate() {
        let bb = g.nodes.iter().filter_map(|n| node_rects.get(n)).fold(Rect::NOTHING, |a, r| a.union(*r));
        if !bb.is_finite() {
            out.groups.push(None);
            continue;
        }
        let frame =
            Rect::from_min_max(bb.min - egui::vec2(GROUP_PAD, GROUP_PAD + GROUP_BAR), bb.max + egui::vec2(GROUP_PAD, GROUP_PAD));
        let c = color_of(g.color.as_deref(), GROUP_COLOR);
        let is_sel = selected == Some(Annotation::Group(i));
        painter.rect_filled(frame, 8.0, c.gamma_multiply(0.22));
        let bar = Rect::from_min_size(frame.min, egui::vec2(frame.width(), GROUP_BAR));
        painter.rect_filled(bar, egui::CornerRadius { nw: 8, ne: 8, sw: 0, se: 0 }, c.gamma_multiply(0.8));
        let stroke = if is_sel { Stroke::new(2.5, Color32::from_rgb(255, 200, 80)) } else { Stroke::new(1.0, c) };
        painter.rect_stroke(frame, 8.0, stroke, egui::StrokeKind::Outside);
        painter.text(
            bar.left_center() + egui::vec2(10.0, 0.0),
            egui::Align2::LEFT_CENTER,
            &g.title,
            FontId::proportional(15.0),
            Color32::WHITE,
        );
        out.groups.push(Some(frame));
    }
    for (i, c) in doc.comments.iter().enumerate() {
        let pos = match comment_at {
            Some((j, p)) if j == i => p,
            _ => Pos2::new(c.pos.0, c.pos.1),
        };
        let text = if c.text.trim().is_empty() { "(empty comment)" } else { c.text.as_str() };
        let galley = painter.layout(text.to_string(), FontId::proportional(14.0), Color32::from_gray(20), COMMENT_WRAP);
        let rect = Rect::from_min_size(pos, galley.size() + egui::vec2(20.0, 16.0));
        let fill = color_of(c.color.as_deref(), COMMENT_COLOR);
        painter.rect_filled(rect.translate(egui::vec2(3.0, 3.0)), 4.0, Color32::from_black_alpha(70));
        painter.rect_filled(rect, 4.0, fill);
        if selected == Some(Annotation::Comment(i)) {
            painter.rect_stroke(rect, 4.0, Stroke::new(2.5, Color32::from_rgb(255, 200, 80)), egui::StrokeKind::Outside);
        }
        painter.galley(pos + egui::vec2(10.0, 8.0), galley, Color32::from_gray(20));
        out.comments.push(rect);
    }
    out
}

/// The colours groups and comments are drawn in, in document order.
pub fn annotation_colors(doc: &GraphDoc) -> (Vec<Color32>, Vec<Color32>) {
    (
        doc.groups.iter().map(|g| color_of(g.color.as_deref(), GROUP_COLOR)).collect(),
        doc.comments.iter().map(|c| color_of(c.color.as_deref(), COMMENT_COLOR)).collect(),
    )
}

/// The minimap: groups and comments as boxes in their colours (`boxes`, canvas rects), every
/// node (selected ones highlighted) and the visible part of the canvas, in a box at
/// `screen_rect`. Returns the canvas position to centre the view on while the user clicks or
/// drags in it.
pub fn minimap(
    ctx: &egui::Context,
    screen_rect: Rect,
    nodes: &[(Rect, bool)],
    boxes: &[(Rect, Color32)],
    view: Rect,
) -> Option<Pos2> {
    let content = nodes.iter().fold(Rect::NOTHING, |a, (r, _)| a.union(*r));
    let content = boxes.iter().fold(content, |a, (r, _)| a.union(*r));
    if !content.is_finite() {
        return None;
    }
    let world = content.union(view).expand(40.0);
    let inner = screen_rect.shrink(6.0);
    let s = (inner.width() / world.width()).min(inner.height() / world.height());
    let offset = inner.center() - world.center().to_vec2() * s;
    let to_map = |p: Pos2| Pos2::new(p.x * s + offset.x, p.y * s + offset.y);
    let mut target = None;
    egui::Area::new(egui::Id::new("pyrograph-minimap")).fixed_pos(screen_rect.min).order(egui::Order::Foreground).show(
        ctx,
        |ui| {
            let (rect, resp) = ui.allocate_exact_size(screen_rect.size(), egui::Sense::click_and_drag());
            let painter = ui.painter_at(rect);
            painter.rect_filled(rect, 6.0, Color32::from_black_alpha(190));
            painter.rect_stroke(rect, 6.0, Stroke::new(1.0, Color32::from_gray(90)), egui::StrokeKind::Inside);
            for (r, c) in boxes {
                let m = Rect::from_min_max(to_map(r.min), to_map(r.max));
                painter.rect_filled(m, 2.0, c.gamma_multiply(0.45));
            }
            for (r, sel) in nodes {
                let m = Rect::from_min_max(to_map(r.min), to_map(r.max));
                let c = if *sel { Color32::from_rgb(255, 200, 80) } else { Color32::from_gray(150) };
                painter.rect_filled(m, 1.0, c);
            }
            let v = Rect::from_min_max(to_map(view.min), to_map(view.max)).intersect(rect);
            painter.rect_stroke(v, 2.0, Stroke::new(1.5, Color32::from_rgb(120, 200, 255)), egui::StrokeKind::Inside);
            if (resp.clicked() || resp.dragged())
                && let Some(p) = resp.interact_pointer_pos()
            {
                target = Some(Pos2::new((p.x - offset.x) / s, (p.y - offset.y) / s));
            }
            resp.on_hover_text("minimap: click or drag to move the view (M hides it)");
        },
    );
    target
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hits_prefer_comments_then_group_bars() {
        let rects = AnnotationRects {
            groups: vec![Some(Rect::from_min_max(Pos2::new(0.0, 0.0), Pos2::new(300.0, 200.0))), None],
            comments: vec![Rect::from_min_max(Pos2::new(10.0, 5.0), Pos2::new(60.0, 40.0))],
        };
        assert_eq!(rects.hit(Pos2::new(20.0, 10.0)), Some(Annotation::Comment(0)));
        assert_eq!(rects.hit(Pos2::new(200.0, 10.0)), Some(Annotation::Group(0)));
        assert_eq!(rects.hit(Pos2::new(200.0, 100.0)), None, "a group's body is canvas: rectangles start there");
        assert_eq!(rects.group_bar(1), None);
    }
}
