//! The wind field value (Perry 1994 §3.2.3), as data the particle nodes evaluate.

use std::hash::Hash;
use std::sync::Arc;

use pyrograph_core::declare::{Anim, AnimError};
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
    /// Parameters that change over time (a gust, turbulence that rises), sampled at the time of
    /// each frame or simulation step; `None` for a wind that is the same at every frame.
    pub animation: Option<Arc<WindAnimation>>,
}

/// The animated parameters of a [`WindField`]: each, when set, replaces the field's constant
/// at the time it is sampled.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct WindAnimation {
    /// The constant large-scale wind `w_L` (when `large` is [`LargeWind::Constant`]).
    pub wind: Option<Anim<[f32; 3]>>,
    /// Flame noisiness `C`.
    pub noise_c: Option<Anim<f32>>,
    /// Convection coefficient `k_g`.
    pub k_g: Option<Anim<f32>>,
}

impl WindField {
    /// The field as it is at `frame` (fractional for sub-steps) of a clip at `fps`: every animated
    /// parameter sampled, no animation left. Errors name the wind field's port and the frame.
    pub fn at_frame(&self, frame: f64, fps: f64) -> Result<WindField, AnimError> {
        let Some(anim) = &self.animation else { return Ok(self.clone()) };
        let mut out = WindField { animation: None, ..self.clone() };
        if let (Some(w), LargeWind::Constant(v)) = (&anim.wind, &mut out.large) {
            *v = w.at(frame, fps)?;
        }
        if let Some(c) = &anim.noise_c {
            out.noise_c = c.at(frame, fps)?;
        }
        if let Some(k) = &anim.k_g {
            out.k_g = k.at(frame, fps)?;
        }
        Ok(out)
    }
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
            animation: None,
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
