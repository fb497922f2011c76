//! Eigenfires training, projection and reconstruction (thesis §4.2, §4.3, §4.8; eq. 12–18, 22).
//!
//! Training follows Turk and Pentland's M×M trick: with the `M` mean-free frames as the columns
//! of `A` (`N × M`), the eigenvectors of the small Gram matrix `L = AᵀA` (eq. 16) give the
//! eigenfires `u_l = A v_l / √μ_l` (eq. 17), so the `N × N` covariance of eq. 15 is never built.
//! Memory stays near the data size: the frames (`N·M` floats) plus the eigenfires (`N·E`), and
//! `M × M` matrices in f64. `L` is accumulated in f64 over blocks of pixel rows, so the null
//! direction left by subtracting the mean (`E = M − 1`) is told apart from real small eigenvalues.
//!
//! The algorithms: training in memory ([`training`]) and out of core ([`blocks`]), projection and
//! reconstruction ([`projection`]); what the nodes share ([`clips`]) and the nodes ([`nodes`]).

pub mod blocks;
pub mod clips;
pub mod nodes;
pub mod projection;
mod simd;
pub mod training;

pub use blocks::{BlockSource, ReadFrames, train_blocks};
pub use clips::{ClipError, components_to_use, empty_clip, gather_frames, samples_to_clip, train_from_clips};
pub use nodes::{Eigenfires, EigenfiresOut, Project, Reconstruct};
pub use projection::{project, reconstruct};
pub use training::{Database, RELATIVE_EIGENVALUE_FLOOR, train};

#[cfg(test)]
pub(crate) mod tests;
