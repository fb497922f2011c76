//! `volume.preview`: a quick look at a volume before the volume renderer: an orthographic view
//! along −z through the density and the flame, composited front to back (Porter & Duff "over"
//! along each ray, as Kajiya & Von Herzen 1984's emission–absorption model reduces to without
//! scattering). Smoke is lit by a uniform ambient light, the flame glows through a fire ramp.

use std::sync::Arc;

use glam::{IVec3, Vec3};
use pyrograph_core::{Channels, Cook, CookCtx, Image, NodeError, port};
use rayon::prelude::*;

use crate::grid::{VOXELS, Volume, brick_of, voxel};

pyrograph_core::node! {
    /// A quick front view of a volume: each pixel looks along −z through the voxels below it, the smoke
    /// absorbing (Beer–Lambert, `extinction` per unit density per world unit) and lit by a uniform ambient
    /// light, the flame glowing through a fire ramp (dark red, orange, yellow, white) scaled by `exposure`,
    /// composited front to back (the emission–absorption model of Kajiya & Von Herzen 1984 without
    /// scattering or shadows). For thumbnails and checks; volume.render lights and shadows volumes.
    #[node("volume.preview", "Volume", PerFrame)]
    pub struct Preview {
        /// The volume (volume.simulate, volume.load_vdb).
        volume: Arc<Volume>,
        /// Image width in pixels.
        #[range(1, 16384)]
        width: u32 = 192,
        /// Image height in pixels.
        #[range(1, 16384)]
        height: u32 = 256,
        /// World point at the image's centre (its z is ignored).
        center: [f32; 3] = [0.0, 1.5, 0.0],
        /// World height the image spans.
        #[range(1e-4, 1e6)]
        size: f32 = 4.0,
        /// Smoke extinction per unit of density per world unit.
        #[range(0.0, 1e6)]
        extinction: f32 = 8.0,
        /// Brightness of the ambient light on the smoke.
        #[range(0.0, 1e3)]
        ambient: f32 = 0.35,
        /// Brightness of the flame: light emitted per world unit of flame 1.
        #[range(0.0, 1e6)]
        exposure: f32 = 8.0,
        /// Background colour behind the volume.
        background: [f32; 4] = [0.0, 0.0, 0.0, 1.0],
    }
    /// The view, RGBA.
    -> image: Arc<Image>
}

impl Cook for Preview {
    fn cook(self, _: &CookCtx) -> Result<Arc<Image>, NodeError> {
        if self.center.iter().chain(&self.background).any(|v| !v.is_finite()) {
            return Err(NodeError::port(port!(Preview, center), "the centre and background must be finite"));
        }
        let view = View {
            width: self.width,
            height: self.height,
            center: Vec3::from_array(self.center),
            size: self.size,
            extinction: self.extinction,
            ambient: self.ambient,
            exposure: self.exposure,
            background: self.background,
        };
        Ok(Arc::new(preview(&self.volume, &view)))
    }
}

/// What a preview shows and how.
#[derive(Clone, Copy, Debug)]
pub struct View {
    /// Pixels across.
    pub width: u32,
    /// Pixels down.
    pub height: u32,
    /// World point at the centre.
    pub center: Vec3,
    /// World height spanned.
    pub size: f32,
    /// Smoke extinction per density per world unit.
    pub extinction: f32,
    /// Ambient light on the smoke.
    pub ambient: f32,
    /// Flame brightness.
    pub exposure: f32,
    /// Background.
    pub background: [f32; 4],
}

/// Fire colours from dark red to white over a flame value of 0 to 1 and beyond.
pub fn fire_ramp(f: f32) -> Vec3 {
    let keys = [
        (0.0, Vec3::ZERO),
        (0.15, Vec3::new(0.5, 0.05, 0.0)),
        (0.4, Vec3::new(1.0, 0.35, 0.02)),
        (0.7, Vec3::new(1.0, 0.75, 0.2)),
        (1.0, Vec3::new(1.0, 0.95, 0.8)),
    ];
    let f = f.max(0.0);
    for w in keys.windows(2) {
        if f <= w[1].0 {
            let t = (f - w[0].0) / (w[1].0 - w[0].0);
            return w[0].1.lerp(w[1].1, t);
        }
    }
    keys[keys.len() - 1].1 * f
}

/// The view of `v`.
pub fn preview(v: &Volume, view: &View) -> Image {
    let (w, h) = (view.width as usize, view.height as usize);
    let mut data = vec![0.0f32; w * h * 4];
    let flame = v.scalar("flame");
    let density = v.scalar("density");
    let bounds = v.topology.voxel_bounds();
    let vs = v.transform.voxel_size as f32;
    let pixel = view.size / view.height as f32;
    data.par_chunks_mut(w * 4).enumerate().for_each(|(row, out)| {
        for (col, px) in out.chunks_mut(4).enumerate() {
            let world = view.center
                + Vec3::new((col as f32 + 0.5 - w as f32 / 2.0) * pixel, (h as f32 / 2.0 - row as f32 - 0.5) * pixel, 0.0);
            let idx = v.transform.to_index(world).round().as_ivec3();
            let (mut colour, mut transmit) = (Vec3::ZERO, 1.0f32);
            if let Some((lo, hi)) = bounds.filter(|(lo, hi)| idx.x >= lo.x && idx.x <= hi.x && idx.y >= lo.y && idx.y <= hi.y) {
                let mut z = hi.z;
                while z >= lo.z && transmit > 1e-4 {
                    let at = IVec3::new(idx.x, idx.y, z);
                    let Some(b) = v.topology.find(brick_of(at)) else {
                        z = (z & !7) - 1;
                        continue;
                    };
                    let l = at & IVec3::splat(7);
                    let i = b as usize * VOXELS + voxel(l.x as usize, l.y as usize, l.z as usize);
                    let d = density.map_or(0.0, |d| d[i].max(0.0));
                    let f = flame.map_or(0.0, |f| f[i].max(0.0));
                    let absorb = 1.0 - (-view.extinction * d * vs).exp();
                    colour += transmit * (Vec3::splat(view.ambient) * absorb + fire_ramp(f) * view.exposure * vs);
                    transmit *= 1.0 - absorb;
                    z -= 1;
                }
            }
            let bg = Vec3::new(view.background[0], view.background[1], view.background[2]);
            let c = colour + bg * transmit * view.background[3];
            px.copy_from_slice(&[c.x, c.y, c.z, 1.0 - transmit * (1.0 - view.background[3])]);
        }
    });
    Image::from_vec(view.width, view.height, Channels::Rgba, data)
        .unwrap_or_else(|| Image::new(view.width, view.height, Channels::Rgba))
}
