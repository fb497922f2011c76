//! The wind field value (Perry 1994 §3.2.3), as data the particle nodes evaluate.

use std::hash::Hash;

use pyrograph_core::fingerprint::Fingerprinter;
use pyrograph_core::{TypeInfo, ValueType};

/// The large-scale part `w_L(p, t)` of a [`WindField`] (Perry 1994 §3.2.3, §3.4).
#[derive(Clone, Debug, PartialEq, Default)]
pub enum LargeWind {
    /// No large-scale wind.
    #[default]
    None,
    /// A constant wind vector.
    Constant([f32; 3]),
    /// A Rankine vortex around the vertical axis through `center`: tangential speed grows
    /// linearly to `strength` at `radius`, then falls off as `1/r`.
    Vortex {
        /// A point on the vortex axis.
        center: [f32; 3],
        /// Tangential speed at `radius` (positive: counter-clockwise seen from above).
        strength: f32,
        /// Core radius.
        radius: f32,
    },
    /// The wind felt by flames on an object moving with this velocity: its negative (§3.4).
    MovingObject([f32; 3]),
}

/// The wind `u∞(p, t) = −k_g g + w_L(p, t) + w_S(p, t)` of Perry 1994 §3.2.3, as data; the
/// particle nodes evaluate it. `w_S` is eq. 3.1: `((p − p(0))·ĵ) C ∇N(k_p p − k_s T ĵ)`.
#[derive(Clone, Debug, PartialEq)]
pub struct WindField {
    /// Gravity `g` (Perry: `−ĵ`).
    pub gravity: [f32; 3],
    /// Convection coefficient `k_g` (Perry: 1.0).
    pub k_g: f32,
    /// Large-scale wind `w_L`.
    pub large: LargeWind,
    /// Flame noisiness `C` of eq. 3.1.
    pub noise_c: f32,
    /// Inverse inter-flame cohesion `k_p`: the scale of positions in noise space.
    pub k_p: f32,
    /// Flame sampling `k_s`: how fast time moves down through the noise field (per frame).
    pub k_s: f32,
    /// Seed of the noise field.
    pub seed: u32,
    /// World length of one unit of the height factor of eq. 3.1 (the paper measures height in
    /// unit-time integration steps; smaller values bend flames more).
    pub height_unit: f32,
}

impl Default for WindField {
    fn default() -> Self {
        WindField {
            gravity: [0.0, -1.0, 0.0],
            k_g: 1.0,
            large: LargeWind::None,
            noise_c: 0.04,
            k_p: 1.0,
            k_s: 0.1,
            seed: 0,
            height_unit: 1.0,
        }
    }
}

impl ValueType for WindField {
    const INFO: &'static TypeInfo = &TypeInfo {
        name: "WindField",
        doc: "A wind field description (Perry 1994 §3.2.3), evaluated by the particle nodes.",
        color: [120, 160, 250],
    };

    fn hash_into(&self, h: &mut Fingerprinter) {
        format!("{self:?}").hash(h);
    }

    fn byte_size(&self) -> usize {
        std::mem::size_of::<WindField>()
    }

    fn summary(&self) -> String {
        format!("WindField k_g={} C={} k_p={} k_s={} w_L={:?}", self.k_g, self.noise_c, self.k_p, self.k_s, self.large)
    }
}
