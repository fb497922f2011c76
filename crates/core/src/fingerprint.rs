//! Content fingerprints that key the evaluator's cache.

use std::collections::hash_map::DefaultHasher;
use std::hash::Hasher;

/// A deterministic 64-bit hasher (SipHash with fixed keys), stable within one build of pyrograph.
#[derive(Clone, Debug, Default)]
pub struct Fingerprinter(DefaultHasher);

impl Fingerprinter {
    /// A fresh hasher.
    pub fn new() -> Self {
        Fingerprinter(DefaultHasher::new())
    }
}

impl Hasher for Fingerprinter {
    fn finish(&self) -> u64 {
        self.0.finish()
    }
    fn write(&mut self, bytes: &[u8]) {
        self.0.write(bytes)
    }
}

/// Hashes float samples by their bit patterns, as one byte slice (much faster than per-float calls).
pub fn hash_f32s(h: &mut Fingerprinter, data: &[f32]) {
    h.write(bytemuck::cast_slice(data));
}
