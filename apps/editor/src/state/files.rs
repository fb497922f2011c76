//! Opening and saving documents, and the recent-files list.

use std::path::{Path, PathBuf};

use pyrograph_frontend::core::GraphDoc;
use pyrograph_frontend::core::document::write_atomic;

use super::Editor;

impl Editor {
    /// Recently opened files, newest first.
    pub fn recent(&self) -> &[PathBuf] {
        &self.recent
    }

    /// Keeps the recent-files list in `file` (read now, written on every open/save).
    pub fn use_recent_file(&mut self, file: PathBuf) {
        if let Ok(text) = std::fs::read_to_string(&file) {
            self.recent = text.lines().filter(|l| !l.trim().is_empty()).map(PathBuf::from).take(10).collect();
        }
        self.recent_file = Some(file);
    }

    /// Starts a new, empty document.
    pub fn new_document(&mut self) {
        self.cooker.cancel();
        self.path = None;
        self.scope.clear();
        self.doc = GraphDoc::new();
        self.saved = GraphDoc::new();
        self.saves += 1;
        self.history.clear();
        self.selection.clear();
        self.preview = None;
        self.preview_req = None;
        self.revision += 1;
        self.revalidate();
    }

    /// Saves to the current file (atomically).
    pub fn save(&mut self) -> Result<(), String> {
        let path = self.path.clone().ok_or("the document has no file yet: use Save As")?;
        self.save_as(&path)
    }

    /// Saves to `path` (atomically) and makes it the current file.
    pub fn save_as(&mut self, path: &Path) -> Result<(), String> {
        match self.root_doc().save(path, true) {
            Ok(()) => {
                let moved = self.path.as_deref() != Some(path);
                self.path = Some(path.to_path_buf());
                self.saved = self.root_doc().clone();
                self.saves += 1;
                self.push_recent(path);
                self.set_status(format!("saved {}", path.display()), false);
                if moved {
                    // Relative paths (and the plugins/ folder) now resolve against another folder.
                    self.plugins_for(path.parent());
                    self.revalidate();
                    self.revision += 1;
                }
                Ok(())
            }
            Err(e) => {
                let msg = format!("cannot save {}: {e}", path.display());
                self.set_status(msg.clone(), true);
                Err(msg)
            }
        }
    }

    pub(super) fn push_recent(&mut self, path: &Path) {
        let p = std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf());
        self.recent.retain(|r| *r != p);
        self.recent.insert(0, p);
        self.recent.truncate(10);
        if let Some(file) = &self.recent_file {
            if let Some(dir) = file.parent() {
                let _ = std::fs::create_dir_all(dir);
            }
            let text: String = self.recent.iter().map(|p| format!("{}\n", p.display())).collect();
            // Best effort: a recent-files list that cannot be written must not stop a save.
            let _ = write_atomic(file, text.as_bytes(), true);
        }
    }
}
