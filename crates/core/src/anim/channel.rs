//! Keyframed animation channels: a value that changes over frames, given by keys (like Blender's
//! F-curves or Houdini's channels).
//!
//! A [`Channel`] is a list of [`Key`]s, each a frame, a value and an [`Interp`]olation mode, plus how
//! the curve continues before the first key and after the last ([`Extrap`]). [`Channel::sample`]
//! gives the value at any frame, fractional frames included (simulation sub-steps sample between
//! frames).
//!
//! # Rules
//!
//! - **Keys.** [`Channel::new`] refuses an empty list, a frame, value or slope that is not a finite
//!   number, keys out of frame order and two keys at the same frame; the [`KeyError`] names the key
//!   in words an artist can act on. Keys are never sorted silently: a key typed at the wrong frame
//!   is a mistake the artist should see, not one the curve should hide.
//! - **One key**: the channel is that value everywhere.
//! - **Segments.** The curve from key i to key i+1 follows key i's mode (its *outgoing* segment, as
//!   in Blender):
//!   - `Constant`: key i's value on `[f_i, f_{i+1})`, key i+1's value at `f_{i+1}`;
//!   - `Linear`: the straight line between the two keys;
//!   - `Smooth`, `Tangent`, `Ease`: the cubic Hermite curve through both keys with slope `m_out`
//!     at key i and `m_in` at key i+1. `Ease`: both 0. Otherwise `m_out` is key i's `out_slope`
//!     if key i is `Tangent`, else key i's automatic slope; `m_in` is key i+1's `in_slope` if key
//!     i+1 is `Tangent`, else key i+1's automatic slope.
//! - **Automatic slopes** are exactly SciPy's `PchipInterpolator` derivatives, computed from every
//!   key's frame and value whatever its mode. With `h_k = f_{k+1} − f_k` and
//!   `δ_k = (v_{k+1} − v_k) / h_k`: at an interior key, 0 if `δ_{k−1}` and `δ_k` differ in sign or
//!   either is 0, else the weighted harmonic mean `(w1 + w2) / m = w1 / δ_{k−1} + w2 / δ_k` with
//!   `w1 = 2h_k + h_{k−1}`, `w2 = h_k + 2h_{k−1}`. At the two end keys, SciPy's one-sided
//!   three-point estimate `d = ((2h0 + h1)δ0 − h0·δ1) / (h0 + h1)`, set to 0 if its sign differs
//!   from `δ0`'s, else to `3δ0` if `δ0` and `δ1` differ in sign and `|d| > 3|δ0|` (`h0, δ0` being
//!   the end segment, `h1, δ1` its neighbour). With two keys both slopes are `δ0`. These slopes
//!   never make an all-`Smooth` curve overshoot: it is monotone wherever the keys are.
//! - **Extrapolation.** Before the first key the curve follows `before`, after the last `after`:
//!   - `Hold`: the end key's value;
//!   - `Linear`: the end key's value plus slope × frames past it, the slope being the end
//!     segment's derivative at the end key (`Constant` segment: 0, `Linear`: its slope, cubic: its
//!     end slope; one key: 0);
//!   - `Cycle`: the frame wrapped into `[f_first, f_last]` with period `f_last − f_first`
//!     (Euclidean remainder, so negative offsets wrap the same way); a period of 0 (one key) holds.
//! - **Odd frames.** A NaN frame samples to NaN; an infinite frame holds, extrapolates linearly to
//!   ±infinity, or (cycling) samples to NaN, as the arithmetic says.
//!
//! Sampling is called per frame and per sub-step, so [`Channel::new`] turns every segment into the
//! coefficients of its polynomial once and [`Channel::sample`] is a binary search plus at most a
//! cubic in Horner form: no allocation, a few nanoseconds for a handful of keys.

use std::fmt;

/// How the curve runs from a key to the next one (the key's *outgoing* segment, as in Blender).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Interp {
    /// Hold this key's value until the next key, then jump.
    Constant,
    /// A straight line to the next key.
    Linear,
    /// A cubic with automatic slopes (SciPy's PCHIP) that never overshoot the keys.
    Smooth,
    /// A cubic with zero slope at both ends of the segment: eases out of this key and into the next.
    Ease,
    /// A cubic with explicit slopes at this key; the next key supplies the slope at the segment's end.
    Tangent {
        /// Slope (value per frame) with which the curve arrives at this key, if the previous
        /// segment is a `Smooth` or `Tangent` cubic.
        in_slope: f64,
        /// Slope (value per frame) with which the curve leaves this key.
        out_slope: f64,
    },
}

impl Interp {
    /// The names [`Interp::parse`] accepts (a `Tangent` key needs its slopes, so it has no bare name).
    pub const NAMES: &'static [&'static str] = &["constant", "linear", "smooth", "ease"];

    /// The mode's name as written in documents: one of [`Interp::NAMES`], or `"tangent"`.
    pub fn name(&self) -> &'static str {
        match self {
            Interp::Constant => "constant",
            Interp::Linear => "linear",
            Interp::Smooth => "smooth",
            Interp::Ease => "ease",
            Interp::Tangent { .. } => "tangent",
        }
    }

    /// The mode named `name` (one of [`Interp::NAMES`]), or `None`.
    pub fn parse(name: &str) -> Option<Interp> {
        match name {
            "constant" => Some(Interp::Constant),
            "linear" => Some(Interp::Linear),
            "smooth" => Some(Interp::Smooth),
            "ease" => Some(Interp::Ease),
            _ => None,
        }
    }
}

/// How a channel continues before its first key or after its last.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Extrap {
    /// Keep the end key's value.
    Hold,
    /// Repeat the keyed stretch, with period last frame − first frame.
    Cycle,
    /// Continue in a straight line with the curve's slope at the end key.
    Linear,
}

impl Extrap {
    /// The names [`Extrap::parse`] accepts, in declaration order.
    pub const NAMES: &'static [&'static str] = &["hold", "cycle", "linear"];

    /// The mode's name as written in documents.
    pub fn name(self) -> &'static str {
        match self {
            Extrap::Hold => "hold",
            Extrap::Cycle => "cycle",
            Extrap::Linear => "linear",
        }
    }

    /// The mode named `name` (one of [`Extrap::NAMES`]), or `None`.
    pub fn parse(name: &str) -> Option<Extrap> {
        match name {
            "hold" => Some(Extrap::Hold),
            "cycle" => Some(Extrap::Cycle),
            "linear" => Some(Extrap::Linear),
            _ => None,
        }
    }
}

/// One key: the channel's value at a frame, and how the curve leaves it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Key {
    /// The frame (fractional frames allowed).
    pub frame: f64,
    /// The value at that frame.
    pub value: f64,
    /// How the curve runs from this key to the next.
    pub interp: Interp,
}

/// Why keys cannot make a channel; `key` is the 0-based index of the offending key (None: the list as a whole).
#[derive(Clone, Debug, PartialEq)]
pub struct KeyError {
    /// The offending key's 0-based index, or `None` when the list as a whole is wrong.
    pub key: Option<usize>,
    /// What is wrong, in an artist's words.
    pub message: String,
}

impl fmt::Display for KeyError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        // Messages about one key's own numbers start "its …" and get the key's (1-based) number;
        // the others already name the keys they are about.
        match self.key {
            Some(k) if self.message.starts_with("its ") => write!(f, "key {}: {}", k + 1, self.message),
            _ => f.write_str(&self.message),
        }
    }
}

impl std::error::Error for KeyError {}

/// A keyed curve, checked and ready to sample. Build it with [`Channel::new`].
#[derive(Clone, Debug, PartialEq)]
pub struct Channel {
    keys: Vec<Key>,
    /// Segment i as `c[0] + c[1]·t + c[2]·t² + c[3]·t³` with `t = frame − keys[i].frame`: the
    /// slopes are folded in once here so sampling is a search and a Horner step.
    segments: Vec<[f64; 4]>,
    /// The curve's slope leaving the first key and arriving at the last (for `Extrap::Linear`).
    start_slope: f64,
    end_slope: f64,
    before: Extrap,
    after: Extrap,
}

/// A segment's polynomial and its slopes at both ends.
struct Segment {
    coeffs: [f64; 4],
    start_slope: f64,
    end_slope: f64,
}

impl Channel {
    /// Checks `keys` (see the module's rules) and precomputes every segment.
    pub fn new(keys: Vec<Key>, before: Extrap, after: Extrap) -> Result<Channel, KeyError> {
        check_keys(&keys)?;
        let auto = auto_slopes(&keys);
        let mut segments = Vec::with_capacity(keys.len() - 1);
        let (mut start_slope, mut end_slope) = (0.0, 0.0);
        for (i, pair) in keys.windows(2).enumerate() {
            let seg = segment(&pair[0], &pair[1], auto[i], auto[i + 1]);
            // Finite keys can still overflow here (values 1e308 apart, frames 1e-300 apart); such
            // a segment would sample to inf or NaN, so it is refused rather than drawn.
            if !seg.coeffs.iter().chain([&seg.start_slope, &seg.end_slope]).all(|c| c.is_finite()) {
                let message = format!(
                    "the curve from key {} to key {} is too steep to compute: \
                     move the keys further apart in frame or closer in value",
                    i + 1,
                    i + 2
                );
                return Err(KeyError { key: Some(i + 1), message });
            }
            if i == 0 {
                start_slope = seg.start_slope;
            }
            end_slope = seg.end_slope;
            segments.push(seg.coeffs);
        }
        Ok(Channel { keys, segments, start_slope, end_slope, before, after })
    }

    /// The curve's value at `frame` (any frame; outside the keys the extrapolation modes apply).
    pub fn sample(&self, frame: f64) -> f64 {
        let first = &self.keys[0];
        let last = &self.keys[self.keys.len() - 1];
        if frame < first.frame {
            self.extrapolate(self.before, frame, first, self.start_slope)
        } else if frame > last.frame {
            self.extrapolate(self.after, frame, last, self.end_slope)
        } else {
            // Between the keys, or NaN (which compares false both ways above).
            self.inside(frame)
        }
    }

    /// The keys, as given.
    pub fn keys(&self) -> &[Key] {
        &self.keys
    }

    /// How the curve continues before the first key.
    pub fn before(&self) -> Extrap {
        self.before
    }

    /// How the curve continues after the last key.
    pub fn after(&self) -> Extrap {
        self.after
    }

    /// Lowest and highest value the curve takes between its first and last key, for range checks
    /// without sampling every frame.
    ///
    /// Exact: `Constant`, `Linear` and `Ease` segments never leave their end values, nor does a
    /// `Smooth` segment between automatic slopes, and every cubic segment is also searched for its
    /// extrema inside the segment. That search covers `Tangent` segments and, as well, a `Smooth`
    /// segment arriving at a `Tangent` key, which takes that key's `in_slope` and can overshoot.
    /// Extrapolated parts are not included (a `Linear` extrapolation is unbounded).
    pub fn value_bounds(&self) -> (f64, f64) {
        let mut lo = self.keys.iter().map(|k| k.value).fold(f64::INFINITY, f64::min);
        let mut hi = self.keys.iter().map(|k| k.value).fold(f64::NEG_INFINITY, f64::max);
        for (c, pair) in self.segments.iter().zip(self.keys.windows(2)) {
            for t in stationary_points(c, pair[1].frame - pair[0].frame).into_iter().flatten() {
                let v = horner(c, t);
                lo = lo.min(v);
                hi = hi.max(v);
            }
        }
        (lo, hi)
    }

    /// The curve at a frame in `[f_first, f_last]` (also reached by cycled frames).
    fn inside(&self, frame: f64) -> f64 {
        // The number of keys at or before `frame`: segment `i − 1` holds it.
        let i = self.keys.partition_point(|k| k.frame <= frame);
        if i == 0 {
            // Only a NaN frame is before nothing here.
            return f64::NAN;
        }
        match self.segments.get(i - 1) {
            Some(c) => horner(c, frame - self.keys[i - 1].frame),
            // At (or, by rounding a cycled frame, a hair past) the last key.
            None => self.keys[self.keys.len() - 1].value,
        }
    }

    /// The curve outside the keys, past `end` (the first or last key) whose segment has `slope` there.
    fn extrapolate(&self, mode: Extrap, frame: f64, end: &Key, slope: f64) -> f64 {
        match mode {
            Extrap::Hold => end.value,
            // A zero slope holds exactly, even at an infinite frame (0 · ∞ would be NaN).
            Extrap::Linear if slope == 0.0 => end.value,
            Extrap::Linear => end.value + slope * (frame - end.frame),
            Extrap::Cycle => {
                let first = self.keys[0].frame;
                let period = self.keys[self.keys.len() - 1].frame - first;
                if period > 0.0 { self.inside(first + (frame - first).rem_euclid(period)) } else { end.value }
            }
        }
    }
}

/// `c[0] + c[1]·t + c[2]·t² + c[3]·t³`.
fn horner(c: &[f64; 4], t: f64) -> f64 {
    c[0] + t * (c[1] + t * (c[2] + t * c[3]))
}

/// The first reason `keys` cannot make a channel, if any.
fn check_keys(keys: &[Key]) -> Result<(), KeyError> {
    if keys.is_empty() {
        return Err(KeyError { key: None, message: "needs at least one key".into() });
    }
    for (i, k) in keys.iter().enumerate() {
        let (in_slope, out_slope) = match k.interp {
            Interp::Tangent { in_slope, out_slope } => (in_slope, out_slope),
            _ => (0.0, 0.0),
        };
        let numbers = [("frame", k.frame), ("value", k.value), ("in slope", in_slope), ("out slope", out_slope)];
        if let Some((what, x)) = numbers.into_iter().find(|(_, x)| !x.is_finite()) {
            let message = format!("its {what} is {x}: frames, values and slopes must be finite numbers");
            return Err(KeyError { key: Some(i), message });
        }
    }
    for (i, pair) in keys.windows(2).enumerate() {
        let (a, b) = (pair[0].frame, pair[1].frame);
        // Artists count keys from 1, as the keys' list reads.
        let (j, first, second) = (i + 1, i + 1, i + 2);
        if b < a {
            let message = format!("key {second} at frame {b} comes before key {first} at frame {a}: write keys in frame order");
            return Err(KeyError { key: Some(j), message });
        }
        if b == a {
            return Err(KeyError { key: Some(j), message: format!("keys {first} and {second} are both at frame {a}") });
        }
    }
    Ok(())
}

/// -1, 0 or 1 like NumPy's `sign` (so ±0 is 0, unlike `f64::signum`): SciPy's shape tests compare these.
fn sign(x: f64) -> f64 {
    if x > 0.0 {
        1.0
    } else if x < 0.0 {
        -1.0
    } else {
        0.0
    }
}

/// The automatic slope at every key: SciPy `PchipInterpolator._find_derivatives`, operation for
/// operation, so the curves match SciPy's to the last few bits.
fn auto_slopes(keys: &[Key]) -> Vec<f64> {
    let n = keys.len();
    if n == 1 {
        return vec![0.0];
    }
    let h: Vec<f64> = keys.windows(2).map(|p| p[1].frame - p[0].frame).collect();
    let delta: Vec<f64> = keys.windows(2).zip(&h).map(|(p, h)| (p[1].value - p[0].value) / h).collect();
    if n == 2 {
        // SciPy: with two points, interpolate linearly.
        return vec![delta[0]; 2];
    }
    let mut m = vec![0.0; n];
    for k in 1..n - 1 {
        let (d0, d1) = (delta[k - 1], delta[k]);
        // A key where the data turns or flattens is an extremum of the curve: slope 0 keeps the
        // curve from overshooting it.
        if sign(d0) != sign(d1) || d0 == 0.0 || d1 == 0.0 {
            continue;
        }
        let w1 = 2.0 * h[k] + h[k - 1];
        let w2 = h[k] + 2.0 * h[k - 1];
        m[k] = 1.0 / ((w1 / d0 + w2 / d1) / (w1 + w2));
    }
    m[0] = edge_slope(h[0], h[1], delta[0], delta[1]);
    m[n - 1] = edge_slope(h[n - 2], h[n - 3], delta[n - 2], delta[n - 3]);
    m
}

/// SciPy's `PchipInterpolator._edge_case`: a one-sided three-point slope at an end key (`h0`, `d0`
/// the end segment, `h1`, `d1` its neighbour), clamped so the end segment keeps its shape.
fn edge_slope(h0: f64, h1: f64, d0: f64, d1: f64) -> f64 {
    let d = ((2.0 * h0 + h1) * d0 - h0 * d1) / (h0 + h1);
    if sign(d) != sign(d0) {
        0.0
    } else if sign(d0) != sign(d1) && d.abs() > 3.0 * d0.abs() {
        3.0 * d0
    } else {
        d
    }
}

/// The polynomial of the segment from `a` to `b`, given both keys' automatic slopes.
fn segment(a: &Key, b: &Key, auto_a: f64, auto_b: f64) -> Segment {
    let h = b.frame - a.frame;
    let delta = (b.value - a.value) / h;
    let (m_out, m_in) = match a.interp {
        Interp::Constant => return Segment { coeffs: [a.value, 0.0, 0.0, 0.0], start_slope: 0.0, end_slope: 0.0 },
        Interp::Linear => return Segment { coeffs: [a.value, delta, 0.0, 0.0], start_slope: delta, end_slope: delta },
        Interp::Ease => (0.0, 0.0),
        Interp::Smooth => (auto_a, incoming_slope(b, auto_b)),
        Interp::Tangent { out_slope, .. } => (out_slope, incoming_slope(b, auto_b)),
    };
    // The cubic Hermite coefficients as SciPy's CubicHermiteSpline computes them.
    let t = (m_out + m_in - 2.0 * delta) / h;
    Segment { coeffs: [a.value, m_out, (delta - m_out) / h - t, t / h], start_slope: m_out, end_slope: m_in }
}

/// The slope a cubic segment arrives at key `b` with: its `in_slope` if it is a `Tangent` key, else automatic.
fn incoming_slope(b: &Key, auto_b: f64) -> f64 {
    match b.interp {
        Interp::Tangent { in_slope, .. } => in_slope,
        _ => auto_b,
    }
}

/// Where the segment polynomial `c` has zero slope strictly inside `(0, h)`: its possible extrema.
fn stationary_points(c: &[f64; 4], h: f64) -> [Option<f64>; 2] {
    // Roots of c[1] + 2c[2]·t + 3c[3]·t², by the cancellation-free form of the quadratic formula.
    let (qa, qb, qc) = (3.0 * c[3], 2.0 * c[2], c[1]);
    let roots = if qa == 0.0 {
        [(qb != 0.0).then(|| -qc / qb), None]
    } else {
        let disc = qb * qb - 4.0 * qa * qc;
        if disc < 0.0 {
            [None, None]
        } else {
            let q = -0.5 * (qb + sign_or_one(qb) * disc.sqrt());
            [Some(q / qa), (q != 0.0).then(|| qc / q)]
        }
    };
    roots.map(|r| r.filter(|t| *t > 0.0 && *t < h))
}

/// `x`'s sign as ±1, with +1 for zero (the quadratic formula needs a side to take).
fn sign_or_one(x: f64) -> f64 {
    if x < 0.0 { -1.0 } else { 1.0 }
}

#[cfg(test)]
mod tests {
    use std::collections::BTreeSet;

    use proptest::prelude::*;
    use serde_json::Value;

    use super::*;

    fn key(frame: f64, value: f64, interp: Interp) -> Key {
        Key { frame, value, interp }
    }

    fn error(keys: Vec<Key>) -> KeyError {
        match Channel::new(keys, Extrap::Hold, Extrap::Hold) {
            Ok(c) => panic!("expected an error, got {c:?}"),
            Err(e) => e,
        }
    }

    /// One case of channel_reference.json as a channel, its name and its `[frame, expected]` samples.
    fn reference_case(case: &Value) -> (String, Channel, Vec<(f64, f64)>) {
        let name = case["name"].as_str().expect("name").to_string();
        let number = |v: &Value| v.as_f64().expect("number");
        let keys = case["keys"]
            .as_array()
            .expect("keys")
            .iter()
            .map(|k| {
                let interp = match k[2].as_str().expect("interp name") {
                    "tangent" => Interp::Tangent { in_slope: number(&k[3]), out_slope: number(&k[4]) },
                    other => Interp::parse(other).expect("known interp name"),
                };
                key(number(&k[0]), number(&k[1]), interp)
            })
            .collect();
        let extrap = |field: &str| Extrap::parse(case[field].as_str().expect("extrap name")).expect("known extrap name");
        let channel = Channel::new(keys, extrap("before"), extrap("after")).expect(&name);
        let samples = case["samples"].as_array().expect("samples").iter().map(|s| (number(&s[0]), number(&s[1]))).collect();
        (name, channel, samples)
    }

    #[test]
    fn matches_the_scipy_reference() {
        let cases: Value = serde_json::from_str(include_str!("channel_reference.json")).expect("reference JSON");
        let (mut checked, mut failures) = (0, Vec::new());
        for case in cases.as_array().expect("a list of cases") {
            let (name, channel, samples) = reference_case(case);
            for (frame, want) in samples {
                let got = channel.sample(frame);
                checked += 1;
                let close = (got - want).abs() <= 1e-6; // false for NaN too
                if !close {
                    failures.push(format!("{name}: frame {frame}: got {got}, SciPy says {want}"));
                }
            }
        }
        assert!(failures.is_empty(), "{} of {checked} samples differ:\n{}", failures.len(), failures.join("\n"));
        assert!(checked > 500, "only {checked} reference samples");
    }

    #[test]
    fn the_reference_covers_every_mode() {
        let cases: Value = serde_json::from_str(include_str!("channel_reference.json")).expect("reference JSON");
        let cases = cases.as_array().expect("a list of cases");
        let names = |f: &dyn Fn(&Value) -> Vec<String>| cases.iter().flat_map(f).collect::<BTreeSet<String>>();
        let segment_modes = names(&|c| {
            let keys = c["keys"].as_array().expect("keys");
            keys[..keys.len() - 1].iter().map(|k| k[2].as_str().expect("name").to_string()).collect()
        });
        let mut want: BTreeSet<String> = Interp::NAMES.iter().map(|s| s.to_string()).collect();
        want.insert("tangent".into());
        assert_eq!(segment_modes, want);
        let extraps: BTreeSet<String> = Extrap::NAMES.iter().map(|s| s.to_string()).collect();
        assert_eq!(names(&|c| vec![c["before"].as_str().expect("before").to_string()]), extraps);
        assert_eq!(names(&|c| vec![c["after"].as_str().expect("after").to_string()]), extraps);
    }

    #[test]
    fn errors_name_the_key() {
        let e = error(vec![]);
        assert_eq!((e.key, e.to_string()), (None, "needs at least one key".to_string()));

        let s = Interp::Smooth;
        let e = error(vec![key(0.0, 0.0, s), key(10.0, 1.0, s), key(40.0, 2.0, s), key(20.0, 3.0, s)]);
        assert_eq!(e.key, Some(3));
        assert_eq!(e.message, "key 4 at frame 20 comes before key 3 at frame 40: write keys in frame order");
        assert_eq!(e.to_string(), e.message);

        let e = error(vec![key(0.0, 0.0, s), key(10.0, 1.0, s), key(40.0, 2.0, s), key(40.0, 3.0, s)]);
        assert_eq!((e.key, e.message.as_str()), (Some(3), "keys 3 and 4 are both at frame 40"));

        let e = error(vec![key(0.0, 0.0, s), key(f64::NAN, 1.0, s)]);
        assert_eq!(e.to_string(), "key 2: its frame is NaN: frames, values and slopes must be finite numbers");
        let e = error(vec![key(0.0, 0.0, s), key(1.0, 1.0, s), key(2.0, f64::NAN, s)]);
        assert_eq!((e.key, e.message.as_str()), (Some(2), "its value is NaN: frames, values and slopes must be finite numbers"));
        let e = error(vec![key(0.0, 0.0, Interp::Tangent { in_slope: 1.0, out_slope: f64::INFINITY })]);
        assert_eq!(
            (e.key, e.message.as_str()),
            (Some(0), "its out slope is inf: frames, values and slopes must be finite numbers")
        );
        let e = error(vec![key(0.0, 0.0, s), key(1.0, 0.0, Interp::Tangent { in_slope: f64::NAN, out_slope: 0.0 })]);
        assert_eq!(
            (e.key, e.message.as_str()),
            (Some(1), "its in slope is NaN: frames, values and slopes must be finite numbers")
        );

        // Finite keys whose curve overflows are refused too, rather than sampling to infinity.
        let e = error(vec![key(0.0, -1e308, Interp::Linear), key(0.5, 1e308, Interp::Linear)]);
        assert_eq!(e.key, Some(1));
        assert!(e.message.starts_with("the curve from key 1 to key 2 is too steep"), "{}", e.message);
    }

    #[test]
    fn names_round_trip() {
        for name in Interp::NAMES {
            assert_eq!(Interp::parse(name).map(|i| i.name()), Some(*name));
        }
        assert_eq!(Interp::Tangent { in_slope: 0.0, out_slope: 0.0 }.name(), "tangent");
        assert_eq!(Interp::parse("tangent"), None);
        for name in Extrap::NAMES {
            assert_eq!(Extrap::parse(name).map(Extrap::name), Some(*name));
        }
        assert_eq!(Extrap::parse("Hold"), None);
    }

    #[test]
    fn tangent_bounds_find_the_overshoot_and_odd_frames_behave() {
        // 3t(1 − t)² on [0, 1]: peaks at t = 1/3 with 4/9, although both keys are 0.
        let keys = vec![key(0.0, 0.0, Interp::Tangent { in_slope: 0.0, out_slope: 3.0 }), key(1.0, 0.0, Interp::Smooth)];
        let c = Channel::new(keys, Extrap::Cycle, Extrap::Linear).expect("valid keys");
        let (lo, hi) = c.value_bounds();
        assert_eq!(lo, 0.0);
        assert!((hi - 4.0 / 9.0).abs() < 1e-12, "{hi}");
        assert!(c.sample(f64::NAN).is_nan());
        assert!(c.sample(f64::NEG_INFINITY).is_nan(), "an infinite frame has no place in a cycle");
        // The end slope of the cubic is the Smooth key's automatic slope, 0 here: linear extrapolation holds.
        assert_eq!(c.sample(f64::INFINITY), 0.0);
        assert_eq!((c.before(), c.after(), c.keys().len()), (Extrap::Cycle, Extrap::Linear, 2));
    }

    fn named_interp() -> BoxedStrategy<Interp> {
        prop_oneof![Just(Interp::Constant), Just(Interp::Linear), Just(Interp::Smooth), Just(Interp::Ease)].boxed()
    }

    /// Any mode that keeps equal keys flat: the named ones, or `Tangent` with zero slopes.
    fn flat_interp() -> BoxedStrategy<Interp> {
        prop_oneof![4 => named_interp(), 1 => Just(Interp::Tangent { in_slope: 0.0, out_slope: 0.0 })].boxed()
    }

    fn any_interp() -> BoxedStrategy<Interp> {
        prop_oneof![
            4 => named_interp(),
            1 => (-20.0..20.0f64, -20.0..20.0f64).prop_map(|(in_slope, out_slope)| Interp::Tangent { in_slope, out_slope }),
        ]
        .boxed()
    }

    fn any_extrap() -> impl Strategy<Value = Extrap> {
        prop_oneof![Just(Extrap::Hold), Just(Extrap::Cycle), Just(Extrap::Linear)]
    }

    /// 1 to 12 increasing frames, unevenly spaced (gaps from a twentieth of a frame to 30 frames).
    fn frames() -> impl Strategy<Value = Vec<f64>> {
        (-100.0..100.0f64, prop::collection::vec(0.05..30.0f64, 0..12)).prop_map(|(start, gaps)| {
            let mut frames = vec![start];
            for g in gaps {
                frames.push(frames[frames.len() - 1] + g);
            }
            frames
        })
    }

    /// Keys at `frames()` with values from -100 to 100 and modes from `interp`.
    fn keys_with(interp: BoxedStrategy<Interp>) -> impl Strategy<Value = Vec<Key>> {
        frames().prop_flat_map(move |frames| {
            let n = frames.len();
            (Just(frames), prop::collection::vec(-100.0..100.0f64, n), prop::collection::vec(interp.clone(), n))
                .prop_map(|(f, v, m)| (0..f.len()).map(|i| key(f[i], v[i], m[i])).collect())
        })
    }

    /// 1000 frames evenly from the first key to the last, plus the keys' own frames, in order.
    fn grid(keys: &[Key]) -> Vec<f64> {
        let (a, b) = (keys[0].frame, keys[keys.len() - 1].frame);
        let mut g: Vec<f64> =
            (0..=1000).map(|i| a + (b - a) * f64::from(i) / 1000.0).chain(keys.iter().map(|k| k.frame)).collect();
        g.sort_by(f64::total_cmp);
        g
    }

    proptest! {
        #[test]
        fn equal_values_give_a_constant(
            keys in keys_with(flat_interp()),
            value in -1e3..1e3f64,
            before in any_extrap(),
            after in any_extrap(),
            frames in prop::collection::vec(-1e4..1e4f64, 50),
        ) {
            let keys: Vec<Key> = keys.into_iter().map(|k| Key { value, ..k }).collect();
            let c = Channel::new(keys.clone(), before, after).expect("valid keys");
            for f in frames.into_iter().chain(grid(&keys)) {
                prop_assert_eq!(c.sample(f), value, "frame {}", f);
            }
            prop_assert_eq!(c.value_bounds(), (value, value));
        }

        #[test]
        fn keys_are_hit_exactly(keys in keys_with(any_interp()), before in any_extrap(), after in any_extrap()) {
            let c = Channel::new(keys.clone(), before, after).expect("valid keys");
            for k in &keys {
                prop_assert_eq!(c.sample(k.frame), k.value, "key at frame {}", k.frame);
            }
        }

        #[test]
        fn monotone_keys_give_a_monotone_curve(
            keys in keys_with(Just(Interp::Smooth).boxed()),
            mode in prop_oneof![Just(Interp::Smooth), Just(Interp::Linear), Just(Interp::Ease)],
            decreasing in any::<bool>(),
            flat_runs in prop::collection::vec(any::<bool>(), 12),
        ) {
            // Sorted values, some repeated (flat runs), ascending or descending.
            let mut values: Vec<f64> = keys.iter().map(|k| k.value).collect();
            values.sort_by(f64::total_cmp);
            for i in 1..values.len() {
                if flat_runs[i] {
                    values[i] = values[i - 1];
                }
            }
            if decreasing {
                values.reverse();
            }
            let keys: Vec<Key> = keys.iter().zip(values).map(|(k, value)| key(k.frame, value, mode)).collect();
            let c = Channel::new(keys.clone(), Extrap::Hold, Extrap::Hold).expect("valid keys");
            let samples: Vec<f64> = grid(&keys).into_iter().map(|f| c.sample(f)).collect();
            let sign = if decreasing { -1.0 } else { 1.0 };
            for (i, pair) in samples.windows(2).enumerate() {
                // Rounding may wobble a flat stretch by a few ulps; a real overshoot is far bigger.
                prop_assert!(sign * (pair[1] - pair[0]) >= -1e-9, "sample {} goes from {} to {}", i, pair[0], pair[1]);
            }
        }

        #[test]
        fn value_bounds_contain_every_sample(keys in keys_with(any_interp())) {
            let c = Channel::new(keys.clone(), Extrap::Linear, Extrap::Linear).expect("valid keys");
            let (lo, hi) = c.value_bounds();
            let slack = 1e-9 * (1.0 + lo.abs() + hi.abs());
            for f in grid(&keys) {
                let v = c.sample(f);
                prop_assert!(lo - slack <= v && v <= hi + slack, "frame {}: {} outside [{}, {}]", f, v, lo, hi);
            }
        }
    }
}
