//! Looking at a database: eigenfires as 8-bit images (thesis §4.4 eq. 19–20, Fig. 23), paths of
//! the frames in the first three components (Fig. 24) and weight charts (Figs. 27–28).
//!
//! Labels are drawn with a built-in 3×5 pixel digit font (no font files needed).

use std::sync::Arc;

use crate::values::{Basis, FrameItem, FrameList, Weights};
use pyrograph_core::declare::Cook;
use pyrograph_core::{Channels, CookCtx, Image, NodeError, port};

/// Eq. 19–20: `samples` scaled by `255 / (max − min)` and shifted by `−255 min / (max − min)`,
/// rounded to 8 bits (returned as 0..1 floats on the 1/255 grid). A constant vector maps to 0.
pub fn to_8bit(samples: &[f32]) -> Vec<f32> {
    let (lo, hi) = samples.iter().fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), &v| (a.min(v), b.max(v)));
    if hi.is_nan() || lo.is_nan() || hi <= lo {
        return vec![0.0; samples.len()];
    }
    let scaling = 255.0 / f64::from(hi - lo);
    let shifting = -255.0 * f64::from(lo) / f64::from(hi - lo);
    samples.iter().map(|&v| ((f64::from(v) * scaling + shifting).round().clamp(0.0, 255.0) / 255.0) as f32).collect()
}

/// Eigenfire `k` (1-based; 0 = the mean image Ψ) as an 8-bit gray image (eq. 19–20).
pub fn eigenfire_image(basis: &Basis, k: usize) -> Result<Image, String> {
    let samples = if k == 0 {
        &basis.mean[..]
    } else {
        basis.eigenvector(k - 1).ok_or_else(|| format!("eigenfire {k} does not exist; the basis has {}", basis.components()))?
    };
    Image::from_vec(basis.width, basis.height, Channels::Gray, to_8bit(samples)).ok_or_else(|| "basis size mismatch".into())
}

/// An RGBA drawing surface.
pub struct Canvas {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Straight RGBA, row-major.
    pub data: Vec<f32>,
}

/// 3×5 glyphs of the digits 0–9 and '-', '.', one row of 3 bits per entry.
const GLYPHS: [[u8; 5]; 12] = [
    [7, 5, 5, 5, 7],
    [2, 6, 2, 2, 7],
    [7, 1, 7, 4, 7],
    [7, 1, 7, 1, 7],
    [5, 5, 7, 1, 1],
    [7, 4, 7, 1, 7],
    [7, 4, 7, 5, 7],
    [7, 1, 1, 1, 1],
    [7, 5, 7, 5, 7],
    [7, 5, 7, 1, 7],
    [0, 0, 7, 0, 0],
    [0, 0, 0, 0, 2],
];

impl Canvas {
    /// A canvas filled with `background`.
    pub fn new(width: u32, height: u32, background: [f32; 4]) -> Self {
        let data = std::iter::repeat_n(background, width as usize * height as usize).flatten().collect();
        Canvas { width, height, data }
    }

    /// Sets one pixel (ignored outside).
    pub fn put(&mut self, x: i64, y: i64, c: [f32; 4]) {
        if x >= 0 && y >= 0 && (x as u32) < self.width && (y as u32) < self.height {
            let i = (y as usize * self.width as usize + x as usize) * 4;
            self.data[i..i + 4].copy_from_slice(&c);
        }
    }

    /// Fills a rectangle.
    pub fn rect(&mut self, x0: i64, y0: i64, x1: i64, y1: i64, c: [f32; 4]) {
        for y in y0.min(y1)..=y0.max(y1) {
            for x in x0.min(x1)..=x0.max(x1) {
                self.put(x, y, c);
            }
        }
    }

    /// A one-pixel line (DDA).
    pub fn line(&mut self, a: (f64, f64), b: (f64, f64), c: [f32; 4]) {
        let steps = (b.0 - a.0).abs().max((b.1 - a.1).abs()).ceil().max(1.0) as usize;
        if steps > 100_000 {
            return;
        }
        for s in 0..=steps {
            let t = s as f64 / steps as f64;
            self.put((a.0 + (b.0 - a.0) * t).round() as i64, (a.1 + (b.1 - a.1) * t).round() as i64, c);
        }
    }

    /// Draws `text` (digits, '-' and '.') with its top-left at (x, y), `scale` pixels per dot.
    pub fn text(&mut self, x: i64, y: i64, text: &str, scale: i64, c: [f32; 4]) {
        for (i, ch) in text.chars().enumerate() {
            let g = match ch {
                '0'..='9' => GLYPHS[ch as usize - '0' as usize],
                '-' => GLYPHS[10],
                '.' => GLYPHS[11],
                _ => continue,
            };
            let gx = x + i as i64 * 4 * scale;
            for (r, bits) in g.iter().enumerate() {
                for col in 0..3 {
                    if bits & (4 >> col) != 0 {
                        self.rect(
                            gx + col * scale,
                            y + r as i64 * scale,
                            gx + col * scale + scale - 1,
                            y + r as i64 * scale + scale - 1,
                            c,
                        );
                    }
                }
            }
        }
    }

    /// Copies a gray image in at (x, y).
    pub fn blit_gray(&mut self, img: &Image, x: i64, y: i64) {
        for yy in 0..img.height() {
            for xx in 0..img.width() {
                let v = img.pixel(xx, yy)[0];
                self.put(x + i64::from(xx), y + i64::from(yy), [v, v, v, 1.0]);
            }
        }
    }

    /// The canvas as an RGBA image.
    pub fn into_image(self) -> Image {
        let (w, h) = (self.width, self.height);
        Image::from_vec(w, h, Channels::Rgba, self.data).unwrap_or_else(|| Image::new(w, h, Channels::Rgba))
    }
}

const WHITE: [f32; 4] = [1.0, 1.0, 1.0, 1.0];
const BACKGROUND: [f32; 4] = [0.08, 0.08, 0.08, 1.0];

/// Fig. 23: eigenfires `1..=count` in a labelled grid of `columns`, each with its number below.
pub fn eigenfire_grid(basis: &Basis, count: usize, columns: usize, labels: bool) -> Result<Image, String> {
    if count == 0 || count > basis.components() {
        return Err(format!("count {count} must be 1..={} (the basis's eigenfires)", basis.components()));
    }
    let columns = columns.clamp(1, count);
    let rows = count.div_ceil(columns);
    let (w, h) = (i64::from(basis.width), i64::from(basis.height));
    let gap = 4;
    let label_h = if labels { 14 } else { 0 };
    let cw = columns as i64 * (w + gap) + gap;
    let ch = rows as i64 * (h + label_h + gap) + gap;
    let mut canvas = Canvas::new(cw as u32, ch as u32, BACKGROUND);
    for k in 0..count {
        let img = eigenfire_image(basis, k + 1)?;
        let x = gap + (k % columns) as i64 * (w + gap);
        let y = gap + (k / columns) as i64 * (h + label_h + gap);
        canvas.blit_gray(&img, x, y);
        if labels {
            canvas.text(x + 1, y + h + 2, &(k + 1).to_string(), 2, WHITE);
        }
    }
    Ok(canvas.into_image())
}

/// Colours of training clips in plots (red, yellow, green as in Fig. 24, then more).
const CLIP_COLORS: [[f32; 4]; 5] =
    [[0.95, 0.25, 0.2, 1.0], [0.95, 0.85, 0.2, 1.0], [0.3, 0.9, 0.35, 1.0], [0.3, 0.6, 1.0, 1.0], [0.9, 0.4, 0.9, 1.0]];

/// Fig. 24: every row of `weights` as a point in the first three components, seen from `yaw` and
/// `pitch` (degrees) with an orthographic camera; consecutive frames of a clip (`clip_of`) are
/// joined into paths; `overlay` (weight vectors) is drawn as a white path on top. Axes: red, green,
/// blue for components 1, 2, 3.
pub fn pca_plot(
    weights: &Weights,
    clip_of: &[u32],
    overlay: &[Vec<f32>],
    size: (u32, u32),
    yaw: f64,
    pitch: f64,
    paths: bool,
) -> Result<Image, String> {
    if weights.frames == 0 {
        return Err("there are no weights to plot".into());
    }
    let c = weights.components.min(3);
    let point = |r: &[f32]| -> [f64; 3] {
        let mut p = [0.0; 3];
        for (k, v) in p.iter_mut().enumerate().take(c) {
            *v = f64::from(r[k]);
        }
        p
    };
    let (sy, cy, sp, cp) = (yaw.to_radians().sin(), yaw.to_radians().cos(), pitch.to_radians().sin(), pitch.to_radians().cos());
    let project = |p: [f64; 3]| -> (f64, f64) {
        let x = cy * p[0] - sy * p[2];
        let z = sy * p[0] + cy * p[2];
        let y = cp * p[1] - sp * z;
        (x, y)
    };
    let pts: Vec<(f64, f64)> = (0..weights.frames).map(|i| project(point(&weights.data[i * weights.components..]))).collect();
    let extent = pts.iter().fold(1e-12_f64, |m, p| m.max(p.0.abs()).max(p.1.abs())) * 1.1;
    let (w, h) = (f64::from(size.0), f64::from(size.1));
    let scale = 0.5 * w.min(h) / extent;
    let screen = |p: (f64, f64)| (w / 2.0 + p.0 * scale, h / 2.0 - p.1 * scale);
    let mut canvas = Canvas::new(size.0, size.1, BACKGROUND);
    let axes = [[extent, 0.0, 0.0], [0.0, extent, 0.0], [0.0, 0.0, extent]];
    let axis_colors = [[0.9, 0.2, 0.2, 1.0], [0.2, 0.9, 0.2, 1.0], [0.3, 0.4, 1.0, 1.0]];
    for (a, col) in axes.iter().zip(axis_colors) {
        canvas.line(screen(project([0.0; 3])), screen(project(*a)), col);
    }
    for i in 0..pts.len() {
        let clip = clip_of.get(i).copied().unwrap_or(0) as usize;
        let col = CLIP_COLORS[clip % CLIP_COLORS.len()];
        let dim = [col[0] * 0.6, col[1] * 0.6, col[2] * 0.6, 1.0];
        if paths && i > 0 && clip_of.get(i - 1).copied().unwrap_or(0) as usize == clip {
            canvas.line(screen(pts[i - 1]), screen(pts[i]), dim);
        }
    }
    for (i, p) in pts.iter().enumerate() {
        let col = CLIP_COLORS[clip_of.get(i).copied().unwrap_or(0) as usize % CLIP_COLORS.len()];
        let (x, y) = screen(*p);
        canvas.rect(x as i64 - 1, y as i64 - 1, x as i64 + 1, y as i64 + 1, col);
    }
    let over: Vec<(f64, f64)> = overlay.iter().map(|r| screen(project(point(r)))).collect();
    for win in over.windows(2) {
        canvas.line(win[0], win[1], WHITE);
    }
    for &(x, y) in &over {
        canvas.rect(x as i64 - 2, y as i64 - 2, x as i64 + 2, y as i64 + 2, WHITE);
    }
    Ok(canvas.into_image())
}

/// Figs. 27–28: clustered columns, one cluster per component (`components` of them), one bar per
/// frame `first..first + frames`, dark to bright; zero is the middle line.
pub fn weight_bars(weights: &Weights, first: usize, frames: usize, components: usize, size: (u32, u32)) -> Result<Image, String> {
    if frames == 0 || first + frames > weights.frames {
        return Err(format!("frames {first}..{} are not all in the {} rows of weights", first + frames, weights.frames));
    }
    if components == 0 || components > weights.components {
        return Err(format!("components must be 1..={}", weights.components));
    }
    let (w, h) = (i64::from(size.0), i64::from(size.1));
    let mut canvas = Canvas::new(size.0, size.1, BACKGROUND);
    let peak = (first..first + frames)
        .flat_map(|f| weights.data[f * weights.components..f * weights.components + components].iter())
        .fold(1e-12_f32, |m, v| m.max(v.abs()));
    let label_h = 14;
    let mid = (h - label_h) / 2;
    let cluster = (w - 8) as f64 / components as f64;
    let bar = ((cluster * 0.85) / frames as f64).max(1.0);
    canvas.line((0.0, mid as f64), (w as f64, mid as f64), [0.5, 0.5, 0.5, 1.0]);
    for c in 0..components {
        let x0 = 4.0 + c as f64 * cluster;
        for f in 0..frames {
            let v = weights.data[(first + f) * weights.components + c];
            let t = if frames > 1 { f as f32 / (frames - 1) as f32 } else { 1.0 };
            let col = [0.25 + 0.75 * t, 0.12 + 0.6 * t, 0.05 + 0.2 * t, 1.0];
            let top = mid as f64 - f64::from(v / peak) * (mid as f64 - 4.0);
            let x = x0 + f as f64 * bar;
            canvas.rect(x as i64, mid, (x + bar - 1.0).max(x) as i64, top as i64, col);
        }
        if components <= 40 || c % 10 == 9 {
            canvas.text(x0 as i64, h - label_h + 3, &(c + 1).to_string(), 2, WHITE);
        }
    }
    Ok(canvas.into_image())
}

pyrograph_core::node! {
    /// Shows eigenfire k as an 8-bit gray image, scaled by 255/(max − min) and shifted by −255·min/(max − min) (thesis §4.4, eq. 19–20).
    ///
    /// k = 0 shows the mean image Ψ the same way.
    #[node("eigen.eigenfire_view", "Eigenfires", Source)]
    pub struct EigenfireView {
        /// The Eigenfires basis.
        basis: Arc<Basis>,
        /// Eigenfire number (1 = largest eigenvalue); 0 = mean image.
        #[range(0, 1_000_000)]
        k: usize = 1,
    }
    /// The eigenfire (gray, 8-bit steps).
    -> image: Arc<Image>
}

impl Cook for EigenfireView {
    fn cook(self, _: &CookCtx) -> Result<Arc<Image>, NodeError> {
        let img = eigenfire_image(&self.basis, self.k).map_err(|m| NodeError::port(port!(EigenfireView, k), m))?;
        Ok(Arc::new(img))
    }
}

pyrograph_core::node! {
    /// Lays the first n eigenfires out as one labelled sheet, each scaled to 8 bits by eq. 19–20 (thesis §4.4, Fig. 23).
    ///
    /// Labels are the eigenfire numbers in a built-in pixel font.
    #[node("eigen.eigenfire_grid", "Eigenfires", Source)]
    pub struct EigenfireGrid {
        /// The Eigenfires basis.
        basis: Arc<Basis>,
        /// How many eigenfires, from the first.
        #[range(1, 10_000)]
        count: usize = 9,
        /// Eigenfires per row.
        #[range(1, 1000)]
        columns: usize = 3,
        /// Print each eigenfire's number under it.
        labels: bool = true,
    }
    /// The sheet (RGBA).
    -> image: Arc<Image>
}

impl Cook for EigenfireGrid {
    fn cook(self, _: &CookCtx) -> Result<Arc<Image>, NodeError> {
        let img = eigenfire_grid(&self.basis, self.count, self.columns, self.labels)
            .map_err(|m| NodeError::port(port!(EigenfireGrid, count), m))?;
        Ok(Arc::new(img))
    }
}

pyrograph_core::node! {
    /// Plots every frame as a point in the first three components, with paths joining consecutive frames (thesis §4.4, Fig. 24).
    ///
    /// Points are coloured by training clip (red, yellow, green, …); axes red, green, blue are components 1, 2, 3.
    /// A frame list (a generated animation) can be traced on top in white (§4.4: validating new images).
    #[node("eigen.pca_plot", "Eigenfires", Source)]
    pub struct PcaPlot {
        /// The basis (for each frame's source clip).
        basis: Arc<Basis>,
        /// The weights to plot (e.g. the training weights).
        weights: Arc<Weights>,
        /// Optional animation traced in white (database frames index weights).
        overlay: Arc<FrameList> = Arc::new(FrameList::default()),
        /// Camera turn about component 2, degrees.
        #[range(-360.0, 360.0)]
        yaw: f64 = 30.0,
        /// Camera tilt, degrees.
        #[range(-90.0, 90.0)]
        pitch: f64 = 20.0,
        /// Join consecutive frames of each clip.
        paths: bool = true,
        /// Image width.
        #[range(16, 8192)]
        width: u32 = 640,
        /// Image height.
        #[range(16, 8192)]
        height: u32 = 640,
    }
    /// The plot (RGBA).
    -> image: Arc<Image>
}

/// Weight vectors of a frame list: database frames are rows of `weights`.
pub fn frame_list_weights(list: &FrameList, weights: &Weights) -> Result<Vec<Vec<f32>>, String> {
    list.items
        .iter()
        .map(|item| match item {
            FrameItem::Frame(f) => weights
                .row(*f as usize)
                .map(<[f32]>::to_vec)
                .ok_or_else(|| format!("frame {f} is past the {} rows of weights", weights.frames)),
            FrameItem::Weights(w) => Ok(w.clone()),
        })
        .collect()
}

impl Cook for PcaPlot {
    fn cook(self, _: &CookCtx) -> Result<Arc<Image>, NodeError> {
        let (basis, weights) = (&*self.basis, &*self.weights);
        let clip_of: Vec<u32> =
            if basis.sources.len() == weights.frames { basis.sources.iter().map(|s| s.clip).collect() } else { Vec::new() };
        let overlay = frame_list_weights(&self.overlay, weights).map_err(|m| NodeError::port(port!(PcaPlot, overlay), m))?;
        let size = (self.width, self.height);
        let img = pca_plot(weights, &clip_of, &overlay, size, self.yaw, self.pitch, self.paths)
            .map_err(|m| NodeError::port(port!(PcaPlot, weights), m))?;
        Ok(Arc::new(img))
    }
}

pyrograph_core::node! {
    /// Charts the weights of consecutive frames as clustered columns per eigenfire (thesis §4.6, Figs. 27–28).
    ///
    /// One cluster per component, one bar per frame from dark (first) to bright (last); frames = 1 gives Fig. 28.
    #[node("eigen.weight_bars", "Eigenfires", Source)]
    pub struct WeightBars {
        /// The weights.
        weights: Arc<Weights>,
        /// First frame (row).
        #[range(0, 100_000_000)]
        first: usize = 0,
        /// Number of frames per cluster.
        #[range(1, 10_000)]
        frames: usize = 31,
        /// Number of eigenfires (clusters).
        #[range(1, 10_000)]
        components: usize = 10,
        /// Image width.
        #[range(16, 8192)]
        width: u32 = 960,
        /// Image height.
        #[range(32, 8192)]
        height: u32 = 360,
    }
    /// The chart (RGBA).
    -> image: Arc<Image>
}

impl Cook for WeightBars {
    fn cook(self, _: &CookCtx) -> Result<Arc<Image>, NodeError> {
        let size = (self.width, self.height);
        let img = weight_bars(&self.weights, self.first, self.frames, self.components, size)
            .map_err(|m| NodeError::port(port!(WeightBars, frames), m))?;
        Ok(Arc::new(img))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pca::tests::{random_frames, sources};
    use crate::pca::train;

    #[test]
    fn eq_19_20_maps_min_to_0_and_max_to_255() {
        let out = to_8bit(&[-0.02, 0.0, 0.03]);
        assert_eq!(out[0], 0.0);
        assert_eq!(out[2], 1.0);
        assert_eq!(out[1], (0.02_f64 / 0.05 * 255.0).round() as f32 / 255.0);
        assert_eq!(to_8bit(&[0.5, 0.5]), vec![0.0, 0.0]);
    }

    #[test]
    fn grid_has_the_cells_and_rejects_too_many() {
        let db = train(8, 6, random_frames(8, 6, 12, 31), sources(12), 0).unwrap();
        let g = eigenfire_grid(&db.basis, 9, 3, true).unwrap();
        assert_eq!(g.size(), (3 * 12 + 4, 3 * (6 + 14 + 4) + 4));
        assert!(eigenfire_grid(&db.basis, 12, 3, true).unwrap_err().contains("1..=11"));
        assert!(eigenfire_image(&db.basis, 0).is_ok());
        assert!(eigenfire_image(&db.basis, 12).is_err());
    }

    #[test]
    fn plots_draw_something() {
        let db = train(8, 6, random_frames(8, 6, 12, 32), sources(12), 0).unwrap();
        let p = pca_plot(&db.weights, &[0; 12], &[db.weights.row(0).unwrap().to_vec()], (64, 64), 30.0, 20.0, true).unwrap();
        let lit = p.data().chunks(4).filter(|c| c[0] > 0.5).count();
        assert!(lit > 10);
        let b = weight_bars(&db.weights, 0, 5, 4, (120, 80)).unwrap();
        assert_eq!(b.size(), (120, 80));
        assert!(weight_bars(&db.weights, 10, 5, 4, (120, 80)).is_err());
    }
}
