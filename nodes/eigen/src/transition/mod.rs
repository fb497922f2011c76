//! Recognition and motion transitions in fire space (thesis §4.5 eq. 21, §5.1.1 low-pass filter,
//! §5.1.2.1 Direct Bridging, §5.1.2.2 End Growing Connection, Algorithm 1).
//!
//! Every distance is eq. 21, `D_ab = ‖Ω_a − Ω_b‖`, over the first `e` components (the E for
//! detection). Frames are rows of the database's training weights.
//!
//! One file per algorithm; [`nodes`] adapts them to node types.

mod bridging;
mod distance;
mod end_growing;
mod lowpass;
pub mod nodes;

pub use bridging::direct_bridging;
pub use distance::{check_range, distance, distances_to, exclusion_mask, frame_distance, recognize};
pub use end_growing::{
    EndGrowing, ThetaMin, clip_thresholds, end_exclusion, end_growing, end_growing_adaptive, largest_jump, optimize_path,
    parse_thresholds,
};
pub use lowpass::{Kernel, lowpass_kernel, lowpass_transition};

#[cfg(test)]
mod tests;
