//! Rendering the generic flame model (Stich & Magnor §3.1–3.2): the appearance is the mean
//! normalized image plus the eigenflames weighted by the row's appearance parameters; the
//! deformation is the inverse normalization, with the sparsely sampled path and width parameters
//! interpolated by natural cubic splines, the height scaling the main axis.

use pyrograph_core::{Channels, Image};
use pyrograph_nodes_imaging::color::ColorRamp;
use rayon::prelude::*;

use super::fit::{MIN_WIDTH, knot};
use super::shape::Spline;
use crate::values::FlameModel;

/// Controls of the renderer (§5.1: offsets on the path, and scaling of height, width and size).
#[derive(Clone, Debug, PartialEq)]
pub struct RenderSettings {
    /// Output size; 0 takes the fitted frame's width / height.
    pub size: (u32, u32),
    /// Overall scale of the flame about its base.
    pub scale: f64,
    /// Path offset at the tip, as a fraction of the flame height, growing with the square of the
    /// height (a bent flame, §5.1). Positive bends to the right of an upright flame.
    pub bend: f64,
    /// Frames over which the bend ramps in from 0 (0 = the full bend from the first frame).
    pub bend_ramp: usize,
    /// Multiplies the height parameter.
    pub height_scale: f64,
    /// Multiplies the width parameters.
    pub width_scale: f64,
    /// Scale the fitted picture to fit inside the output (centred, bottom on the bottom), so a
    /// flame keeps its size in the output whatever the footage's resolution or crop; `scale`
    /// applies on top.
    pub fit_to_output: bool,
}

impl Default for RenderSettings {
    fn default() -> Self {
        RenderSettings {
            size: (0, 0),
            scale: 1.0,
            bend: 0.0,
            bend_ramp: 0,
            height_scale: 1.0,
            width_scale: 1.0,
            fit_to_output: false,
        }
    }
}

/// Entries of the path / width lookup tables over the normalized height range.
const TABLE: usize = 1024;

/// Checks that a parameter row fits the model.
pub fn check_row(model: &FlameModel, row: &[f64]) -> Result<(), String> {
    if row.len() != model.dim() {
        return Err(format!(
            "a parameter row has {} values but the model needs {} (N_p {} + N_w {} + N_e {} + height)",
            row.len(),
            model.dim(),
            model.path_samples,
            model.width_samples,
            model.eigenflames
        ));
    }
    let n = model.width as usize * model.height as usize;
    if model.mean.len() != n || model.basis.len() < n * model.eigenflames {
        return Err("the flame model's eigenflames do not match its normalized image size".into());
    }
    if row.iter().any(|v| !v.is_finite()) {
        return Err("a parameter row holds a non-finite value".into());
    }
    Ok(())
}

/// The normalized appearance of a row: mean + Σ eig_k · eigenflame_k (§3.2), clamped at 0.
pub fn appearance(model: &FlameModel, row: &[f64]) -> Vec<f32> {
    let n = model.width as usize * model.height as usize;
    let off = model.path_samples + model.width_samples;
    let mut out = model.mean.clone();
    for k in 0..model.eigenflames {
        let w = row[off + k] as f32;
        let e = &model.basis[k * n..(k + 1) * n];
        out.iter_mut().zip(e).for_each(|(o, &b)| *o += w * b);
    }
    out.iter_mut().for_each(|v| *v = v.max(0.0));
    out
}

/// The bend (fraction of the height at the tip) of frame `index`.
pub fn bend_at(s: &RenderSettings, index: usize) -> f64 {
    if s.bend_ramp == 0 { s.bend } else { s.bend * (index as f64 / s.bend_ramp as f64).min(1.0) }
}

/// Renders one parameter row (frame `index`, for the bend ramp) as a gray image.
pub fn render_frame(model: &FlameModel, row: &[f64], s: &RenderSettings, index: usize) -> Result<Image, String> {
    check_row(model, row)?;
    let (fw, fh) = model.frame_size;
    let out_w = if s.size.0 == 0 { fw } else { s.size.0 };
    let out_h = if s.size.1 == 0 { fh } else { s.size.1 };
    if out_w == 0 || out_h == 0 {
        return Err("the output size is 0 (the model has no frame size; set width and height)".into());
    }
    if !(s.scale > 0.0 && s.height_scale > 0.0 && s.width_scale > 0.0) {
        return Err("scale, height_scale and width_scale must be positive".into());
    }
    let (np, nw, ne) = (model.path_samples, model.width_samples, model.eigenflames);
    let height = row[np + nw + ne] * s.height_scale;
    if height <= 0.0 {
        return Err(format!("the height parameter must be positive, got {height}"));
    }
    let img = appearance(model, row);
    let bend = bend_at(s, index) * height;
    let path: Vec<f64> = (0..np).map(|k| row[k] + bend * knot(k, np).powi(2)).collect();
    let width: Vec<f64> = (0..nw).map(|k| row[np + k] * s.width_scale).collect();
    let (path, width) = (Spline::new(&path), Spline::new(&width));
    let [v0, v1] = model.v_range;
    let span = (v1 - v0).max(1e-9);
    // Path and 1/width over the normalized height range.
    let table: Vec<(f32, f32)> = (0..=TABLE)
        .map(|i| {
            let v = v0 + span * i as f64 / TABLE as f64;
            (path.at(v) as f32, (1.0 / width.at(v).max(MIN_WIDTH)) as f32)
        })
        .collect();

    // Output pixel → fitted-frame coordinates: the anchor keeps its offset from the bottom centre
    // (times the fit's scale k when the fitted picture is fitted into the output).
    let k = if s.fit_to_output && fw > 0 && fh > 0 {
        (f64::from(out_w) / f64::from(fw)).min(f64::from(out_h) / f64::from(fh))
    } else {
        1.0
    };
    let anchor = [
        f64::from(out_w) / 2.0 + (model.anchor[0] - f64::from(fw) / 2.0) * k,
        f64::from(out_h) - (f64::from(fh) - model.anchor[1]) * k,
    ];
    let inv = 1.0 / (s.scale * k);
    let e = model.axis;
    let across = [-e[1], e[0]];
    let (nwid, nhgt) = (model.width as usize, model.height as usize);
    let u_ext = model.u_extent;
    // u → column, v → row (row 0 is the top, v1).
    let col_scale = (nwid as f64 / (2.0 * u_ext)) as f32;
    let col_off = (u_ext * nwid as f64 / (2.0 * u_ext) - 0.5) as f32;
    let row_scale = (nhgt as f64 / span) as f32;
    let tab_scale = TABLE as f64 / span;
    let inv_h = 1.0 / height;
    let (ex, ey, ax, ay) = (e[0] as f32, e[1] as f32, across[0] as f32, across[1] as f32);

    let mut data = vec![0.0_f32; out_w as usize * out_h as usize];
    data.par_chunks_mut(out_w as usize).enumerate().for_each(|(y, line)| {
        let dy = ((y as f64 + 0.5 - anchor[1]) * inv) as f32;
        for (x, o) in line.iter_mut().enumerate() {
            let dx = ((x as f64 + 0.5 - anchor[0]) * inv) as f32;
            let v = f64::from(dx * ex + dy * ey) * inv_h;
            if v <= v0 || v >= v1 {
                continue;
            }
            let tf = ((v - v0) * tab_scale) as f32;
            let ti = (tf as usize).min(TABLE - 1);
            let tt = tf - ti as f32;
            let (p0, iw0) = table[ti];
            let (p1, iw1) = table[ti + 1];
            let p = p0 + (p1 - p0) * tt;
            let iw = iw0 + (iw1 - iw0) * tt;
            let t = dx * ax + dy * ay;
            let u = (t - p) * iw;
            let cf = u * col_scale + col_off;
            let rf = ((v1 - v) as f32) * row_scale - 0.5;
            *o = bilinear(&img, nwid, nhgt, cf, rf);
        }
    });
    Image::from_vec(out_w, out_h, Channels::Gray, data).ok_or_else(|| "rendered frame has the wrong size".into())
}

/// Bilinear sample of a row-major image at fractional (column, row), zero outside.
#[inline]
fn bilinear(img: &[f32], w: usize, h: usize, cf: f32, rf: f32) -> f32 {
    if cf <= -1.0 || rf <= -1.0 || cf >= w as f32 || rf >= h as f32 {
        return 0.0;
    }
    let (fx, fy) = (cf.floor(), rf.floor());
    let (tx, ty) = (cf - fx, rf - fy);
    let (ix, iy) = (fx as isize, fy as isize);
    let at = |x: isize, y: isize| -> f32 {
        if x < 0 || y < 0 || x >= w as isize || y >= h as isize { 0.0 } else { img[y as usize * w + x as usize] }
    };
    let top = at(ix, iy) + (at(ix + 1, iy) - at(ix, iy)) * tx;
    let bottom = at(ix, iy + 1) + (at(ix + 1, iy + 1) - at(ix, iy + 1)) * tx;
    top + (bottom - top) * ty
}

pyrograph_core::choice! {
    /// How the alpha of the coloured output is set.
    pub enum Alpha {
        /// Alpha 1 everywhere (the ramp's black background stays).
        Opaque = "opaque",
        /// Alpha = clamped intensity (straight alpha), for compositing.
        Intensity = "intensity",
    }
}

/// Colours a gray flame through an intensity → colour transfer function (§5.1).
pub fn colorize(gray: &Image, ramp: &ColorRamp, exposure: f32, alpha: Alpha) -> Image {
    let mut data = vec![0.0_f32; gray.data().len() * 4];
    data.par_chunks_mut(4 * gray.width().max(1) as usize).zip(gray.data().par_chunks(gray.width().max(1) as usize)).for_each(
        |(dst, src)| {
            for (px, &g) in dst.chunks_exact_mut(4).zip(src) {
                let t = g * exposure;
                let [r, gg, b] = ramp.color_at(t);
                let a = match alpha {
                    Alpha::Opaque => 1.0,
                    Alpha::Intensity => t.clamp(0.0, 1.0),
                };
                px.copy_from_slice(&[r, gg, b, a]);
            }
        },
    );
    Image::from_vec(gray.width(), gray.height(), Channels::Rgba, data)
        .unwrap_or_else(|| Image::new(gray.width(), gray.height(), Channels::Rgba))
}
