//! The timeline ports shared by every node that makes a clip of its own: how many frames, at what
//! rate. Declared once, flattened into each node as its `frames` and `fps` ports.

crate::ports! {
    /// The length and rate of a clip a node makes (its `frames` and `fps` ports). A node with
    /// other defaults declares `timeline: Timeline = Timeline { frames: 96, fps: 24.0 }`.
    #[derive(PartialEq)]
    pub struct Timeline {
        /// Number of frames.
        #[range(1, 100_000)]
        frames: usize = 48,
        /// Frames per second.
        #[range(1.0, 240.0)]
        fps: f64 = 24.0,
    }
}
