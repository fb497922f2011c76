//! Shape measurements of the generic flame model (Stich & Magnor §3.1): geometric moments up to
//! order 3 (eq. 1), the main axes they define, connected plumes, and the natural cubic spline that
//! interpolates the sparsely sampled path and width parameters.

/// Geometric moments `M_pq = Σ x^p y^q I(x, y)` (eq. 1) of a gray image up to order 3, taken at
/// pixel centres (`x = column + 0.5`, `y = row + 0.5`, y down).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Moments {
    /// `M_00`: the total intensity.
    pub m00: f64,
    /// `M_10`, `M_01`.
    pub m1: [f64; 2],
    /// `M_20`, `M_11`, `M_02`.
    pub m2: [f64; 3],
    /// `M_30`, `M_21`, `M_12`, `M_03`.
    pub m3: [f64; 4],
}

impl Moments {
    /// The moments of a row-major `width × height` gray image.
    pub fn of_image(data: &[f32], width: usize, height: usize) -> Moments {
        let mut m = Moments::default();
        for (row, line) in data.chunks_exact(width.max(1)).take(height).enumerate() {
            let y = row as f64 + 0.5;
            // Per-row sums in x, then combined with powers of y.
            let (mut s0, mut s1, mut s2, mut s3) = (0.0_f64, 0.0_f64, 0.0_f64, 0.0_f64);
            for (col, &v) in line.iter().enumerate() {
                if v != 0.0 {
                    let v = f64::from(v);
                    let x = col as f64 + 0.5;
                    s0 += v;
                    s1 += v * x;
                    s2 += v * x * x;
                    s3 += v * x * x * x;
                }
            }
            m.add_row(y, [s0, s1, s2, s3]);
        }
        m
    }

    fn add_row(&mut self, y: f64, [s0, s1, s2, s3]: [f64; 4]) {
        self.m00 += s0;
        self.m1[0] += s1;
        self.m1[1] += s0 * y;
        self.m2[0] += s2;
        self.m2[1] += s1 * y;
        self.m2[2] += s0 * y * y;
        self.m3[0] += s3;
        self.m3[1] += s2 * y;
        self.m3[2] += s1 * y * y;
        self.m3[3] += s0 * y * y * y;
    }

    /// Shifts the coordinate origin by `(dx, dy)` (moments of the same image placed `dx, dy` further).
    pub fn translated(&self, dx: f64, dy: f64) -> Moments {
        // Binomial expansion of (x + dx)^p (y + dy)^q.
        let [m10, m01] = self.m1;
        let [m20, m11, m02] = self.m2;
        let [m30, m21, m12, m03] = self.m3;
        let m00 = self.m00;
        Moments {
            m00,
            m1: [m10 + dx * m00, m01 + dy * m00],
            m2: [
                m20 + 2.0 * dx * m10 + dx * dx * m00,
                m11 + dx * m01 + dy * m10 + dx * dy * m00,
                m02 + 2.0 * dy * m01 + dy * dy * m00,
            ],
            m3: [
                m30 + 3.0 * dx * m20 + 3.0 * dx * dx * m10 + dx.powi(3) * m00,
                m21 + 2.0 * dx * m11 + dx * dx * m01 + dy * (m20 + 2.0 * dx * m10 + dx * dx * m00),
                m12 + 2.0 * dy * m11 + dy * dy * m10 + dx * (m02 + 2.0 * dy * m01 + dy * dy * m00),
                m03 + 3.0 * dy * m02 + 3.0 * dy * dy * m01 + dy.powi(3) * m00,
            ],
        }
    }

    /// The intensity centroid `(M_10 / M_00, M_01 / M_00)`; `None` for an empty image.
    pub fn centroid(&self) -> Option<[f64; 2]> {
        (self.m00 > 0.0).then(|| [self.m1[0] / self.m00, self.m1[1] / self.m00])
    }

    /// Normalized central moments `[μ20, μ11, μ02] / M_00` (the covariance of the distribution).
    pub fn covariance(&self) -> Option<[f64; 3]> {
        let [cx, cy] = self.centroid()?;
        let n = self.m00;
        Some([self.m2[0] / n - cx * cx, self.m2[1] / n - cx * cy, self.m2[2] / n - cy * cy])
    }

    /// Normalized third-order central moments `[μ30, μ21, μ12, μ03] / M_00`.
    pub fn central3(&self) -> Option<[f64; 4]> {
        let [cx, cy] = self.centroid()?;
        let c = self.translated(-cx, -cy);
        let n = self.m00;
        Some([c.m3[0] / n, c.m3[1] / n, c.m3[2] / n, c.m3[3] / n])
    }

    /// The main axes: `(major unit vector, σ_major, σ_minor)` from the second-order moments. The
    /// major axis is the eigenvector of the covariance with the larger eigenvalue; its sign is
    /// chosen pointing up the image (negative y; positive x when exactly horizontal).
    pub fn main_axes(&self) -> Option<([f64; 2], f64, f64)> {
        let [a, b, c] = self.covariance()?;
        let theta = 0.5 * (2.0 * b).atan2(a - c);
        let mut dir = [theta.cos(), theta.sin()];
        if dir[1] > 0.0 || (dir[1] == 0.0 && dir[0] < 0.0) {
            dir = [-dir[0], -dir[1]];
        }
        let mid = 0.5 * (a + c);
        let r = (0.25 * (a - c) * (a - c) + b * b).sqrt();
        Some((dir, (mid + r).max(0.0).sqrt(), (mid - r).max(0.0).sqrt()))
    }

    /// Skewness of the distribution along the unit direction `dir` (third-order moments):
    /// positive when the long tail points along `dir`.
    pub fn skewness_along(&self, dir: [f64; 2]) -> Option<f64> {
        let [a, b, c] = self.covariance()?;
        let [m30, m21, m12, m03] = self.central3()?;
        let [x, y] = dir;
        let var = a * x * x + 2.0 * b * x * y + c * y * y;
        let third = m30 * x * x * x + 3.0 * m21 * x * x * y + 3.0 * m12 * x * y * y + m03 * y * y * y;
        (var > 0.0).then(|| third / var.powf(1.5))
    }
}

/// Labels 8-connected regions of non-zero pixels; returns per-pixel labels (0 = background,
/// regions 1..) and the total intensity of each region (index `label − 1`).
pub fn plumes(data: &[f32], width: usize, height: usize) -> (Vec<u32>, Vec<f64>) {
    let mut labels = vec![0_u32; data.len()];
    let mut masses = Vec::new();
    let mut stack = Vec::new();
    for start in 0..data.len().min(width * height) {
        if data[start] <= 0.0 || labels[start] != 0 {
            continue;
        }
        let label = masses.len() as u32 + 1;
        let mut mass = 0.0_f64;
        labels[start] = label;
        stack.push(start);
        while let Some(p) = stack.pop() {
            mass += f64::from(data[p]);
            let (x, y) = ((p % width) as isize, (p / width) as isize);
            for dy in -1..=1_isize {
                for dx in -1..=1_isize {
                    let (nx, ny) = (x + dx, y + dy);
                    if nx < 0 || ny < 0 || nx >= width as isize || ny >= height as isize {
                        continue;
                    }
                    let q = ny as usize * width + nx as usize;
                    if data[q] > 0.0 && labels[q] == 0 {
                        labels[q] = label;
                        stack.push(q);
                    }
                }
            }
        }
        masses.push(mass);
    }
    (labels, masses)
}

/// A natural cubic spline through values at equidistant knots on `0..1` (`v_k = k / (n − 1)`),
/// held constant outside (§3.1: the sparsely sampled path and width parameters are interpolated
/// with a cubic spline). One knot gives a constant, two a straight line.
#[derive(Clone, Debug, PartialEq)]
pub struct Spline {
    values: Vec<f64>,
    /// Second derivatives at the knots (with respect to the knot index).
    second: Vec<f64>,
}

impl Spline {
    /// The spline through `values` (at least one).
    pub fn new(values: &[f64]) -> Spline {
        let n = values.len();
        let mut second = vec![0.0; n];
        if n >= 3 {
            // Tridiagonal system for unit knot spacing: M_{i−1} + 4 M_i + M_{i+1} = 6 (y_{i+1} − 2 y_i + y_{i−1}),
            // natural ends M_0 = M_{n−1} = 0 (Thomas algorithm).
            let m = n - 2;
            let mut c = vec![0.0; m];
            let mut d = vec![0.0; m];
            for i in 0..m {
                let rhs = 6.0 * (values[i + 2] - 2.0 * values[i + 1] + values[i]);
                let (prev_c, prev_d) = if i == 0 { (0.0, 0.0) } else { (c[i - 1], d[i - 1]) };
                let denom = 4.0 - prev_c;
                c[i] = 1.0 / denom;
                d[i] = (rhs - prev_d) / denom;
            }
            for i in (0..m).rev() {
                let next = if i + 1 < m { second[i + 2] } else { 0.0 };
                second[i + 1] = d[i] - c[i] * next;
            }
        }
        Spline { values: values.to_vec(), second }
    }

    /// The value at height `v` (clamped to 0..1).
    pub fn at(&self, v: f64) -> f64 {
        let n = self.values.len();
        match n {
            0 => 0.0,
            1 => self.values[0],
            _ => {
                let x = v.clamp(0.0, 1.0) * (n - 1) as f64;
                let i = (x.floor() as usize).min(n - 2);
                let t = x - i as f64;
                let (y0, y1, m0, m1) = (self.values[i], self.values[i + 1], self.second[i], self.second[i + 1]);
                let a = 1.0 - t;
                a * y0 + t * y1 + ((a * a * a - a) * m0 + (t * t * t - t) * m1) / 6.0
            }
        }
    }
}

/// Linear interpolation of `values` sampled at the centres of `values.len()` equal slices of 0..1,
/// evaluated at `v` (clamped to the first and last centre).
pub fn slice_value(values: &[f64], v: f64) -> f64 {
    let n = values.len();
    if n == 0 {
        return 0.0;
    }
    let x = (v * n as f64 - 0.5).clamp(0.0, (n - 1) as f64);
    let i = (x.floor() as usize).min(n.saturating_sub(2));
    if n == 1 {
        return values[0];
    }
    let t = x - i as f64;
    values[i] * (1.0 - t) + values[i + 1] * t
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A filled ellipse (semi-axes `a` along angle `deg`, `b` across) centred at (cx, cy).
    pub fn ellipse(w: usize, h: usize, c: [f64; 2], a: f64, b: f64, deg: f64) -> Vec<f32> {
        let (s, co) = deg.to_radians().sin_cos();
        let sub = 4;
        let mut out = vec![0.0_f32; w * h];
        for y in 0..h {
            for x in 0..w {
                let mut hits = 0;
                for sy in 0..sub {
                    for sx in 0..sub {
                        let px = x as f64 + (sx as f64 + 0.5) / sub as f64 - c[0];
                        let py = y as f64 + (sy as f64 + 0.5) / sub as f64 - c[1];
                        let (u, v) = (px * co + py * s, -px * s + py * co);
                        if (u / a).powi(2) + (v / b).powi(2) <= 1.0 {
                            hits += 1;
                        }
                    }
                }
                out[y * w + x] = hits as f32 / (sub * sub) as f32;
            }
        }
        out
    }

    #[test]
    fn moments_of_a_rotated_ellipse_give_its_angle_and_axes() {
        let (w, h) = (160, 160);
        for deg in [-70.0_f64, -25.0, 10.0, 60.0] {
            let img = ellipse(w, h, [83.0, 77.0], 50.0, 18.0, deg);
            let m = Moments::of_image(&img, w, h);
            let c = m.centroid().unwrap();
            assert!((c[0] - 83.0).abs() < 0.05 && (c[1] - 77.0).abs() < 0.05, "centroid {c:?}");
            let (dir, major, minor) = m.main_axes().unwrap();
            // The major axis is ±(cos, sin) of the angle; the sign convention points it up (y < 0).
            let cross = dir[0] * deg.to_radians().sin() - dir[1] * deg.to_radians().cos();
            assert!(cross.abs() < 0.002, "{deg}°: axis {dir:?}");
            assert!(dir[1] <= 0.0);
            // A uniform ellipse with semi-axis a has σ = a / 2 along it.
            assert!((major - 25.0).abs() < 0.1, "{deg}°: σ_major {major}");
            assert!((minor - 9.0).abs() < 0.1, "{deg}°: σ_minor {minor}");
            // Symmetric: no skew.
            assert!(m.skewness_along(dir).unwrap().abs() < 0.01);
        }
    }

    #[test]
    fn translated_moments_equal_moments_of_the_shifted_image() {
        let (w, h) = (40, 30);
        let img = ellipse(w, h, [15.0, 12.0], 9.0, 4.0, 30.0);
        let shifted: Vec<f32> =
            (0..w * h).map(|p| if p % w >= 3 && p / w >= 2 { img[(p / w - 2) * w + p % w - 3] } else { 0.0 }).collect();
        let a = Moments::of_image(&img, w, h).translated(3.0, 2.0);
        let b = Moments::of_image(&shifted, w, h);
        for (x, y) in a.m3.iter().chain(&a.m2).zip(b.m3.iter().chain(&b.m2)) {
            assert!((x - y).abs() < 1e-6 * y.abs().max(1.0), "{x} vs {y}");
        }
    }

    #[test]
    fn a_tail_gives_positive_skewness_towards_it() {
        let (w, h) = (20, 60);
        // Bright at the bottom, thin tail towards the top.
        let img: Vec<f32> =
            (0..w * h).map(|p| if (8..12).contains(&(p % w)) { ((p / w) as f32 / h as f32).powi(3) } else { 0.0 }).collect();
        let m = Moments::of_image(&img, w, h);
        assert!(m.skewness_along([0.0, -1.0]).unwrap() > 0.5);
    }

    #[test]
    fn plumes_are_counted_and_weighed() {
        let (w, h) = (10, 6);
        let mut img = vec![0.0_f32; w * h];
        img[w + 1] = 1.0;
        img[2 * w + 2] = 1.0; // diagonal neighbour: same plume
        img[3 * w + 7] = 0.5;
        let (labels, masses) = plumes(&img, w, h);
        assert_eq!(masses, vec![2.0, 0.5]);
        assert_eq!(labels[w + 1], labels[2 * w + 2]);
        assert_ne!(labels[3 * w + 7], labels[w + 1]);
    }

    #[test]
    fn spline_interpolates_its_knots_and_lines_exactly() {
        let s = Spline::new(&[0.0, 2.0, 1.0, 3.0, -1.0]);
        for (k, want) in [0.0, 2.0, 1.0, 3.0, -1.0].iter().enumerate() {
            assert!((s.at(k as f64 / 4.0) - want).abs() < 1e-12);
        }
        let line = Spline::new(&[1.0, 2.0, 3.0, 4.0]);
        assert!((line.at(0.5) - 2.5).abs() < 1e-12);
        assert_eq!(Spline::new(&[7.0]).at(0.3), 7.0);
        assert!((Spline::new(&[0.0, 1.0]).at(0.25) - 0.25).abs() < 1e-12);
        assert_eq!(line.at(2.0), 4.0, "held constant outside");
    }

    #[test]
    fn slice_values_interpolate_between_centres() {
        let v = [0.0, 1.0, 4.0];
        assert_eq!(slice_value(&v, 0.0), 0.0);
        assert!((slice_value(&v, 0.5) - 1.0).abs() < 1e-12);
        assert!((slice_value(&v, 1.0) - 4.0).abs() < 1e-12);
        assert!((slice_value(&v, 1.0 / 3.0) - 0.5).abs() < 1e-12);
    }
}
