//! What the Eigenfires nodes share: frames between clips and sample buffers, checked for size
//! and channels, and the number of components a node uses; errors name the node's port.

use std::sync::Arc;

use pyrograph_core::{Channels, Clip, CookCtx, Image, NodeError, PortType, Value};
use rayon::prelude::*;

use crate::values::Basis;

/// An empty `Clip<Image>`: the default of optional clip inputs.
pub fn empty_clip() -> Clip {
    Clip::from_frames(PortType::Image, 0.0, Vec::new())
}

/// Pulls every frame of `clip` (in parallel) into `out` (one `N`-sample gray frame after
/// another), checking size and channels; errors name `port`.
pub fn gather_frames(clip: &Clip, size: (u32, u32), out: &mut [f32], port: &str, ctx: &CookCtx) -> Result<(), NodeError> {
    let n = size.0 as usize * size.1 as usize;
    out.par_chunks_mut(n).enumerate().try_for_each(|(i, dst)| {
        let img = clip.image(i, ctx).map_err(|e| NodeError::port(port, e.to_string()))?;
        check_frame(&img, size, i, port)?;
        dst.copy_from_slice(img.data());
        ctx.frame_progress(i + 1, clip.len());
        Ok(())
    })
}

pub(super) fn check_frame(img: &Image, size: (u32, u32), i: usize, port: &str) -> Result<(), NodeError> {
    if img.channels() != Channels::Gray {
        return Err(NodeError::port(port, format!("frame {i} is RGBA; Eigenfires train on gray frames (add imaging.to_gray)")));
    }
    if img.size() != size {
        return Err(NodeError::port(
            port,
            format!(
                "frame {i} is {}x{} but the database frames are {}x{}; every frame must be the same size",
                img.width(),
                img.height(),
                size.0,
                size.1
            ),
        ));
    }
    Ok(())
}

/// Wraps `rows × N` samples as a clip of gray images.
pub fn samples_to_clip(basis: &Basis, samples: Vec<f32>, clamp: bool, fps: f64) -> Result<Clip, NodeError> {
    let n = basis.pixels();
    let frames = samples
        .par_chunks(n.max(1))
        .map(|s| {
            let data = if clamp { s.iter().map(|v| v.clamp(0.0, 1.0)).collect() } else { s.to_vec() };
            Image::from_vec(basis.width, basis.height, Channels::Gray, data)
                .map(|img| Value::Image(Arc::new(img)))
                .ok_or_else(|| NodeError::msg("reconstructed frame has the wrong size"))
        })
        .collect::<Result<Vec<_>, _>>()?;
    Ok(Clip::from_frames(PortType::Image, fps, frames))
}

/// The number of components to use: `requested`, or all `available` when 0; more than available
/// is an error naming `port`.
pub fn components_to_use(requested: usize, available: usize, port: &str) -> Result<usize, NodeError> {
    match requested {
        0 => Ok(available),
        r if r > available => Err(NodeError::port(
            port,
            format!("asks for {r} components but only {available} are available; use at most {available} (0 = all)"),
        )),
        r => Ok(r),
    }
}
