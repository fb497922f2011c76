//! Eigenfires training, projection and reconstruction (thesis §4.2, §4.3, §4.8; eq. 12–18, 22).
//!
//! Training follows Turk and Pentland's M×M trick: with the `M` mean-free frames as the columns
//! of `A` (`N × M`), the eigenvectors of the small Gram matrix `L = AᵀA` (eq. 16) give the
//! eigenfires `u_l = A v_l / √μ_l` (eq. 17), so the `N × N` covariance of eq. 15 is never built.
//! Memory stays near the data size: the frames (`N·M` floats) plus the eigenfires (`N·E`), and
//! `M × M` matrices in f64. `L` is accumulated in f64 over blocks of pixel rows, so the null
//! direction left by subtracting the mean (`E = M − 1`) is told apart from real small eigenvalues.

use std::sync::Arc;

use crate::values::{Basis, FrameRef, Weights};
use faer::linalg::matmul::matmul;
use faer::linalg::matmul::triangular::{self, BlockStructure};
use faer::{Accum, Mat, MatMut, MatRef, Par, Side};
use pyrograph_core::params::{ClipOf, Cook};
use pyrograph_core::{Channels, Clip, CookCtx, Image, NodeError, PortType, Registry, Value, port};
use rayon::prelude::*;

/// Adds this module's node types.
pub fn register(registry: &mut Registry) {
    registry.add(Eigenfires::node());
    registry.add(Project::node());
    registry.add(Reconstruct::node());
}

/// A trained Eigenfires database: the basis and the weights of its training frames.
#[derive(Clone, Debug, PartialEq)]
pub struct Database {
    /// Mean, eigenfires, eigenvalues and frame sources.
    pub basis: Basis,
    /// Training frames × components (eq. 18 for every training frame).
    pub weights: Weights,
}

/// Eigenvalues of `L` below this fraction of the largest count as zero (not meaningful). `L` is
/// accumulated in f32 (relative precision ≈ 6e-8 per product sum), so anything under 1e-6 of the
/// largest is rounding noise, i.e. singular values under 1e-3 of the largest.
pub const RELATIVE_EIGENVALUE_FLOOR: f64 = 1e-6;

pub(crate) fn par() -> Par {
    Par::rayon(0)
}

/// Pixel rows per task of the eigenfire lift.
const LIFT_BAND_ROWS: usize = 1024;

/// `u = a · v` for a tall `a` (pixels × frames), split into bands of pixel rows that each rayon
/// task multiplies on its own. At the thesis size (274,700 × 2,197 times 2,197 × 1,100) this ran
/// 1.2–1.4× faster than handing the whole product to faer's parallel matmul, which splits the
/// work inside each block instead; every band reads its slice of `a` once and writes its rows
/// of `u` once. The same holds for reconstruction's `images += basis · weights`.
fn lift(u: MatMut<'_, f32>, accum: Accum, a: MatRef<'_, f32>, v: MatRef<'_, f32>) {
    let mut bands = Vec::with_capacity(u.nrows().div_ceil(LIFT_BAND_ROWS));
    let mut rest = u;
    let mut r0 = 0;
    while rest.nrows() > 0 {
        let rows = LIFT_BAND_ROWS.min(rest.nrows());
        let (band, below) = rest.split_at_row_mut(rows);
        bands.push((r0, band));
        rest = below;
        r0 += rows;
    }
    bands.into_par_iter().for_each(|(r0, band)| {
        let rows = band.nrows();
        matmul(band, accum, a.subrows(r0, rows), v, 1.0, Par::Seq);
    });
}

/// Frees `data` on a short-lived thread: returning a few GB of centred frames to the system
/// takes ~0.1 ms per MB of page unmapping, which the caller need not wait for.
fn release_in_background(data: Vec<f32>) {
    // When no thread can be started, the closure and with it `data` are dropped right here.
    let _ = std::thread::Builder::new().name("pca-release".into()).spawn(move || drop(data));
}

/// `Σ x²` in f64, in eight independent partial sums (one running sum is a chain of dependent
/// additions that runs at a quarter of the speed and does not vectorize).
fn sum_of_squares(u: &[f32]) -> f64 {
    let mut acc = [0.0_f64; 8];
    let mut blocks = u.chunks_exact(8);
    for block in blocks.by_ref() {
        for (a, &x) in acc.iter_mut().zip(block) {
            *a += f64::from(x) * f64::from(x);
        }
    }
    let tail: f64 = blocks.remainder().iter().map(|&x| f64::from(x) * f64::from(x)).sum();
    acc.iter().sum::<f64>() + tail
}

/// Trains an Eigenfires basis (§4.2) on `frames`: `M = sources.len()` gray images of
/// `width × height`, frame `n` at `frames[n·N..(n+1)·N]`. `frames` is consumed (made mean-free in
/// place). Keeps every meaningful eigenfire (at most `M − 1`), or the first `max_components` when
/// that is non-zero. Training weights come from the decomposition itself (`ω_l(n) = √μ_l v_l(n)`),
/// which equals the projection of eq. 18.
pub fn train(
    width: u32,
    height: u32,
    mut frames: Vec<f32>,
    sources: Vec<FrameRef>,
    max_components: usize,
) -> Result<Database, String> {
    let (n, m) = database_shape(width, height, &sources)?;
    if frames.len() != n * m {
        return Err(format!("frame data holds {} samples, expected {m} frames of {n}", frames.len()));
    }

    // Eq. 12: the mean image, accumulated in f64.
    let mut mean = vec![0.0_f32; n];
    mean.par_chunks_mut(4096).enumerate().for_each(|(c, chunk)| {
        let p0 = c * 4096;
        let mut acc = vec![0.0_f64; chunk.len()];
        for f in 0..m {
            let col = &frames[f * n + p0..f * n + p0 + chunk.len()];
            acc.iter_mut().zip(col).for_each(|(a, &v)| *a += f64::from(v));
        }
        chunk.iter_mut().zip(&acc).for_each(|(o, a)| *o = (a / m as f64) as f32);
    });
    // Φ_n = I_n − Ψ, in place.
    frames.par_chunks_mut(n).for_each(|col| col.iter_mut().zip(&mean).for_each(|(v, &mu)| *v -= mu));

    // Eq. 16: L = AᵀA (M × M) as one f32 matrix product (as numpy's float32 gram-trick peer does;
    // faer's blocked kernels accumulate in registers, so the sum over N pixels stays accurate),
    // then widened to f64 for the eigen decomposition.
    // L is symmetric: only its lower triangle is computed (half the flops, as BLAS's syrk).
    let a = MatRef::from_column_major_slice(&frames, n, m);
    let mut gram32 = Mat::<f32>::zeros(m, m);
    triangular::matmul(
        gram32.as_mut(),
        BlockStructure::TriangularLower,
        Accum::Replace,
        a.transpose(),
        BlockStructure::Rectangular,
        a,
        BlockStructure::Rectangular,
        1.0,
        par(),
    );
    let gram = Mat::<f64>::from_fn(m, m, |i, j| f64::from(gram32[(i.max(j), i.min(j))]));
    drop(gram32);

    let dec = decompose(&gram, max_components)?;
    drop(gram);

    // Eq. 17: eigenfire_l = Σ_n V_ln Φ_n, normalised (eq. 14).
    let mut eigenvectors = vec![0.0_f32; n * dec.e];
    if dec.e > 0 {
        lift(MatMut::from_column_major_slice_mut(&mut eigenvectors, n, dec.e), Accum::Replace, a, dec.v_scaled.as_ref());
    }
    release_in_background(frames);
    finish(width, height, mean, eigenvectors, &dec, sources)
}

/// Pixels per frame `N` and frames `M` of a database, checked: frames not empty, `M ≥ 2`.
pub(crate) fn database_shape(width: u32, height: u32, sources: &[FrameRef]) -> Result<(usize, usize), String> {
    let n = width as usize * height as usize;
    let m = sources.len();
    if n == 0 {
        return Err("the frames are empty (0 pixels)".into());
    }
    if m < 2 {
        return Err(format!("PCA needs at least 2 frames, got {m}"));
    }
    Ok((n, m))
}

/// The kept eigenpairs of the Gram matrix `L` (eq. 16).
pub(crate) struct Decomposition {
    /// Eigenfires kept, `E`.
    pub e: usize,
    /// Eigenvalues μ_l of `L`, descending.
    pub mus: Vec<f64>,
    /// `V_E Λ^{-1/2}` (`M × E`), the lift's right factor (eq. 17).
    pub v_scaled: Mat<f32>,
    /// `V_E`, eigenvector `l` at `[l·M..(l+1)·M]`.
    pub v_kept: Vec<f64>,
}

/// Eigen-decomposes the Gram matrix (its lower triangle is read), keeps every meaningful
/// eigenpair (or the first `max_components`), in descending order with a deterministic sign.
pub(crate) fn decompose(gram: &Mat<f64>, max_components: usize) -> Result<Decomposition, String> {
    let m = gram.nrows();
    let eig = gram.self_adjoint_eigen(Side::Lower).map_err(|e| format!("eigen decomposition failed: {e:?}"))?;
    let s = eig.S().column_vector();
    let v = eig.U();
    // Descending order; faer returns them ascending.
    let mut order: Vec<usize> = (0..m).collect();
    order.sort_by(|&x, &y| s[y].total_cmp(&s[x]));
    let mu_max = s[order[0]];
    if mu_max.is_nan() || mu_max <= 0.0 {
        return Err("all frames are identical: there is no variation to analyse".into());
    }
    let available = order.iter().take(m - 1).filter(|&&i| s[i] > mu_max * RELATIVE_EIGENVALUE_FLOOR).count();
    let e = if max_components == 0 { available } else { max_components.min(available) };

    // Scaled eigenvectors V_E Λ^{-1/2}, with a deterministic sign (largest entry positive).
    let mut v_scaled = Mat::<f32>::zeros(m, e);
    let mut v_kept = vec![0.0_f64; m * e];
    let mut mus = Vec::with_capacity(e);
    for (l, &i) in order.iter().take(e).enumerate() {
        let mu = s[i];
        let col = v.col(i);
        let (mut big, mut sign) = (0.0_f64, 1.0_f64);
        for r in 0..m {
            if col[r].abs() > big {
                big = col[r].abs();
                sign = col[r].signum();
            }
        }
        for r in 0..m {
            let x = col[r] * sign;
            v_kept[l * m + r] = x;
            v_scaled[(r, l)] = (x / mu.sqrt()) as f32;
        }
        mus.push(mu);
    }

    Ok(Decomposition { e, mus, v_scaled, v_kept })
}

/// Normalises the lifted eigenfires (eq. 14) and forms the training weights
/// `ω_l(n) = u_lᵀ Φ_n = √μ_l v_l(n)` (eq. 18).
pub(crate) fn finish(
    width: u32,
    height: u32,
    mean: Vec<f32>,
    mut eigenvectors: Vec<f32>,
    dec: &Decomposition,
    sources: Vec<FrameRef>,
) -> Result<Database, String> {
    let n = width as usize * height as usize;
    let (m, e, mus, v_kept) = (sources.len(), dec.e, &dec.mus, &dec.v_kept);
    eigenvectors.par_chunks_mut(n).for_each(|u| {
        let norm = sum_of_squares(u).sqrt();
        if norm > 0.0 {
            // One division per eigenfire, not per pixel (f64 division is 4–5× a multiply).
            let inv = 1.0 / norm;
            u.iter_mut().for_each(|x| *x = (f64::from(*x) * inv) as f32);
        }
    });

    // Training weights ω_l(n) = u_lᵀ Φ_n = √μ_l v_l(n).
    let mut weights = vec![0.0_f32; m * e];
    for (row, w) in weights.chunks_mut(e.max(1)).enumerate().take(m) {
        for l in 0..e {
            w[l] = (mus[l].sqrt() * v_kept[l * m + row]) as f32;
        }
    }
    let eigenvalues = mus.iter().map(|mu| mu / m as f64).collect();
    let basis = Basis { width, height, mean, eigenvectors, eigenvalues, sources };
    let weights = Weights::new(m, e, weights).ok_or("weights size mismatch")?;
    Ok(Database { basis, weights })
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

/// Eq. 18 for many frames at once: the weights `Ωᵀ = U_Eᵀ (I − Ψ)` of the frames in `frames`
/// (`F` images of the basis size, one after another), with the first `e` eigenfires.
/// Returns `F × e` row-major weights.
pub fn project(basis: &Basis, frames: &[f32], e: usize) -> Result<Weights, String> {
    let n = basis.pixels();
    if e > basis.components() {
        return Err(format!("{e} components asked, the basis has {}", basis.components()));
    }
    if n == 0 || !frames.len().is_multiple_of(n) {
        return Err(format!("frame data of {} samples is not a whole number of {n}-sample frames", frames.len()));
    }
    let f = frames.len() / n;
    let mut phi = frames.to_vec();
    phi.par_chunks_mut(n).for_each(|col| col.iter_mut().zip(&basis.mean).for_each(|(v, &mu)| *v -= mu));
    let mut out = vec![0.0_f32; f * e];
    if e > 0 && f > 0 {
        let u = MatRef::from_column_major_slice(&basis.eigenvectors[..n * e], n, e);
        let phi = MatRef::from_column_major_slice(&phi, n, f);
        let dst = MatMut::from_column_major_slice_mut(&mut out, e, f);
        matmul(dst, Accum::Replace, u.transpose(), phi, 1.0, par());
    }
    Weights::new(f, e, out).ok_or_else(|| "weights size mismatch".to_string())
}

/// Eq. 22 for many frames as one matrix product: `I = U_E Ω + Ψ` for every row of `weights`,
/// using its first `e` columns. Returns the images' samples one after another (`rows × N`).
pub fn reconstruct(basis: &Basis, weights: &Weights, e: usize) -> Result<Vec<f32>, String> {
    let n = basis.pixels();
    if e > basis.components() || e > weights.components {
        return Err(format!("{e} components asked; the basis has {} and the weights {}", basis.components(), weights.components));
    }
    let f = weights.frames;
    let mut out: Vec<f32> = Vec::with_capacity(n * f);
    for _ in 0..f {
        out.extend_from_slice(&basis.mean);
    }
    if e > 0 && f > 0 {
        let u = MatRef::from_column_major_slice(&basis.eigenvectors[..n * e], n, e);
        let w = MatRef::from_column_major_slice(&weights.data, weights.components, f).subrows(0, e);
        let dst = MatMut::from_column_major_slice_mut(&mut out, n, f);
        lift(dst, Accum::Add, u, w);
    }
    Ok(out)
}

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

fn check_frame(img: &Image, size: (u32, u32), i: usize, port: &str) -> Result<(), NodeError> {
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

impl Cook for Eigenfires {
    fn cook(self, ctx: &CookCtx) -> Result<EigenfiresOut, NodeError> {
        let clips: [(&str, &Clip); 3] = [
            (port!(Eigenfires, clip1), &*self.clip1),
            (port!(Eigenfires, clip2), &*self.clip2),
            (port!(Eigenfires, clip3), &*self.clip3),
        ];
        let clip1 = port!(Eigenfires, clip1);
        if self.clip1.is_empty() {
            return Err(NodeError::port(clip1, "the clip has no frames"));
        }
        let first = self.clip1.image(0, ctx).map_err(|e| NodeError::port(clip1, e.to_string()))?;
        let size = first.size();
        let n = size.0 as usize * size.1 as usize;
        let m: usize = clips.iter().map(|(_, c)| c.len()).sum();
        let total = n.checked_mul(m).ok_or_else(|| NodeError::msg("database too large"))?;
        let max_components = self.max_components;
        let memory = self.memory_mb.saturating_mul(1 << 20);
        if total.saturating_mul(4) > memory {
            // Two blocks in memory: at most half the budget each, and no more than BLOCK_BYTES.
            let block = (BLOCK_BYTES.min(memory / 2) / (n * 4)).max(1);
            return train_from_clips(&clips, size, max_components, block, ctx).map(EigenfiresOut::from);
        }
        let mut data = vec![0.0_f32; total];
        let mut sources = Vec::with_capacity(m);
        let mut offset = 0;
        for (k, (port, clip)) in clips.iter().enumerate() {
            let len = clip.len();
            gather_frames(clip, size, &mut data[offset * n..(offset + len) * n], port, ctx)?;
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

/// [`crate::pca_blocks::train_blocks`] over the frames of the training clips (named by their
/// ports), read block by block.
fn train_from_clips(
    clips: &[(&str, &Clip)],
    size: (u32, u32),
    max_components: usize,
    block: usize,
    ctx: &CookCtx,
) -> Result<Database, NodeError> {
    let n = size.0 as usize * size.1 as usize;
    let mut starts = Vec::with_capacity(clips.len());
    let mut sources = Vec::new();
    for (k, (_, clip)) in clips.iter().enumerate() {
        starts.push(sources.len());
        sources.extend((0..clip.len()).map(|f| FrameRef { clip: k as u32, index: f as u32 }));
    }
    let read = |r: std::ops::Range<usize>, out: &mut [f32]| -> Result<(), String> {
        ctx.check_cancel().map_err(|e| e.to_string())?;
        out.par_chunks_mut(n).enumerate().try_for_each(|(j, dst)| {
            let g = r.start + j;
            let k = starts.partition_point(|&s| s <= g) - 1;
            let (port, clip) = clips[k];
            let img = clip.image(g - starts[k], ctx).map_err(|e| format!("{port}: {e}"))?;
            check_frame(&img, size, g - starts[k], port).map_err(|e| e.to_string())?;
            dst.copy_from_slice(img.data());
            Ok(())
        })
    };
    let scratch = ctx.settings().cache_dir.clone().unwrap_or_else(std::env::temp_dir);
    let progress = |done: usize, total: usize| ctx.frame_progress(done, total);
    let source = crate::pca_blocks::BlockSource { read: &read, scratch: Some(&scratch), progress: &progress };
    crate::pca_blocks::train_blocks(size.0, size.1, sources, max_components, block, &source)
        .map_err(|m| NodeError::port(port!(Eigenfires, clip1), m))
}

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
    pub struct ProjectOut {
        /// Frames × components weights.
        weights: Arc<Weights>,
    }
}

/// Frames per batch while projecting a clip.
const PROJECT_BATCH: usize = 256;

impl Cook for Project {
    fn cook(self, ctx: &CookCtx) -> Result<ProjectOut, NodeError> {
        let (basis, clip) = (&*self.basis, &*self.clip);
        let port = port!(Project, clip);
        let e = components_to_use(self.components, basis.components(), port!(Project, components))?;
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
                check_frame(&img, (basis.width, basis.height), start + k, port)?;
                dst.copy_from_slice(img.data());
                Ok::<_, NodeError>(())
            })?;
            let w = project(basis, &frames, e).map_err(|m| NodeError::port(port, m))?;
            data.extend_from_slice(&w.data);
            ctx.frame_progress(end, clip.len());
            start = end;
        }
        let w = Weights::new(clip.len(), e, data).ok_or_else(|| NodeError::msg("weights size mismatch"))?;
        Ok(ProjectOut { weights: Arc::new(w) })
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
    pub struct ReconstructOut {
        /// The reconstructed gray frames.
        clip: ClipOf<Arc<Image>>,
    }
}

impl Cook for Reconstruct {
    fn cook(self, _: &CookCtx) -> Result<ReconstructOut, NodeError> {
        let (basis, weights) = (&*self.basis, &*self.weights);
        if weights.frames == 0 {
            return Err(NodeError::port(port!(Reconstruct, weights), "there are no rows of weights to reconstruct"));
        }
        let components = port!(Reconstruct, components);
        let e = components_to_use(self.components, basis.components().min(weights.components), components)?;
        let samples = reconstruct(basis, weights, e).map_err(|m| NodeError::port(components, m))?;
        let clip = samples_to_clip(basis, samples, self.clamp, self.fps)?;
        Ok(ReconstructOut { clip: ClipOf::new(clip) })
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A deterministic pseudo-random generator for test data.
    pub fn lcg(seed: &mut u64) -> f32 {
        *seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((*seed >> 40) as f32) / (1u64 << 24) as f32
    }

    /// `m` random gray frames of `w × h` (one after another).
    pub fn random_frames(w: u32, h: u32, m: usize, seed: u64) -> Vec<f32> {
        let mut s = seed;
        (0..w as usize * h as usize * m).map(|_| lcg(&mut s)).collect()
    }

    pub fn sources(m: usize) -> Vec<FrameRef> {
        (0..m).map(|i| FrameRef { clip: 0, index: i as u32 }).collect()
    }

    #[test]
    fn out_of_core_training_from_clips_matches_the_in_memory_cook() {
        let (w, h) = (6u32, 5u32);
        let n = (w * h) as usize;
        let frames = random_frames(w, h, 23, 4);
        let img = |f: usize| {
            Value::Image(Arc::new(Image::from_vec(w, h, Channels::Gray, frames[f * n..(f + 1) * n].to_vec()).unwrap()))
        };
        let clip1 = Clip::from_frames(PortType::Image, 24.0, (0..15).map(img).collect());
        let empty = Clip::from_frames(PortType::Image, 24.0, Vec::new());
        let clip3 = Clip::from_frames(PortType::Image, 24.0, (15..23).map(img).collect());
        let clips = [("clip1", &clip1), ("clip2", &empty), ("clip3", &clip3)];
        let ctx = CookCtx::new();
        let out = train_from_clips(&clips, (w, h), 0, 4, &ctx).unwrap();
        let b = &out.basis;
        let whole = train(w, h, frames.clone(), sources(23), 0).unwrap();
        assert_eq!(b.components(), whole.basis.components());
        assert_eq!(b.sources[15], FrameRef { clip: 2, index: 0 }, "frames keep their clip and index");
        for k in 0..b.components() {
            let cos: f64 = b
                .eigenvector(k)
                .unwrap()
                .iter()
                .zip(whole.basis.eigenvector(k).unwrap())
                .map(|(x, y)| f64::from(*x) * f64::from(*y))
                .sum();
            assert!(cos > 1.0 - 5e-7, "eigenfire {k}: cos {cos}");
        }
        // A frame of the wrong size is reported with its clip and index.
        let odd =
            Clip::from_frames(PortType::Image, 24.0, vec![img(0), Value::Image(Arc::new(Image::new(2, 2, Channels::Gray)))]);
        let err = train_from_clips(&[("clip1", &odd)], (w, h), 0, 1, &ctx).unwrap_err().to_string();
        assert!(err.contains("frame 1 is 2x2"), "{err}");
    }

    #[test]
    fn full_rank_reconstruction_equals_the_input() {
        let (w, h, m) = (9, 7, 12);
        let frames = random_frames(w, h, m, 1);
        let db = train(w, h, frames.clone(), sources(m), 0).unwrap();
        assert_eq!(db.basis.components(), m - 1, "E = M − 1");
        let rec = reconstruct(&db.basis, &db.weights, m - 1).unwrap();
        let err: f64 = rec.iter().zip(&frames).map(|(a, b)| f64::from(a - b).powi(2)).sum::<f64>().sqrt();
        let norm: f64 = frames.iter().map(|a| f64::from(*a).powi(2)).sum::<f64>().sqrt();
        assert!(err / norm < 1e-3, "relative error {}", err / norm);
    }

    #[test]
    fn the_banded_lift_equals_one_product_and_covers_a_partial_last_band() {
        let (n, m, e) = (2 * LIFT_BAND_ROWS + 37, 6, 4);
        let a_data = random_frames(n as u32, 1, m, 11);
        let v_data = random_frames(m as u32, 1, e, 12);
        let a = MatRef::from_column_major_slice(&a_data, n, m);
        let v = MatRef::from_column_major_slice(&v_data, m, e);
        let mut banded = vec![f32::NAN; n * e];
        lift(MatMut::from_column_major_slice_mut(&mut banded, n, e), Accum::Replace, a, v);
        let mut whole = vec![0.0_f32; n * e];
        matmul(MatMut::from_column_major_slice_mut(&mut whole, n, e), Accum::Replace, a, v, 1.0, Par::Seq);
        for (i, (x, y)) in banded.iter().zip(&whole).enumerate() {
            assert!((x - y).abs() <= 1e-5 * y.abs().max(1.0), "entry {i}: {x} vs {y}");
        }
    }

    #[test]
    fn eigenvectors_are_orthonormal_and_eigenvalues_descend() {
        let (w, h, m) = (10, 10, 20);
        let db = train(w, h, random_frames(w, h, m, 2), sources(m), 0).unwrap();
        let b = &db.basis;
        for k in 0..b.components() {
            for l in 0..=k {
                let dot: f64 = b
                    .eigenvector(k)
                    .unwrap()
                    .iter()
                    .zip(b.eigenvector(l).unwrap())
                    .map(|(x, y)| f64::from(*x) * f64::from(*y))
                    .sum();
                let want = if k == l { 1.0 } else { 0.0 };
                assert!((dot - want).abs() < 1e-4, "u{k}·u{l} = {dot}");
            }
        }
        assert!(b.eigenvalues.windows(2).all(|p| p[0] >= p[1]), "{:?}", b.eigenvalues);
        assert!(b.eigenvalues.iter().all(|&l| l > 0.0));
    }

    #[test]
    fn training_weights_equal_their_projection() {
        let (w, h, m) = (8, 6, 15);
        let frames = random_frames(w, h, m, 3);
        let db = train(w, h, frames.clone(), sources(m), 0).unwrap();
        let projected = project(&db.basis, &frames, db.basis.components()).unwrap();
        let scale = db.weights.data.iter().fold(0.0_f32, |a, v| a.max(v.abs()));
        for (a, b) in projected.data.iter().zip(&db.weights.data) {
            assert!((a - b).abs() < 1e-4 * scale, "{a} vs {b}");
        }
    }

    #[test]
    fn eigenvalues_are_the_variance_along_each_eigenfire() {
        // Eq. 13: λ_k = (1/M) Σ (u_kᵀ Φ_n)².
        let (w, h, m) = (6, 6, 10);
        let db = train(w, h, random_frames(w, h, m, 4), sources(m), 0).unwrap();
        for k in 0..db.basis.components() {
            let var: f64 = (0..m).map(|n| f64::from(db.weights.row(n).unwrap()[k]).powi(2)).sum::<f64>() / m as f64;
            assert!((var - db.basis.eigenvalues[k]).abs() < 1e-4 * db.basis.eigenvalues[0], "k={k}");
        }
    }

    #[test]
    fn max_components_caps_and_repeated_frames_reduce_the_rank() {
        let (w, h) = (5, 5);
        let one = random_frames(w, h, 3, 5);
        let mut frames = one.clone();
        frames.extend_from_slice(&one); // 6 frames, only 3 distinct: rank 2
        let db = train(w, h, frames, sources(6), 0).unwrap();
        assert_eq!(db.basis.components(), 2);
        let db = train(w, h, random_frames(w, h, 10, 6), sources(10), 4).unwrap();
        assert_eq!(db.basis.components(), 4);
        assert_eq!(db.weights.components, 4);
    }

    #[test]
    fn identical_frames_and_a_single_frame_are_errors() {
        let one = random_frames(4, 4, 1, 7);
        assert!(train(4, 4, one.clone(), sources(1), 0).unwrap_err().contains("at least 2"));
        let twice = [one.clone(), one].concat();
        assert!(train(4, 4, twice, sources(2), 0).unwrap_err().contains("identical"));
    }

    #[test]
    fn reconstruction_with_fewer_components_is_the_projection_onto_them() {
        let (w, h, m) = (7, 7, 10);
        let frames = random_frames(w, h, m, 8);
        let db = train(w, h, frames, sources(m), 0).unwrap();
        let rec = reconstruct(&db.basis, &db.weights, 3).unwrap();
        // Projecting the 3-component reconstruction gives back the first 3 weights.
        let back = project(&db.basis, &rec, 3).unwrap();
        for f in 0..m {
            for k in 0..3 {
                assert!((back.row(f).unwrap()[k] - db.weights.row(f).unwrap()[k]).abs() < 1e-3);
            }
        }
        assert!(reconstruct(&db.basis, &db.weights, m).is_err());
    }
}
