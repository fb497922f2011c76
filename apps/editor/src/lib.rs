//! pyrograph-editor: the node editor, an eframe app that is a thin view over the core graph
//! document.
//!
//! - [`state::Editor`] holds everything that is not drawing: the [`GraphDoc`](pyrograph_frontend::core::GraphDoc)
//!   (which owns the graph), undo/redo snapshots, validation mapped to nodes, the node palette,
//!   files, and cook requests to a background worker ([`cook::Cooker`]) that keeps one
//!   evaluator alive across edits.
//! - [`canvas::Canvas`] mirrors the document in an egui-snarl widget (its callbacks are the
//!   [`viewer`]); gestures come back as [`action::Action`]s, and connection requests go through
//!   the core type checker.
//! - [`app::EditorApp`] lays out menus, canvas, inspector and preview, and applies the actions;
//!   the windows it opens (the [`palette`], the [`browser`]) are widgets over the editor.
//!
//! Tests drive [`state::Editor`] directly and the UI headlessly with egui_kittest.
#![deny(missing_docs)]

pub mod action;
pub mod annotate;
pub mod app;
pub mod browser;
pub mod canvas;
pub mod clipboard;
mod compare_ui;
pub mod cook;
pub mod culling;
pub mod curves;
pub mod gesture;
pub mod gradient;
pub mod history;
pub mod key_ui;
pub mod keying;
pub mod keys;
pub mod layout;
pub mod overlay;
pub mod palette;
mod panels;
pub mod param_widgets;
pub mod paths;
pub mod playback;
pub mod state;
pub mod tangents;
pub mod viewer;

pub use app::EditorApp;
pub use state::Editor;
