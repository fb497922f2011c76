//! Groups (titled, coloured frames around nodes) and sticky comments: the edits the canvas and
//! the inspector make to them. Both live in the document (version 2), so they survive saving.

use pyrograph_frontend::core::{CommentDoc, GroupDoc};

use crate::state::Editor;

/// The colour a new group gets.
pub const GROUP_COLOR: &str = "#4a6a9a";
/// The colour a new comment gets.
pub const COMMENT_COLOR: &str = "#d8c060";

/// A selected group or comment, by index in the document.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Annotation {
    /// `doc.groups[i]`.
    Group(usize),
    /// `doc.comments[i]`.
    Comment(usize),
}

impl Editor {
    /// Puts `ids` into a new group titled `title` (taking them out of any group they were in);
    /// returns its index, or `None` when no id names a node.
    pub fn group_nodes(&mut self, ids: &[String], title: &str) -> Option<usize> {
        let ids: Vec<String> = ids.iter().filter(|id| self.node_doc(id).is_some()).cloned().collect();
        if ids.is_empty() {
            self.set_status("select the nodes to group first", true);
            return None;
        }
        let index = self.edit(None, |d| {
            for id in &ids {
                d.ungroup_node(id);
            }
            d.groups.push(GroupDoc { title: title.to_string(), color: Some(GROUP_COLOR.into()), nodes: ids.clone() });
            d.groups.len() - 1
        });
        self.set_status(format!("grouped {} node(s) as \"{title}\"", ids.len()), false);
        Some(index)
    }

    /// Adds a comment at canvas position `pos`; returns its index.
    pub fn add_comment(&mut self, text: &str, pos: (f32, f32)) -> usize {
        self.edit(None, |d| {
            d.comments.push(CommentDoc {
                text: text.to_string(),
                pos: (pos.0.round(), pos.1.round()),
                color: Some(COMMENT_COLOR.into()),
            });
            d.comments.len() - 1
        })
    }

    /// Sets a group's title (typing coalesces into one undo step until sealed).
    pub fn set_group_title(&mut self, index: usize, title: &str) {
        self.edit(Some(&format!("group-title:{index}")), |d| {
            if let Some(g) = d.groups.get_mut(index) {
                g.title = title.to_string();
            }
        });
    }

    /// Sets a comment's text (typing coalesces into one undo step until sealed).
    pub fn set_comment_text(&mut self, index: usize, text: &str) {
        self.edit(Some(&format!("comment-text:{index}")), |d| {
            if let Some(c) = d.comments.get_mut(index) {
                c.text = text.to_string();
            }
        });
    }

    /// Sets the colour (`"#rrggbb"`) of a group or comment.
    pub fn set_annotation_color(&mut self, which: Annotation, color: &str) {
        self.edit(Some(&format!("color:{which:?}")), |d| match which {
            Annotation::Group(i) => {
                if let Some(g) = d.groups.get_mut(i) {
                    g.color = Some(color.to_string());
                }
            }
            Annotation::Comment(i) => {
                if let Some(c) = d.comments.get_mut(i) {
                    c.color = Some(color.to_string());
                }
            }
        });
    }

    /// Moves a comment (one undo step per drag).
    pub fn move_comment(&mut self, index: usize, pos: (f32, f32)) {
        self.edit(Some("move"), |d| {
            if let Some(c) = d.comments.get_mut(index) {
                c.pos = (pos.0.round(), pos.1.round());
            }
        });
    }

    /// Removes a group (its nodes stay) or a comment.
    pub fn remove_annotation(&mut self, which: Annotation) {
        self.edit(None, |d| match which {
            Annotation::Group(i) if i < d.groups.len() => {
                d.groups.remove(i);
            }
            Annotation::Comment(i) if i < d.comments.len() => {
                d.comments.remove(i);
            }
            _ => {}
        });
    }

    /// The group node `id` belongs to.
    pub fn group_of(&self, id: &str) -> Option<usize> {
        self.doc().groups.iter().position(|g| g.nodes.iter().any(|n| n == id))
    }
}

/// A `"#rrggbb"` colour as RGB bytes.
pub fn hex_rgb(text: &str) -> Option<[u8; 3]> {
    let c = pyrograph_frontend::core::graph::parse_hex_color(text)?;
    Some([0, 1, 2].map(|i| (c[i] * 255.0).round().clamp(0.0, 255.0) as u8))
}

/// RGB bytes as `"#rrggbb"`.
pub fn rgb_hex(c: [u8; 3]) -> String {
    format!("#{:02x}{:02x}{:02x}", c[0], c[1], c[2])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hex_colours_round_trip() {
        assert_eq!(hex_rgb("#4a6a9a"), Some([0x4a, 0x6a, 0x9a]));
        assert_eq!(rgb_hex([0x4a, 0x6a, 0x9a]), "#4a6a9a");
        assert_eq!(hex_rgb("blue"), None);
    }

    #[test]
    fn grouping_moves_nodes_out_of_their_old_group_and_undoes() {
        let mut ed = Editor::with_default_registry();
        ed.auto_cook = false;
        let a = ed.add_node("value.float", (0.0, 0.0)).unwrap();
        let b = ed.add_node("value.float", (0.0, 100.0)).unwrap();
        assert_eq!(ed.group_nodes(&[a.clone(), b.clone()], "first"), Some(0));
        assert_eq!(ed.group_nodes(std::slice::from_ref(&b), "second"), Some(1));
        assert_eq!(ed.doc().groups[0].nodes, vec![a.clone()]);
        assert_eq!(ed.group_of(&b), Some(1));
        assert_eq!(ed.group_nodes(&["nope".to_string()], "x"), None, "no nodes, no group");
        ed.undo();
        assert_eq!(ed.doc().groups.len(), 1);
        assert_eq!(ed.group_of(&b), Some(0));
    }
}
