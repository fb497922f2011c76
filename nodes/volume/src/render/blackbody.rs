//! Blackbody colour: Planck's law integrated against the CIE 1931 2° colour-matching functions
//! and taken to linear sRGB (D65). The matching functions are the multi-lobe Gaussian fit of
//! Wyman, Sloan & Shirley 2013 ("Simple Analytic Approximations to the CIE XYZ Color Matching
//! Functions", JCGT 2(2)), within a few thousandths of the tabulated ones: no crate carries
//! the CIE tables, and the fit is five lines.

use glam::Vec3;

/// Planck's constant, the speed of light and Boltzmann's constant (SI).
const H: f64 = 6.626_070_15e-34;
const C: f64 = 2.997_924_58e8;
const K: f64 = 1.380_649e-23;

/// CIE 1931 x̄, ȳ, z̄ at wavelength `nm`.
fn matching(nm: f64) -> [f64; 3] {
    let g = |mu: f64, below: f64, above: f64| {
        let t = (nm - mu) / if nm < mu { below } else { above };
        (-0.5 * t * t).exp()
    };
    [
        1.056 * g(599.8, 37.9, 31.0) + 0.362 * g(442.0, 16.0, 26.7) - 0.065 * g(501.1, 20.4, 26.2),
        0.821 * g(568.8, 46.9, 40.5) + 0.286 * g(530.9, 16.3, 31.1),
        1.217 * g(437.0, 11.8, 36.0) + 0.681 * g(459.0, 26.0, 13.8),
    ]
}

/// Spectral radiance of a blackbody at `kelvin` and wavelength `nm` (Planck's law, W·sr⁻¹·m⁻³).
pub fn planck(nm: f64, kelvin: f64) -> f64 {
    let l = nm * 1e-9;
    2.0 * H * C * C / l.powi(5) / ((H * C / (l * K * kelvin)).exp_m1())
}

/// CIE XYZ of a blackbody at `kelvin`, integrated over 360–830 nm in 1 nm steps.
pub fn xyz(kelvin: f64) -> [f64; 3] {
    let mut out = [0.0; 3];
    for nm in 360..=830 {
        let b = planck(f64::from(nm), kelvin);
        let m = matching(f64::from(nm));
        for k in 0..3 {
            out[k] += b * m[k];
        }
    }
    out
}

/// The chromaticity (x, y) of a blackbody at `kelvin`.
pub fn chromaticity(kelvin: f64) -> (f64, f64) {
    let [x, y, z] = xyz(kelvin);
    (x / (x + y + z), y / (x + y + z))
}

/// Linear sRGB (D65) of a blackbody at `kelvin`, scaled to luminance 1; channels below 0 (out of
/// the sRGB gamut: the deepest reds) are clipped.
pub fn rgb(kelvin: f64) -> Vec3 {
    let [x, y, z] = xyz(kelvin.max(1.0));
    if y.is_nan() || y <= 0.0 {
        return Vec3::ZERO;
    }
    let (x, z) = (x / y, z / y);
    let r = 3.240_454_2 * x - 1.537_138_5 - 0.498_531_4 * z;
    let g = -0.969_266 * x + 1.876_010_8 + 0.041_556 * z;
    let b = 0.055_643_4 * x - 0.204_025_9 + 1.057_225_2 * z;
    Vec3::new(r as f32, g as f32, b as f32).max(Vec3::ZERO)
}

/// [`rgb`] tabulated over a range of temperatures, read by linear interpolation: a renderer asks
/// for a colour at every sample.
pub struct Table {
    lo: f32,
    hi: f32,
    colours: Vec<Vec3>,
}

impl Table {
    /// Entries of the table.
    const SIZE: usize = 256;

    /// The colours from `lo` to `hi` kelvin (in either order; the range is at least a kelvin wide,
    /// so equal ends give one colour rather than a division by zero).
    pub fn new(lo: f32, hi: f32) -> Table {
        let (lo, hi) = (lo.min(hi).max(1.0), hi.max(lo).max(1.0));
        let hi = hi.max(lo + 1.0);
        let colours =
            (0..Self::SIZE).map(|i| rgb(f64::from(lo) + f64::from(hi - lo) * i as f64 / (Self::SIZE - 1) as f64)).collect();
        Table { lo, hi, colours }
    }

    /// The colour at `kelvin`, clamped to the table's range.
    #[inline]
    pub fn at(&self, kelvin: f32) -> Vec3 {
        let f = ((kelvin - self.lo) / (self.hi - self.lo)).clamp(0.0, 1.0) * (Self::SIZE - 1) as f32;
        let i = (f as usize).min(Self::SIZE - 2);
        self.colours[i].lerp(self.colours[i + 1], f - i as f32)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The Planckian locus as Kim et al. 2002 fit it ("Design of advanced color temperature
    /// control system for HDTV applications": cubic splines through Planck's law over the
    /// tabulated CIE functions), valid from 1,667 K.
    fn kim(t: f64) -> (f64, f64) {
        let x = -0.266_123_9e9 / t.powi(3) - 0.234_358_9e6 / t.powi(2) + 0.877_695_6e3 / t + 0.179_910;
        let y = if t < 2222.0 {
            -1.106_381_4 * x.powi(3) - 1.348_110_20 * x.powi(2) + 2.185_558_32 * x - 0.202_196_83
        } else {
            -0.954_947_6 * x.powi(3) - 1.374_185_93 * x.powi(2) + 2.091_370_15 * x - 0.167_488_67
        };
        (x, y)
    }

    #[test]
    fn blackbody_chromaticity_follows_plancks_law_from_1000_to_3000_kelvin() {
        let mut worst: f64 = 0.0;
        for t in [1700.0, 1900.0, 2100.0, 2300.0, 2500.0, 2700.0, 3000.0] {
            let (x, y) = chromaticity(t);
            let (kx, ky) = kim(t);
            worst = worst.max((x - kx).abs()).max((y - ky).abs());
        }
        println!("largest xy difference from the Planckian locus, 1,700–3,000 K: {worst:.4}");
        assert!(worst < 0.0035, "{worst}");
        // 1,000 K, below the splines' range: the tabulated Planckian locus, (0.6528, 0.3444). The
        // fitted x̄ falls off too fast beyond 650 nm (half the tabulated value at 700 nm), where a
        // 1,000 K body emits most of its visible light, so this end is 0.011 off: a deep red either way.
        let (x, y) = chromaticity(1000.0);
        let off = (x - 0.6528).abs().max((y - 0.3444).abs());
        println!("at 1,000 K: ({x:.4}, {y:.4}), {off:.4} off");
        assert!(off < 0.012, "{off}");
    }

    #[test]
    fn hotter_is_bluer_and_the_table_reads_the_function() {
        let (a, b) = (rgb(1200.0), rgb(2800.0));
        assert!(a.x > 0.0 && a.z / a.x < b.z / b.x, "{a} {b}");
        let table = Table::new(1000.0, 3000.0);
        for k in [1000.0, 1777.0, 2999.0] {
            assert!((table.at(k) - rgb(f64::from(k))).abs().max_element() < 2e-3 * rgb(f64::from(k)).max_element());
        }
        assert_eq!(table.at(100.0), table.at(1000.0));
        // Equal ends (an artist's single flame colour) read that colour, not NaN.
        let one = Table::new(1800.0, 1800.0);
        assert!(one.at(1800.0).is_finite() && (one.at(1800.0) - rgb(1800.0)).abs().max_element() < 1e-3);
    }
}
