//! How a flame sequence looks, in numbers that can be compared with real footage: per flame,
//! the image-space statistics of its area, height, width and energy over time (coefficient of
//! variation, lag-1 and lag-2 autocorrelation), and a banding measure (how much of the flame's
//! vertical luminance profile sits at the frequency of the trajectory's steps).
//!
//! A flame is a run of image columns that the flame mask (luminance above a threshold) covers
//! in some frame of the clip; neighbouring flames are the separate runs (a row of candles).
//! Frames are read twice, through a closure, so a clip of any length is measured in the memory
//! of one frame.

use std::ops::Range;
use std::path::{Path, PathBuf};

use pyrograph_core::document::{GraphDoc, ParamValue, split_endpoint};
use pyrograph_core::{BuildOptions, Channels, CookCtx, Evaluator, Graph, Image, Value};

/// Luminance (Rec. 709) of straight RGBA over black, or the gray value, per pixel.
pub fn luminance(img: &Image) -> Vec<f32> {
    match img.channels() {
        Channels::Gray => img.data().to_vec(),
        Channels::Rgba => {
            img.data().chunks_exact(4).map(|p| (0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]) * p[3].clamp(0.0, 1.0)).collect()
        }
    }
}

/// Coefficient of variation and autocorrelation of one quantity over the frames.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Series {
    /// Mean over the frames.
    pub mean: f64,
    /// Standard deviation over mean (0 when the mean is 0).
    pub cv: f64,
    /// Autocorrelation at lag 1 frame (1 for a constant series).
    pub lag1: f64,
    /// Autocorrelation at lag 2 frames.
    pub lag2: f64,
}

impl Series {
    /// The statistics of `v`.
    pub fn of(v: &[f64]) -> Series {
        let n = v.len().max(1) as f64;
        let mean = v.iter().sum::<f64>() / n;
        let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n;
        let acf = |lag: usize| {
            if var <= 0.0 {
                return 1.0;
            }
            v.windows(lag + 1).map(|w| (w[0] - mean) * (w[lag] - mean)).sum::<f64>() / n / var
        };
        Series { mean, cv: if mean != 0.0 { var.sqrt() / mean.abs() } else { 0.0 }, lag1: acf(1), lag2: acf(2) }
    }
}

/// One flame's look over a clip.
#[derive(Clone, Debug, PartialEq)]
pub struct FlameLook {
    /// The image columns the flame occupies.
    pub columns: Range<u32>,
    /// Mask pixels per frame.
    pub area: Series,
    /// Rows from the mask's top to its bottom.
    pub height: Series,
    /// Columns from the mask's left to its right.
    pub width: Series,
    /// Summed luminance over the mask.
    pub energy: Series,
    /// Mean over frames of [`banding`] of the flame's vertical profile.
    pub banding: f64,
}

/// The look of every flame in a clip, and their mean.
#[derive(Clone, Debug, PartialEq)]
pub struct ClipLook {
    /// Per flame, left to right.
    pub flames: Vec<FlameLook>,
    /// Frames measured.
    pub frames: usize,
}

impl ClipLook {
    /// The mean over flames of a statistic.
    pub fn mean(&self, f: impl Fn(&FlameLook) -> f64) -> f64 {
        self.flames.iter().map(f).sum::<f64>() / self.flames.len().max(1) as f64
    }

    /// One line: the flames' mean CV and lag-1/lag-2 of area, height, width and energy, and banding.
    pub fn summary(&self) -> String {
        let s = |name: &str, f: fn(&FlameLook) -> Series| {
            format!(
                "{name} cv {:.3} lag1 {:.3} lag2 {:.3}",
                self.mean(|l| f(l).cv),
                self.mean(|l| f(l).lag1),
                self.mean(|l| f(l).lag2)
            )
        };
        format!(
            "{} flames, {} frames: {}; {}; {}; {}; banding {:.2e}",
            self.flames.len(),
            self.frames,
            s("area", |l| l.area),
            s("height", |l| l.height),
            s("width", |l| l.width),
            s("energy", |l| l.energy),
            self.mean(|l| l.banding)
        )
    }
}

/// The fraction of the (mean-removed, Hann-windowed) energy of `profile` at `cycles` periods over its length,
/// give or take 0.6×–1.5× (the band the steps of a flame drawn as `cycles` discrete particles
/// fall in), by Parseval against the whole one-sided spectrum. 0 for a profile shorter than 16
/// samples or without variation.
///
/// A handful of DFT bins of a profile of at most a few thousand samples are summed directly:
/// an FFT library would compute every bin to use a dozen.
pub fn banding(profile: &[f64], cycles: usize) -> f64 {
    let n = profile.len();
    if n < 16 || cycles == 0 {
        return 0.0;
    }
    // Mean removed and Hann-windowed: the profile is cut where the mask ends, and without a
    // window that cut leaks low-frequency energy into every bin.
    let mean = profile.iter().sum::<f64>() / n as f64;
    let x: Vec<f64> = profile
        .iter()
        .enumerate()
        .map(|(i, v)| (v - mean) * (0.5 - 0.5 * (std::f64::consts::TAU * i as f64 / (n - 1) as f64).cos()))
        .collect();
    // The window gives the profile a mean again: remove it, so Parseval below counts k ≥ 1 only.
    let windowed_mean = x.iter().sum::<f64>() / n as f64;
    let x: Vec<f64> = x.iter().map(|v| v - windowed_mean).collect();
    let total: f64 = x.iter().map(|v| v * v).sum();
    if total <= 0.0 {
        return 0.0;
    }
    let lo = ((cycles as f64 * 0.6).floor() as usize).max(1);
    let hi = ((cycles as f64 * 1.5).ceil() as usize).min((n - 1) / 2);
    let band: f64 = (lo..=hi)
        .map(|k| {
            let w = std::f64::consts::TAU * k as f64 / n as f64;
            let (re, im) = x.iter().enumerate().fold((0.0, 0.0), |(re, im), (i, v)| {
                let (s, c) = (w * i as f64).sin_cos();
                (re + v * c, im - v * s)
            });
            re * re + im * im
        })
        .sum();
    // Σ_{k=1}^{N-1} |X_k|² = N·Σ(x − mean)², and the spectrum of a real profile is symmetric.
    (2.0 * band / (n as f64 * total)).min(1.0)
}

/// Per-frame measurements of one flame.
#[derive(Default)]
struct Track {
    area: Vec<f64>,
    height: Vec<f64>,
    width: Vec<f64>,
    energy: Vec<f64>,
    banding: Vec<f64>,
}

/// Measures the flames of a clip of `frames` frames, read by `frame(k)` (twice each): pixels
/// with luminance above `threshold` are flame; `steps` is the step count whose frequency
/// [`banding`] looks for. Errors from `frame` are passed on.
pub fn measure<E>(
    frames: usize,
    mut frame: impl FnMut(usize) -> Result<Image, E>,
    threshold: f32,
    steps: usize,
) -> Result<ClipLook, E> {
    // Pass 1: the columns any frame's flame covers.
    let mut covered: Vec<bool> = Vec::new();
    for k in 0..frames {
        let img = frame(k)?;
        let w = img.width() as usize;
        covered.resize(w, false);
        for (i, l) in luminance(&img).iter().enumerate() {
            if *l > threshold {
                covered[i % w] = true;
            }
        }
    }
    let regions = column_runs(&covered);
    // Pass 2: each flame's shape in each frame.
    let mut tracks: Vec<Track> = regions.iter().map(|_| Track::default()).collect();
    for k in 0..frames {
        let img = frame(k)?;
        let (w, h) = (img.width() as usize, img.height() as usize);
        let lum = luminance(&img);
        for (cols, t) in regions.iter().zip(tracks.iter_mut()) {
            let (c0, c1) = (cols.start as usize, (cols.end as usize).min(w));
            let (mut area, mut energy) = (0.0, 0.0);
            let (mut top, mut bottom, mut left, mut right) = (usize::MAX, 0, usize::MAX, 0);
            for y in 0..h {
                for x in c0..c1 {
                    let l = lum[y * w + x];
                    if l > threshold {
                        area += 1.0;
                        energy += l as f64;
                        (top, bottom, left, right) = (top.min(y), bottom.max(y), left.min(x), right.max(x));
                    }
                }
            }
            let seen = area > 0.0;
            t.area.push(area);
            t.energy.push(energy);
            t.height.push(if seen { (bottom - top + 1) as f64 } else { 0.0 });
            t.width.push(if seen { (right - left + 1) as f64 } else { 0.0 });
            if seen {
                let profile: Vec<f64> =
                    (top..=bottom).map(|y| lum[y * w + c0..y * w + c1].iter().map(|&l| l as f64).sum()).collect();
                t.banding.push(banding(&profile, steps));
            }
        }
    }
    let flames = regions
        .into_iter()
        .zip(tracks)
        .map(|(columns, t)| FlameLook {
            columns,
            area: Series::of(&t.area),
            height: Series::of(&t.height),
            width: Series::of(&t.width),
            energy: Series::of(&t.energy),
            banding: t.banding.iter().sum::<f64>() / t.banding.len().max(1) as f64,
        })
        .collect();
    Ok(ClipLook { flames, frames })
}

/// The look of clip output `endpoint` (`node.port`) of the graph file `graph`, with `sets`
/// (`node.param=value`, as the CLI's `--set`) applied: see [`measure`].
pub fn graph_look(graph: &Path, endpoint: &str, sets: &[&str], threshold: f32, steps: usize) -> Result<ClipLook, String> {
    let mut doc = GraphDoc::load(graph).map_err(|d| d.to_string())?;
    for s in sets {
        let (lhs, value) = s.split_once('=').ok_or_else(|| format!("{s}: expected node.param=value"))?;
        let (node, param) = split_endpoint(lhs).ok_or_else(|| format!("{s}: expected node.param=value"))?;
        doc.set_param(node, param, ParamValue::parse_cli(value)).map_err(|e| format!("{s}: {e}"))?;
    }
    let graph =
        Graph::build_file(&doc, graph, &pyrograph_frontend::registry(), &BuildOptions::default()).map_err(|d| d.to_string())?;
    let ctx = CookCtx::new();
    let Value::Clip(clip) = Evaluator::new().output(&graph, endpoint, &ctx).map_err(|e| e.to_string())? else {
        return Err(format!("{endpoint} is not a clip"));
    };
    measure(
        clip.len(),
        |k| match clip.get(k, &ctx).map_err(|e| e.to_string())? {
            Value::Image(img) => Ok(img.as_ref().clone()),
            other => Err(format!("{endpoint} frame {k} is a {}, not an image", other.type_name())),
        },
        threshold,
        steps,
    )
}

/// The look of the PNG frames in `dir` (sorted by name; at most `limit`): see [`measure`].
pub fn footage_look(dir: &Path, limit: usize, threshold: f32, steps: usize) -> Result<ClipLook, String> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(|e| format!("{}: {e}", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x.eq_ignore_ascii_case("png")))
        .collect();
    files.sort();
    files.truncate(limit);
    if files.is_empty() {
        return Err(format!("{}: no PNG frames", dir.display()));
    }
    measure(files.len(), |k| pyrograph_frontend::imaging::io::load_image(&files[k]).map_err(|e| e.to_string()), threshold, steps)
}

/// Runs of covered columns, gaps under 3 columns bridged, runs under 3 columns dropped (noise).
fn column_runs(covered: &[bool]) -> Vec<Range<u32>> {
    let mut runs: Vec<Range<u32>> = Vec::new();
    for (x, &c) in covered.iter().enumerate() {
        if !c {
            continue;
        }
        let x = x as u32;
        match runs.last_mut() {
            Some(r) if x <= r.end + 2 => r.end = x + 1,
            _ => runs.push(x..x + 1),
        }
    }
    runs.retain(|r| r.len() >= 3);
    runs
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn series_of_a_known_sequence() {
        let alternating: Vec<f64> = (0..100).map(|i| if i % 2 == 0 { 1.0 } else { 3.0 }).collect();
        let s = Series::of(&alternating);
        assert!((s.mean - 2.0).abs() < 1e-12 && (s.cv - 0.5).abs() < 1e-12, "{s:?}");
        assert!((s.lag1 + 0.99).abs() < 1e-9 && (s.lag2 - 0.98).abs() < 1e-9, "{s:?}");
        let constant = Series::of(&[4.0; 10]);
        assert_eq!((constant.cv, constant.lag1), (0.0, 1.0));
    }

    #[test]
    fn banding_sees_a_ripple_at_the_step_frequency_and_not_a_smooth_shape() {
        let n = 200;
        let smooth: Vec<f64> = (0..n).map(|i| (std::f64::consts::PI * i as f64 / n as f64).sin()).collect();
        let rippled: Vec<f64> = smooth
            .iter()
            .enumerate()
            .map(|(i, s)| s * (1.0 + 0.2 * (std::f64::consts::TAU * 25.0 * i as f64 / n as f64).sin()))
            .collect();
        let (b0, b1) = (banding(&smooth, 25), banding(&rippled, 25));
        assert!(b0 < 1e-3, "smooth {b0}");
        assert!(b1 > 0.005 && b1 > 20.0 * b0, "rippled {b1} smooth {b0}");
        // A ripple far from the step frequency is not banding.
        let other: Vec<f64> = smooth
            .iter()
            .enumerate()
            .map(|(i, s)| s * (1.0 + 0.2 * (std::f64::consts::TAU * 70.0 * i as f64 / n as f64).sin()))
            .collect();
        assert!(banding(&other, 25) < 1e-3);
        assert_eq!(banding(&[1.0; 10], 25), 0.0, "too short");
        assert_eq!(banding(&[1.0; 64], 25), 0.0, "no variation");
    }

    #[test]
    fn two_flames_are_measured_apart() {
        // Two bright rectangles; the right one grows by a row every frame.
        let frame = |k: usize| -> Result<Image, ()> {
            let mut img = Image::new(40, 30, Channels::Gray);
            for y in 5..20 {
                for x in 5..10 {
                    img.data_mut()[y * 40 + x] = 1.0;
                }
            }
            for y in (20 - k)..25 {
                for x in 25..33 {
                    img.data_mut()[y * 40 + x] = 0.8;
                }
            }
            Ok(img)
        };
        let look = measure(5, frame, 0.5, 25).unwrap();
        assert_eq!(look.flames.len(), 2);
        assert_eq!(look.flames[0].columns, 5..10);
        assert_eq!(look.flames[1].columns, 25..33);
        assert_eq!((look.flames[0].area.mean, look.flames[0].area.cv), (75.0, 0.0));
        assert_eq!(look.flames[1].height.mean, 7.0);
        assert!(look.flames[1].height.cv > 0.1);
        assert!((look.flames[1].energy.mean - 0.8 * 8.0 * 7.0).abs() < 1e-3);
    }
}
