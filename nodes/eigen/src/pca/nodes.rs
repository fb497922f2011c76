//! The nodes `eigen.eigenfires` (training, in memory or out of core), `eigen.project` and
//! `eigen.reconstruct`: they read ports, call the algorithms and name the port an error is about.

use std::sync::Arc;

use pyrograph_core::declare::{ClipOf, Cook};
use pyrograph_core::{Clip, CookCtx, Image, NodeError, port};
use rayon::prelude::*;

use super::clips::{ClipError, check_frame, components_to_use, empty_clip, gather_frames, samples_to_clip, train_from_clips};
use super::projection::{project, reconstruct};
use super::training::{Database, train};
use crate::values::{Basis, FrameRef, Weights};

// ---------------------------------------------------------------------------------------------
// eigen.eigenfires
// ---------------------------------------------------------------------------------------------

pyrograph_core::node! {
    /// Trains an Eigenfires database by PCA (thesis §4.2, eq. 12–17; weights eq. 18).
    ///
    /// The frames of clip1, then clip2 and clip3 when connected (fires A, B, C of the thesis), become one
    /// database of M gray frames of one size; the basis remembers each frame's source clip and index.
    /// The mean image Ψ (eq. 12) and the eigenfires come from the M×M Gram matrix (eq. 16–17), never the
    /// N×N covariance; they are sorted by eigenvalue, at most M − 1 are meaningful (fewer if frames repeat),
    /// and max_components caps how many are kept. The weights output is every training frame projected
    /// (eq. 18). Pixel values are 0..1, so weights and distances are 1/255 of the thesis' numbers. A
    /// database of more f32 frames than memory_mb trains out of core: the frames are read from the clips once, kept
    /// in a scratch file in the cache folder (`--cache-dir`, else the system's temp folder; read from the clips
    /// again when it has no room) and read back in blocks of at most 512 MiB and half of memory_mb, two blocks in
    /// memory at a time. The eigenfires equal the in-memory ones up to rounding (set max_components: the
    /// eigenfires themselves stay in memory).
    #[node("eigen.eigenfires", "Eigenfires", WholeClip)]
    pub struct Eigenfires {
        /// First training clip (gray frames).
        clip1: ClipOf<Arc<Image>>,
        /// Optional second training clip, same frame size.
        clip2: ClipOf<Arc<Image>> = ClipOf::new(empty_clip()),
        /// Optional third training clip, same frame size.
        clip3: ClipOf<Arc<Image>> = ClipOf::new(empty_clip()),
        /// Keep at most this many eigenfires; 0 = all meaningful (M − 1).
        #[range(0, 1_000_000)]
        max_components: usize = 0,
        /// MiB of f32 frames held for training: a larger database trains out of core, block by block.
        #[range(1, 1 << 30)]
        memory_mb: usize = DEFAULT_MEMORY_MB,
    }
    pub struct EigenfiresOut {
        /// Mean image, eigenfires and eigenvalues.
        basis: Arc<Basis>,
        /// Weights of every training frame (frames × components).
        weights: Arc<Weights>,
    }
}

impl From<Database> for EigenfiresOut {
    fn from(db: Database) -> Self {
        EigenfiresOut { basis: Arc::new(db.basis), weights: Arc::new(db.weights) }
    }
}

impl Eigenfires {
    /// A clip reader's error on the port of the clip at fault (`ports[clip]`; training failures
    /// on the first): a cancelled cook stays cancelled.
    pub(super) fn clip_error(ports: &[&str], e: ClipError) -> NodeError {
        let port = |clip: usize| ports.get(clip).copied().unwrap_or(ports[0]);
        match e {
            ClipError::Upstream { error, .. } if error.is_cancelled() => error,
            ClipError::Upstream { clip, error } => NodeError::port(port(clip), error.to_string()),
            ClipError::Frame { clip, message } => NodeError::port(port(clip), message),
            ClipError::Training(message) => NodeError::port(port(0), message),
        }
    }
}

impl Cook for Eigenfires {
    fn cook(self, ctx: &CookCtx) -> Result<EigenfiresOut, NodeError> {
        let clips: [&Clip; 3] = [&self.clip1, &self.clip2, &self.clip3];
        let ports = [port!(Eigenfires, clip1), port!(Eigenfires, clip2), port!(Eigenfires, clip3)];
        let clip1 = ports[0];
        if self.clip1.is_empty() {
            return Err(NodeError::port(clip1, "the clip has no frames"));
        }
        let first =
            self.clip1.image(0, ctx).map_err(|error| Eigenfires::clip_error(&ports, ClipError::Upstream { clip: 0, error }))?;
        let size = first.size();
        let n = size.0 as usize * size.1 as usize;
        let m: usize = clips.iter().map(|c| c.len()).sum();
        let total = n.checked_mul(m).ok_or_else(|| NodeError::msg("database too large"))?;
        let max_components = self.max_components;
        let memory = self.memory_mb.saturating_mul(1 << 20);
        if total.saturating_mul(4) > memory {
            // Two blocks in memory: at most half the budget each, and no more than BLOCK_BYTES.
            let block = (BLOCK_BYTES.min(memory / 2) / (n * 4)).max(1);
            let db = train_from_clips(&clips, size, max_components, block, ctx).map_err(|e| Eigenfires::clip_error(&ports, e))?;
            return Ok(db.into());
        }
        let mut data = vec![0.0_f32; total];
        let mut sources = Vec::with_capacity(m);
        let mut offset = 0;
        for (k, clip) in clips.iter().enumerate() {
            let len = clip.len();
            gather_frames(clip, size, &mut data[offset * n..(offset + len) * n], ctx)
                .map_err(|e| Eigenfires::clip_error(&ports[k..], e))?;
            sources.extend((0..len).map(|f| FrameRef { clip: k as u32, index: f as u32 }));
            offset += len;
        }
        ctx.check_cancel()?;
        let db = train(size.0, size.1, data, sources, max_components).map_err(|m| NodeError::port(clip1, m))?;
        Ok(db.into())
    }
}

/// Default of `memory_mb`: databases of more f32 frames than this train out of core.
const DEFAULT_MEMORY_MB: usize = 4096;

/// Bytes of frames per block of the out-of-core training.
const BLOCK_BYTES: usize = 512 << 20;

// ---------------------------------------------------------------------------------------------
// eigen.project
// ---------------------------------------------------------------------------------------------

pyrograph_core::node! {
    /// Projects gray frames into fire space: ω_k = eigenfire_kᵀ (I − Ψ) (thesis §4.3, eq. 18).
    ///
    /// Every frame of the clip becomes one row of weights, computed in batches as matrix products.
    /// components is the E used for detection (§5.1.2); 0 = all.
    #[node("eigen.project", "Eigenfires", WholeClip)]
    pub struct Project {
        /// The Eigenfires basis.
        basis: Arc<Basis>,
        /// Gray frames of the basis size.
        clip: ClipOf<Arc<Image>>,
        /// Eigenfires to project on (E); 0 = all.
        #[range(0, 1_000_000)]
        components: usize = 0,
    }
    /// Frames × components weights.
    -> weights: Arc<Weights>
}

/// Frames per batch while projecting a clip.
const PROJECT_BATCH: usize = 256;

impl Cook for Project {
    fn cook(self, ctx: &CookCtx) -> Result<Arc<Weights>, NodeError> {
        let (basis, clip) = (&*self.basis, &*self.clip);
        let port = port!(Project, clip);
        let e =
            components_to_use(self.components, basis.components()).map_err(|m| NodeError::port(port!(Project, components), m))?;
        if clip.is_empty() {
            return Err(NodeError::port(port, "the clip has no frames"));
        }
        let n = basis.pixels();
        let mut data = Vec::with_capacity(clip.len() * e);
        let mut start = 0;
        while start < clip.len() {
            let end = (start + PROJECT_BATCH).min(clip.len());
            let mut frames = vec![0.0_f32; (end - start) * n];
            frames.par_chunks_mut(n).enumerate().try_for_each(|(k, dst)| {
                let img = clip.image(start + k, ctx).map_err(|e| NodeError::port(port, e.to_string()))?;
                check_frame(&img, (basis.width, basis.height), start + k).map_err(|m| NodeError::port(port, m))?;
                dst.copy_from_slice(img.data());
                Ok::<_, NodeError>(())
            })?;
            let w = project(basis, &frames, e).map_err(|m| NodeError::port(port, m))?;
            data.extend_from_slice(&w.data);
            ctx.frame_progress(end, clip.len());
            start = end;
        }
        let w = Weights::new(clip.len(), e, data).ok_or_else(|| NodeError::msg("weights size mismatch"))?;
        Ok(Arc::new(w))
    }
}

// ---------------------------------------------------------------------------------------------
// eigen.reconstruct
// ---------------------------------------------------------------------------------------------

pyrograph_core::node! {
    /// Reconstructs images from weights: I = eigenfire Ω + Ψ (thesis §4.8, eq. 22).
    ///
    /// All rows of the weights become frames through one matrix product. components is the E used for
    /// rendering (§4.8, §5.1.2), separate from the E of detection; fewer components compress (Fig. 29).
    #[node("eigen.reconstruct", "Eigenfires", WholeClip)]
    pub struct Reconstruct {
        /// The Eigenfires basis.
        basis: Arc<Basis>,
        /// One row of weights per frame.
        weights: Arc<Weights>,
        /// Eigenfires used for rendering (E); 0 = all the weights hold.
        #[range(0, 1_000_000)]
        components: usize = 0,
        /// Clamp the samples to 0..1.
        clamp: bool = true,
        /// Frame rate of the output clip.
        #[range(0.001, 1000.0)]
        fps: f64 = 30.0,
    }
    /// The reconstructed gray frames.
    -> clip: ClipOf<Arc<Image>>
}

impl Cook for Reconstruct {
    fn cook(self, _: &CookCtx) -> Result<ClipOf<Arc<Image>>, NodeError> {
        let (basis, weights) = (&*self.basis, &*self.weights);
        if weights.frames == 0 {
            return Err(NodeError::port(port!(Reconstruct, weights), "there are no rows of weights to reconstruct"));
        }
        let components = port!(Reconstruct, components);
        let e = components_to_use(self.components, basis.components().min(weights.components))
            .map_err(|m| NodeError::port(components, m))?;
        let samples = reconstruct(basis, weights, e).map_err(|m| NodeError::port(components, m))?;
        let clip = samples_to_clip(basis, samples, self.clamp, self.fps).map_err(NodeError::msg)?;
        Ok(ClipOf::new(clip))
    }
}
