//! Undo/redo as whole-document snapshots: simple and robust, since documents are small.
//!
//! Every committed edit records the document as it was before. Edits that carry the same
//! coalescing key (one slider drag, one text field being typed into) merge into one step until
//! [`History::seal`] is called, which the app does once the pointer is released and no text field
//! has focus.

use pyrograph_frontend::core::GraphDoc;

/// How many steps are kept.
const MAX_STEPS: usize = 500;

struct Entry {
    doc: GraphDoc,
    key: Option<String>,
}

/// The undo and redo stacks.
#[derive(Default)]
pub struct History {
    undo: Vec<Entry>,
    redo: Vec<GraphDoc>,
    sealed: bool,
}

impl History {
    /// An empty history.
    pub fn new() -> Self {
        History::default()
    }

    /// Records `before` (the document before an edit). With a `key` equal to the previous
    /// unsealed edit's key, the edit merges into that step instead.
    pub fn record(&mut self, before: &GraphDoc, key: Option<&str>) {
        self.redo.clear();
        if let (Some(k), Some(last)) = (key, self.undo.last())
            && !self.sealed
            && last.key.as_deref() == Some(k)
        {
            return;
        }
        self.undo.push(Entry { doc: before.clone(), key: key.map(str::to_string) });
        if self.undo.len() > MAX_STEPS {
            self.undo.remove(0);
        }
        self.sealed = key.is_none();
    }

    /// Makes the last two steps one (an edit made of two, as adding a node and wiring it): undo
    /// then goes back to before the first.
    pub fn join_last_two(&mut self) {
        if self.undo.len() >= 2 {
            self.undo.pop();
        }
        self.sealed = true;
    }

    /// Ends the current coalescing run: the next edit is a new step whatever its key.
    pub fn seal(&mut self) {
        self.sealed = true;
    }

    /// The document to go back to, given the current one (which becomes redoable).
    pub fn undo(&mut self, current: &GraphDoc) -> Option<GraphDoc> {
        let entry = self.undo.pop()?;
        self.redo.push(current.clone());
        self.sealed = true;
        Some(entry.doc)
    }

    /// The document to go forward to, given the current one (which becomes undoable).
    pub fn redo(&mut self, current: &GraphDoc) -> Option<GraphDoc> {
        let doc = self.redo.pop()?;
        self.undo.push(Entry { doc: current.clone(), key: None });
        self.sealed = true;
        Some(doc)
    }

    /// Whether there is something to undo.
    pub fn can_undo(&self) -> bool {
        !self.undo.is_empty()
    }

    /// Whether there is something to redo.
    pub fn can_redo(&self) -> bool {
        !self.redo.is_empty()
    }

    /// Forgets everything (after opening another file).
    pub fn clear(&mut self) {
        self.undo.clear();
        self.redo.clear();
        self.sealed = true;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use pyrograph_frontend::core::ParamValue;

    fn doc_with(v: f64) -> GraphDoc {
        let mut d = GraphDoc::new();
        d.add_node("a", pyrograph_frontend::core::NodeDoc::new("value.float").param("value", ParamValue::Float(v)));
        d
    }

    #[test]
    fn same_key_coalesces_until_sealed() {
        let mut h = History::new();
        h.record(&doc_with(0.0), Some("drag"));
        h.record(&doc_with(1.0), Some("drag"));
        h.seal();
        h.record(&doc_with(2.0), Some("drag"));
        let back = h.undo(&doc_with(3.0)).unwrap();
        assert_eq!(back, doc_with(2.0));
        let back = h.undo(&back).unwrap();
        assert_eq!(back, doc_with(0.0));
        assert!(!h.can_undo());
        assert_eq!(h.redo(&back).unwrap(), doc_with(2.0));
    }
}
