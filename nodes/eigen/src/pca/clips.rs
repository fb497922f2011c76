//! What the Eigenfires nodes share: frames between clips and sample buffers, checked for size
//! and channels, and the number of components a node uses. These are algorithms: their errors
//! say what is wrong with which clip's frame, and the node that calls them names the port.

use std::sync::{Arc, Mutex};

use pyrograph_core::{Channels, Clip, CookCtx, Image, NodeError, PortType, Value};
use rayon::prelude::*;

use super::blocks::{BlockSource, train_blocks};
use super::training::Database;
use crate::values::{Basis, FrameRef};

/// An empty `Clip<Image>`: the default of optional clip inputs.
pub fn empty_clip() -> Clip {
    Clip::from_frames(PortType::Image, 0.0, Vec::new())
}

/// Why frames could not be read from a clip (the `clip`-th of those given) or trained on.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ClipError {
    /// A frame failed to cook upstream, or the cook was cancelled: that node error as it is.
    #[error("{error}")]
    Upstream {
        /// Which clip.
        clip: usize,
        /// The error.
        error: NodeError,
    },
    /// A frame that cannot be trained on or projected (its channels or size), and why.
    #[error("{message}")]
    Frame {
        /// Which clip.
        clip: usize,
        /// What is wrong with which frame.
        message: String,
    },
    /// The training itself failed.
    #[error("{0}")]
    Training(String),
}

/// Pulls every frame of `clip` (in parallel) into `out` (one `N`-sample gray frame after
/// another), checking size and channels; the error says what is wrong with which frame.
pub fn gather_frames(clip: &Clip, size: (u32, u32), out: &mut [f32], ctx: &CookCtx) -> Result<(), ClipError> {
    let n = size.0 as usize * size.1 as usize;
    out.par_chunks_mut(n).enumerate().try_for_each(|(i, dst)| {
        let img = clip.image(i, ctx).map_err(|error| ClipError::Upstream { clip: 0, error })?;
        check_frame(&img, size, i).map_err(|message| ClipError::Frame { clip: 0, message })?;
        dst.copy_from_slice(img.data());
        ctx.frame_progress(i + 1, clip.len());
        Ok(())
    })
}

/// Checks that frame `i` of a training or query clip is gray and of the database's `size`.
pub(super) fn check_frame(img: &Image, size: (u32, u32), i: usize) -> Result<(), String> {
    if img.channels() != Channels::Gray {
        return Err(format!("frame {i} is RGBA; Eigenfires train on gray frames (add imaging.to_gray)"));
    }
    if img.size() != size {
        return Err(format!(
            "frame {i} is {}x{} but the database frames are {}x{}; every frame must be the same size",
            img.width(),
            img.height(),
            size.0,
            size.1
        ));
    }
    Ok(())
}

/// Wraps `rows × N` samples as a clip of gray images.
pub fn samples_to_clip(basis: &Basis, samples: Vec<f32>, clamp: bool, fps: f64) -> Result<Clip, String> {
    let n = basis.pixels();
    let frames = samples
        .par_chunks(n.max(1))
        .map(|s| {
            let data = if clamp { s.iter().map(|v| v.clamp(0.0, 1.0)).collect() } else { s.to_vec() };
            Image::from_vec(basis.width, basis.height, Channels::Gray, data)
                .map(|img| Value::Image(Arc::new(img)))
                .ok_or_else(|| "reconstructed frame has the wrong size".to_string())
        })
        .collect::<Result<Vec<_>, _>>()?;
    Ok(Clip::from_frames(PortType::Image, fps, frames))
}

/// The number of components to use: `requested`, or all `available` when 0; more than available
/// is an error (the caller names the port that asked).
pub fn components_to_use(requested: usize, available: usize) -> Result<usize, String> {
    match requested {
        0 => Ok(available),
        r if r > available => {
            Err(format!("asks for {r} components but only {available} are available; use at most {available} (0 = all)"))
        }
        r => Ok(r),
    }
}

/// [`train_blocks`] over the frames of the training clips, read block by block. An error names
/// the clip at fault by its index in `clips`.
pub fn train_from_clips(
    clips: &[&Clip],
    size: (u32, u32),
    max_components: usize,
    block: usize,
    ctx: &CookCtx,
) -> Result<Database, ClipError> {
    let n = size.0 as usize * size.1 as usize;
    let mut starts = Vec::with_capacity(clips.len());
    let mut sources = Vec::new();
    for (k, clip) in clips.iter().enumerate() {
        starts.push(sources.len());
        sources.extend((0..clip.len()).map(|f| FrameRef { clip: k as u32, index: f as u32 }));
    }
    // The block reader reports a message; the error behind it is kept here, whole, so a cancelled
    // cook stays cancelled and a bad frame names its clip.
    let failed: Mutex<Option<ClipError>> = Mutex::new(None);
    let fail = |e: ClipError| {
        let message = e.to_string();
        if let Ok(mut slot) = failed.lock() {
            slot.get_or_insert(e);
        }
        message
    };
    let read = |r: std::ops::Range<usize>, out: &mut [f32]| -> Result<(), String> {
        ctx.check_cancel().map_err(|error| fail(ClipError::Upstream { clip: 0, error }))?;
        out.par_chunks_mut(n).enumerate().try_for_each(|(j, dst)| {
            let g = r.start + j;
            let k = starts.partition_point(|&s| s <= g) - 1;
            let img = clips[k].image(g - starts[k], ctx).map_err(|error| fail(ClipError::Upstream { clip: k, error }))?;
            check_frame(&img, size, g - starts[k]).map_err(|message| fail(ClipError::Frame { clip: k, message }))?;
            dst.copy_from_slice(img.data());
            Ok(())
        })
    };
    let scratch = ctx.settings().cache_dir.clone().unwrap_or_else(std::env::temp_dir);
    let progress = |done: usize, total: usize| ctx.frame_progress(done, total);
    let source = BlockSource { read: &read, scratch: Some(&scratch), progress: &progress };
    train_blocks(size.0, size.1, sources, max_components, block, &source)
        .map_err(|m| failed.lock().ok().and_then(|mut slot| slot.take()).unwrap_or(ClipError::Training(m)))
}
