//! `flame_model.param_plot`: parameter traces over time, the real (fitted) series beside a
//! synthesized one (Stich & Magnor §4.3, §5.1: judging whether the learned process reproduces the
//! flame's flicker), as a grid of small line plots.

use std::sync::Arc;

use crate::values::ParamSeries;
use pyrograph_core::declare::Cook;
use pyrograph_core::{CookCtx, Image, NodeError, port};
use pyrograph_nodes_eigen::view::Canvas;

const BACKGROUND: [f32; 4] = [0.08, 0.08, 0.08, 1.0];
const PANEL: [f32; 4] = [0.13, 0.13, 0.14, 1.0];
const REAL: [f32; 4] = [1.0, 0.62, 0.2, 1.0];
const SYNTH: [f32; 4] = [0.35, 0.8, 1.0, 1.0];
const MEAN: [f32; 4] = [0.35, 0.35, 0.35, 1.0];
const SEPARATOR: [f32; 4] = [0.6, 0.6, 0.6, 1.0];
const LABEL: [f32; 4] = [0.85, 0.85, 0.85, 1.0];

/// Layout of [`param_plot`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlotLayout {
    /// Plots per row of the grid.
    pub columns: usize,
    /// Size of one plot in pixels.
    pub cell: (u32, u32),
    /// Most frames of each series drawn (from the first).
    pub max_frames: usize,
}

impl Default for PlotLayout {
    fn default() -> Self {
        PlotLayout { columns: 4, cell: (240, 80), max_frames: 300 }
    }
}

/// Why [`param_plot`] cannot draw: which series is at fault, or that the plot is too large.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PlotError {
    /// The real series has no columns or frames, or the wrong number of values.
    #[error("the series is empty or malformed")]
    Real,
    /// The synthesized series has other columns than the real one.
    #[error("its columns ({synth}) differ from the real series' ({real})")]
    SynthColumns {
        /// The synthesized series' column names, comma separated.
        synth: String,
        /// The real series' column names, comma separated.
        real: String,
    },
    /// The synthesized series has the wrong number of values.
    #[error("the series is malformed")]
    Synth,
    /// The grid of plots would exceed 100 million pixels.
    #[error("the plot would be {width}x{height} pixels")]
    TooLarge {
        /// Width in pixels.
        width: i64,
        /// Height in pixels.
        height: i64,
    },
}

/// One small plot per parameter: `real` in orange on the left, then (after a gray separator)
/// `synth` in blue on the same value scale; a dark line marks the real series' mean; the number
/// is the column index. `synth` may be empty (no columns) to plot the real series alone; else it
/// must have the same columns.
pub fn param_plot(real: &ParamSeries, synth: &ParamSeries, layout: &PlotLayout) -> Result<Image, PlotError> {
    let dim = real.dim();
    if dim == 0 || real.frames == 0 || real.data.len() != real.frames * dim {
        return Err(PlotError::Real);
    }
    let has_synth = synth.dim() > 0;
    if has_synth && synth.names != real.names {
        return Err(PlotError::SynthColumns { synth: synth.names.join(", "), real: real.names.join(", ") });
    }
    if has_synth && synth.data.len() != synth.frames * dim {
        return Err(PlotError::Synth);
    }
    let (tr, ts) =
        (real.frames.min(layout.max_frames.max(1)), if has_synth { synth.frames.min(layout.max_frames.max(1)) } else { 0 });
    let columns = layout.columns.clamp(1, dim);
    let rows = dim.div_ceil(columns);
    let (cw, ch) = (i64::from(layout.cell.0.max(16)), i64::from(layout.cell.1.max(16)));
    let gap = 4;
    let width = columns as i64 * (cw + gap) + gap;
    let height = rows as i64 * (ch + gap) + gap;
    if width * height > 100_000_000 {
        return Err(PlotError::TooLarge { width, height });
    }
    let mut canvas = Canvas::new(width as u32, height as u32, BACKGROUND);
    let total = (tr + ts).max(2) as f64;
    for c in 0..dim {
        let x0 = gap + (c % columns) as i64 * (cw + gap);
        let y0 = gap + (c / columns) as i64 * (ch + gap);
        canvas.rect(x0, y0, x0 + cw - 1, y0 + ch - 1, PANEL);
        let real_v = |t: usize| real.data[t * dim + c];
        let synth_v = |t: usize| synth.data[t * dim + c];
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for v in (0..tr).map(real_v).chain((0..ts).map(synth_v)) {
            if v.is_finite() {
                lo = lo.min(v);
                hi = hi.max(v);
            }
        }
        if !lo.is_finite() {
            continue;
        }
        let pad = ((hi - lo) * 0.08).max(1e-9 * lo.abs().max(1.0));
        let (lo, hi) = (lo - pad, hi + pad);
        let label_h = 9.0;
        let px = |t: f64| x0 as f64 + 1.0 + t / (total - 1.0) * (cw - 3) as f64;
        let py = |v: f64| y0 as f64 + label_h + (hi - v) / (hi - lo) * (ch as f64 - label_h - 2.0);
        let mean = (0..real.frames).map(real_v).sum::<f64>() / real.frames as f64;
        canvas.line((px(0.0), py(mean)), (px(total - 1.0), py(mean)), MEAN);
        if has_synth {
            let xs = px(tr as f64 - 0.5);
            canvas.line((xs, y0 as f64 + 1.0), (xs, (y0 + ch - 2) as f64), SEPARATOR);
        }
        for t in 1..tr {
            canvas.line((px((t - 1) as f64), py(real_v(t - 1))), (px(t as f64), py(real_v(t))), REAL);
        }
        for t in 1..ts {
            canvas.line((px((tr + t - 1) as f64), py(synth_v(t - 1))), (px((tr + t) as f64), py(synth_v(t))), SYNTH);
        }
        canvas.text(x0 + 2, y0 + 2, &c.to_string(), 1, LABEL);
    }
    Ok(canvas.into_image())
}

pyrograph_core::node! {
    /// Plots every parameter over time, the real series beside a synthesized one (Stich & Magnor §4.3, §5.1), as a grid of small line plots.
    ///
    /// Each plot shows the real (fitted) trace in orange, then after a gray bar the synthesized trace in blue on the
    /// same value scale, with the real mean as a dark line; the number is the column index (path_0.., width_0..,
    /// eig_0.., height for flame_model.fit). Leave `synth` unconnected to plot one series (e.g. arp_learn's
    /// log-likelihood).
    #[node("flame_model.param_plot", "Flame model", Source)]
    pub struct ParamPlot {
        /// The training (fitted) series.
        real: Arc<ParamSeries>,
        /// Optional synthesized series with the same columns (flame_model.arp_sample).
        synth: Arc<ParamSeries> = Arc::new(ParamSeries::default()),
        /// Most frames of each series drawn.
        #[range(2, 1_000_000)]
        frames: usize = 300,
        /// Plots per row.
        #[range(1, 256)]
        columns: usize = 4,
        /// Width of one plot in pixels.
        #[range(16, 4096)]
        cell_width: u32 = 240,
        /// Height of one plot in pixels.
        #[range(16, 4096)]
        cell_height: u32 = 80,
    }
    /// The plots (RGBA).
    -> image: Arc<Image>
}

impl Cook for ParamPlot {
    fn cook(self, _: &CookCtx) -> Result<Arc<Image>, NodeError> {
        let layout = PlotLayout { columns: self.columns, cell: (self.cell_width, self.cell_height), max_frames: self.frames };
        let img = param_plot(&self.real, &self.synth, &layout).map_err(ParamPlot::plot_error)?;
        Ok(Arc::new(img))
    }
}

impl ParamPlot {
    /// The node's error for a failed [`param_plot`]: the series at fault, or `cell_width` for a
    /// plot too large.
    fn plot_error(e: PlotError) -> NodeError {
        let port = match e {
            PlotError::Real => port!(ParamPlot, real),
            PlotError::SynthColumns { .. } | PlotError::Synth => port!(ParamPlot, synth),
            PlotError::TooLarge { .. } => port!(ParamPlot, cell_width),
        };
        NodeError::port(port, e.to_string())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn series(frames: usize, phase: f64) -> ParamSeries {
        let data = (0..frames).flat_map(|t| [(t as f64 * 0.2 + phase).sin(), t as f64]).collect();
        ParamSeries::new(vec!["path_0".into(), "height".into()], frames, data, 25.0).unwrap()
    }

    #[test]
    fn plots_both_series_in_their_colours() {
        let layout = PlotLayout { columns: 2, cell: (100, 50), max_frames: 100 };
        let img = param_plot(&series(60, 0.0), &series(60, 1.0), &layout).unwrap();
        assert_eq!(img.size(), (2 * 104 + 4, 58));
        let count = |c: [f32; 4]| img.data().chunks(4).filter(|p| *p == c).count();
        assert!(count(REAL) > 50 && count(SYNTH) > 50, "{} {}", count(REAL), count(SYNTH));
        let alone = param_plot(&series(60, 0.0), &ParamSeries::default(), &layout).unwrap();
        assert_eq!(alone.data().chunks(4).filter(|p| *p == SYNTH).count(), 0);
    }

    #[test]
    fn mismatched_columns_are_an_error_naming_synth() {
        let other = ParamSeries::new(vec!["a".into(), "b".into()], 3, vec![0.0; 6], 25.0).unwrap();
        let e = param_plot(&series(10, 0.0), &other, &PlotLayout::default()).map_err(ParamPlot::plot_error).unwrap_err();
        assert!(matches!(&e, NodeError::Port { port, .. } if port == "synth"), "{e}");
        assert!(param_plot(&ParamSeries::default(), &ParamSeries::default(), &PlotLayout::default()).is_err());
    }
}
