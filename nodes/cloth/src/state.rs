//! The cloth-flame state value (mass-spring flame project 2019, after Balci & Foroosh 2006).

use std::hash::Hash;

use pyrograph_core::fingerprint::{Fingerprinter, hash_f32s};
use pyrograph_core::{TypeInfo, ValueType};

/// Mass-spring flames at one moment (mass-spring flame project 2019, after Balci & Foroosh 2006):
/// `flames` cloths of `width × height` masses each, in flame-local coordinates (x across, y up,
/// z toward the viewer) around a world root, so a renderer can turn each one to face its camera.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct ClothState {
    /// Masses per row.
    pub width: u32,
    /// Rows of masses; row 0 is the pinned bottom row.
    pub height: u32,
    /// World position of each flame's root (the centre of its pinned bottom row).
    pub roots: Vec<[f32; 3]>,
    /// Per-flame seed (a renderer picks a built-in texture from it).
    pub seeds: Vec<u32>,
    /// Local mass positions, flame-major, then row-major from the bottom row:
    /// `flames × height × width`.
    pub positions: Vec<[f32; 3]>,
    /// Simulation time in seconds.
    pub time: f32,
}

impl ClothState {
    /// Number of flames.
    pub fn flames(&self) -> usize {
        self.roots.len()
    }

    /// The local positions of flame `i`, `None` past the last.
    pub fn flame(&self, i: usize) -> Option<&[[f32; 3]]> {
        let n = self.width as usize * self.height as usize;
        self.positions.get(i * n..(i + 1) * n)
    }
}

impl ValueType for ClothState {
    const INFO: &'static TypeInfo = &TypeInfo {
        name: "ClothState",
        doc: "Mass-spring flame cloths at one moment (mass-spring flame project 2019).",
        color: [250, 150, 90],
    };

    fn hash_into(&self, h: &mut Fingerprinter) {
        (self.width, self.height, self.roots.len(), &self.seeds, self.positions.len(), self.time.to_bits()).hash(h);
        self.roots.iter().chain(&self.positions).for_each(|p| hash_f32s(h, p));
    }

    fn byte_size(&self) -> usize {
        (self.roots.len() + self.positions.len()) * 12 + self.seeds.len() * 4
    }

    fn summary(&self) -> String {
        format!("ClothState {} flames of {}x{} masses", self.flames(), self.width, self.height)
    }
}
