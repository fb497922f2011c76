//! Shared by the flame-model benches: the 150 real candle-black frames as gray planes.

use std::path::PathBuf;

use pyrograph_nodes_flame_model::model::gray_plane;
use pyrograph_nodes_imaging::io::load_image;
use pyrograph_testing::footage;
use rayon::prelude::*;

/// Gray planes, one per frame, and their shared (width, height).
pub type GrayFrames = (Vec<Vec<f32>>, (u32, u32));

/// The candle-black frames and their size, or `None` (with a message) when the footage is absent.
pub fn candle_frames() -> Option<GrayFrames> {
    let dir = footage().join("candle-black/frames");
    let Ok(entries) = std::fs::read_dir(&dir) else {
        eprintln!("skipping: no footage at {} (set PYROGRAPH_FOOTAGE)", dir.display());
        return None;
    };
    let mut files: Vec<PathBuf> =
        entries.filter_map(|e| e.ok().map(|e| e.path())).filter(|p| p.extension().is_some_and(|x| x == "png")).collect();
    files.sort();
    let images: Vec<_> = files.par_iter().map(|f| load_image(f).expect("readable footage frame")).collect();
    let size = images.first()?.size();
    Some((images.iter().map(gray_plane).collect(), size))
}
