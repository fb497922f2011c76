//! Test nodes shared by the core's integration tests.

use pyrograph_core::{Clip, ClipOf, Cook, CookCtx, NodeError, PortType, Value};

pyrograph_core::node! {
    /// A clip of floats 0, 1, 2, …
    #[node("test.ramp", "Test", Source)]
    pub struct Ramp {
        /// length
        #[range(0, 100_000)]
        frames: usize = 10,
    }
    /// the ramp
    -> clip: ClipOf<f64>
}

impl Cook for Ramp {
    fn cook(self, _: &CookCtx) -> Result<ClipOf<f64>, NodeError> {
        let frames = (0..self.frames).map(|f| Value::Float(f as f64)).collect();
        Ok(ClipOf::new(Clip::from_frames(PortType::Float, 24.0, frames)))
    }
}
