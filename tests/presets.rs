//! `pyrograph presets` over a studio library (issue 30): the search path's order, a name that two
//! libraries hold, a preset from a newer pyrograph, and the filters.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use pyrograph_testing::workspace;

fn presets(args: &[&str], studio: &[&Path]) -> (Output, serde_json::Value) {
    let path = std::env::join_paths(studio).unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_pyrograph"))
        .arg("presets")
        .args(args)
        .env("PYROGRAPH_PRESET_PATH", path)
        .current_dir(std::env::temp_dir())
        .output()
        .unwrap();
    let v = serde_json::from_slice(&o.stdout).unwrap_or(serde_json::Value::Null);
    (o, v)
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// The shipped flame card, renamed and retagged as a studio's own "campfire".
fn studio_campfire() -> String {
    let card = std::fs::read_to_string(workspace().join("graphs/presets/flame-card.ron")).unwrap();
    card.replace("name: \"flame card\"", "name: \"campfire\"")
        .replace("tags: [\"fire\", \"card\", \"procedural\"]", "tags: [\"studio\", \"fire\"]")
}

fn names(v: &serde_json::Value) -> Vec<String> {
    v.as_array().unwrap().iter().map(|p| p["name"].as_str().unwrap().to_string()).collect()
}

#[test]
fn a_studio_library_shadows_by_path_order_and_refuses_newer_presets() {
    let (a, b) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    std::fs::write(a.path().join("our-campfire.ron"), studio_campfire()).unwrap();
    std::fs::write(b.path().join("campfire.ron"), studio_campfire().replace("\"studio\"", "\"other-studio\"")).unwrap();
    std::fs::write(b.path().join("future.ron"), "(version: 9, preset: (name: \"future\"), nodes: {})").unwrap();

    let (o, v) = presets(&["--json"], &[a.path(), b.path()]);
    // The refused preset makes the listing fail, but everything usable is still listed.
    assert!(!o.status.success());
    assert!(stderr(&o).contains("future.ron") && stderr(&o).contains("newer than this pyrograph"), "{}", stderr(&o));
    let list = v.as_array().unwrap();
    let campfire = list.iter().find(|p| p["name"] == "campfire").expect("campfire listed");
    // The first folder of PYROGRAPH_PRESET_PATH wins; it hides the second folder's and the shipped one.
    assert_eq!(campfire["file"].as_str().unwrap(), a.path().join("our-campfire.ron").display().to_string());
    let hides: Vec<&str> = campfire["hides"].as_array().unwrap().iter().map(|h| h.as_str().unwrap()).collect();
    assert_eq!(hides.len(), 2, "{hides:?}");
    assert!(hides[0].ends_with("campfire.ron") && hides[0].starts_with(&*b.path().display().to_string()), "{hides:?}");
    assert!(hides[1].ends_with("graphs/presets/campfire.ron"), "{hides:?}");
    assert!(stderr(&o).contains("is hidden by"), "{}", stderr(&o));
    assert_eq!(names(&v).iter().filter(|n| *n == "campfire").count(), 1);
    // The shipped presets come last and carry their metadata.
    let card = list.iter().find(|p| p["name"] == "flame card").expect("the shipped flame card");
    assert_eq!(card["revision"], 1);
    assert!(card["params"].as_array().unwrap().iter().any(|p| p["name"] == "seed"));

    // Swapping the folders swaps the winner.
    let (_, v) = presets(&["--json"], &[b.path(), a.path()]);
    let campfire = v.as_array().unwrap().iter().find(|p| p["name"] == "campfire").unwrap();
    assert_eq!(campfire["file"].as_str().unwrap(), b.path().join("campfire.ron").display().to_string());
}

#[test]
fn tags_and_text_filter_the_listing() {
    let a = tempfile::tempdir().unwrap();
    std::fs::write(a.path().join("our-campfire.ron"), studio_campfire()).unwrap();
    let (o, v) = presets(&["--json", "--tag", "studio"], &[a.path()]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(names(&v), vec!["campfire".to_string()]);
    let (_, v) = presets(&["--json", "--tag", "preprocess", "--search", "TEA-LIGHT"], &[a.path()]);
    assert_eq!(names(&v), vec!["tea-light pre-processing".to_string()]);
    let (o, v) = presets(&["--json", "--search", "no such preset"], &[a.path()]);
    assert!(o.status.success() && v.as_array().unwrap().is_empty());
    // Text output names each preset with its file and tags.
    let (o, _) = presets(&["--tag", "studio"], &[a.path()]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("campfire") && out.contains("our-campfire.ron") && out.contains("[studio, fire]"), "{out}");
}

fn run(args: &[&str], cwd: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_pyrograph"))
        .args(args)
        .current_dir(cwd)
        .env_remove("PYROGRAPH_PRESET_PATH")
        .output()
        .unwrap()
}

#[test]
fn a_preset_renders_by_name_with_its_parameters_set() {
    let dir = tempfile::tempdir().unwrap();
    let args = ["preset", "candle row", "--set", "width=96", "--set", "height=54", "--set", "frames=2", "--out", "renders"];
    let o = run(&args, dir.path());
    assert!(o.status.success(), "{}", stderr(&o));
    let frames: Vec<PathBuf> = (0..2).map(|i| dir.path().join(format!("renders/candle-row/candle-row_{i:04}.png"))).collect();
    for f in &frames {
        assert_eq!(image::image_dimensions(f).unwrap(), (96, 54), "{}", f.display());
    }
    assert!(!dir.path().join("renders/candle-row/candle-row_0002.png").exists(), "frames=2 writes two frames");
    // A second run does not replace the frames unless asked.
    let o = run(&args, dir.path());
    assert!(!o.status.success() && stderr(&o).contains("already exists"), "{}", stderr(&o));
    // A parameter the preset does not expose, and a name no library holds, are errors that say so.
    let o = run(&["preset", "candle row", "--set", "flames=3", "--out", "r2"], dir.path());
    assert!(!o.status.success() && stderr(&o).contains("has no parameter 'flames'"), "{}", stderr(&o));
    let o = run(&["preset", "no such fire", "--out", "r3"], dir.path());
    assert!(!o.status.success() && stderr(&o).contains("no preset named 'no such fire'"), "{}", stderr(&o));
    assert!(stderr(&o).contains("campfire"), "the error lists the presets there are: {}", stderr(&o));
    // The file's stem finds it too; `path` (the preset file itself) cannot be set.
    let o =
        run(&["preset", "candle-row", "--set", "width=32", "--set", "height=18", "--set", "frames=1", "--out", "r4"], dir.path());
    assert!(o.status.success() && dir.path().join("r4/candle-row/candle-row_0000.png").exists(), "{}", stderr(&o));
    let o = run(&["preset", "candle row", "--set", "path=other.ron", "--out", "r5"], dir.path());
    assert!(!o.status.success() && stderr(&o).contains("names the preset file itself"), "{}", stderr(&o));
}

#[test]
fn thumbnails_are_cooked_into_a_folder_and_kept_unless_overwritten() {
    let dir = tempfile::tempdir().unwrap();
    let library = workspace().join("graphs/presets");
    let args =
        ["presets", "--dir", library.to_str().unwrap(), "--tag", "candle", "--tag", "perry", "--thumbnails", "--out", "thumbs"];
    let o = run(&args, dir.path());
    assert!(o.status.success(), "{}", stderr(&o));
    let made = dir.path().join("thumbs/candle-row.png");
    assert_eq!(image::image_dimensions(&made).unwrap(), (256, 144));
    assert!(!dir.path().join("thumbs/campfire.png").exists(), "only the presets the filters pick");
    std::fs::write(&made, b"mine").unwrap();
    let o = run(&args, dir.path());
    assert!(o.status.success() && String::from_utf8_lossy(&o.stdout).contains("kept"), "{}", stderr(&o));
    assert_eq!(std::fs::read(&made).unwrap(), b"mine", "an existing file is kept without --overwrite");
    let mut again = args.to_vec();
    again.push("--overwrite");
    assert!(run(&again, dir.path()).status.success());
    assert_eq!(image::image_dimensions(&made).unwrap(), (256, 144));
}
