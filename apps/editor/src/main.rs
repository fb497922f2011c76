//! `pyrograph-editor [GRAPH]`: opens the node editor, optionally on a graph file.

use std::path::PathBuf;

use pyrograph_editor::{Editor, EditorApp};

fn recent_file() -> Option<PathBuf> {
    let base = std::env::var_os("XDG_CONFIG_HOME")
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".config")))?;
    Some(base.join("pyrograph").join("recent.txt"))
}

fn main() {
    let mut graph = None;
    let mut select = None;
    let mut dump = None;
    // Scrubbing back and forth re-uses cooked frames: interactive work gets a larger frame cache
    // than a batch render (which streams), unless --cache-mb says otherwise.
    let mut cache_mb: usize = 1024;
    let mut plugins = pyrograph_frontend::plugins::PluginFlags::default();
    let mut args = std::env::args_os().skip(1);
    while let Some(a) = args.next() {
        if a == "--help" || a == "-h" {
            println!(
                "usage: pyrograph-editor [GRAPH.ron] [--select NODE] [--state-dump FILE.json] [--cache-mb MIB] [--plugins DIR]… [--no-plugins]"
            );
            println!(
                "  --plugins     load Python plugin nodes from DIR too (also PYROGRAPH_PLUGIN_PATH and plugins/ beside the graph)"
            );
            println!("  --no-plugins  load no Python plugins");
            println!("  --cache-mb    memory for cooked frames shared by every clip (default 1024; View menu)");
            println!("  --state-dump  keep FILE.json current with the selection and node positions (for tests)");
            return;
        } else if a == "--plugins" {
            plugins.dirs.extend(args.next().map(PathBuf::from));
        } else if a == "--no-plugins" {
            plugins.off = true;
        } else if a == "--select" {
            select = args.next().map(|s| s.to_string_lossy().into_owned());
        } else if a == "--cache-mb" {
            match args.next().and_then(|v| v.to_str().and_then(|v| v.parse().ok())) {
                Some(mb) => cache_mb = mb,
                None => {
                    eprintln!("pyrograph-editor: --cache-mb needs a whole number of MiB");
                    std::process::exit(2);
                }
            }
        } else if a == "--state-dump" {
            dump = args.next().map(PathBuf::from);
        } else {
            graph = Some(PathBuf::from(a));
        }
    }
    pyrograph_frontend::core::FrameCache::global().set_budget(cache_mb << 20);
    // Previews revisit frames: hold 8-bit ones at a byte a sample.
    pyrograph_frontend::core::FrameCache::global().set_compact(true);
    let mut editor = Editor::with_plugins(plugins);
    if let Some(f) = recent_file() {
        editor.use_recent_file(f);
    }
    if let Some(g) = &graph {
        if let Some(dir) = g.parent().map(|d| d.join("presets")) {
            editor.add_preset_dir(dir);
        }
        // Read and validated on a loader thread while the window opens; problems are shown
        // in it, and the editor opens either way.
        editor.begin_open(g);
    }
    let mut app = EditorApp::new(editor);
    // The file opens on a loader thread: the node is selected once it is there.
    app.select_on_open = select;
    app.state_dump = dump;
    app.canvas.frame_all();
    let options = eframe::NativeOptions {
        viewport: eframe::egui::ViewportBuilder::default().with_inner_size([1600.0, 1000.0]).with_title("pyrograph editor"),
        renderer: eframe::Renderer::Glow,
        ..Default::default()
    };
    if let Err(e) = eframe::run_native("pyrograph editor", options, Box::new(move |_cc| Ok(Box::new(app)))) {
        eprintln!("pyrograph-editor: cannot open a window: {e}");
        std::process::exit(1);
    }
}
