//! Point lists as typed document values: places on a surface, each with the time (seconds) it
//! takes effect, written in a graph file as
//! `[(0.5, 0.2, -0.15), (2.0, (1.85, 0.1, 0.6)), face(3), (1.0, face(0, (0.2, 0.3, 0.5)))]`:
//! a bare position or face acts at time 0, a `(seconds, place)` pair at that time. A place is a
//! position (the nearest surface point) or a face index with optional barycentric coordinates,
//! as Houdini's primitive number and uv address a point on a mesh. They replace the text form
//! `"x y z; face F b0 b1 b2 @ seconds"`, which is still read from older files.

use std::hash::Hash;

use crate::document::ParamValue;
use crate::fingerprint::Fingerprinter;

/// Where a point is.
#[derive(Clone, Debug, PartialEq)]
pub enum Place {
    /// A position in space; a node snaps it to its surface.
    At([f64; 3]),
    /// A face of the mesh, at barycentric coordinates (the face's centre when `None`).
    Face(u32, Option<[f64; 3]>),
}

/// A list of timed places, in the order written (at least one).
#[derive(Clone, Debug, PartialEq)]
pub struct Points {
    points: Vec<(f64, Place)>,
}

const EXAMPLE: &str = "[(0.5, 0.2, -0.15), (2.0, (1.85, 0.1, 0.6)), face(0)]";

fn number(v: &ParamValue) -> Option<f64> {
    match v {
        ParamValue::Int(i) => Some(*i as f64),
        ParamValue::Float(x) => Some(*x),
        _ => None,
    }
}

fn triple(v: &ParamValue) -> Option<[f64; 3]> {
    match v {
        ParamValue::List(c) if c.len() == 3 => Some([number(&c[0])?, number(&c[1])?, number(&c[2])?]),
        _ => None,
    }
}

impl Points {
    /// Points from `(seconds, place)` entries; errors name the point (counted from 1).
    pub fn new(points: Vec<(f64, Place)>) -> Result<Points, String> {
        if points.is_empty() {
            return Err(format!("needs at least one point, e.g. {EXAMPLE}"));
        }
        for (i, (time, place)) in points.iter().enumerate() {
            let at = |m: &str| format!("point {}: {m}", i + 1);
            if !time.is_finite() || *time < 0.0 {
                return Err(at(&format!("the time must be a number of seconds ≥ 0, got {time}")));
            }
            let finite = match place {
                Place::At(p) => p.iter().all(|x| x.is_finite()),
                Place::Face(_, b) => b.is_none_or(|b| b.iter().all(|x| x.is_finite())),
            };
            if !finite {
                return Err(at("coordinates must be finite numbers"));
            }
        }
        Ok(Points { points })
    }

    /// One point at time 0: the centre of face `face`.
    pub fn face(face: u32) -> Points {
        Points { points: vec![(0.0, Place::Face(face, None))] }
    }

    /// The points, as written.
    pub fn points(&self) -> &[(f64, Place)] {
        &self.points
    }

    /// Reads the file form: a list whose entries are a place, or `(seconds, place)`; a place is
    /// `(x, y, z)`, `face(F)` or `face(F, (b0, b1, b2))`.
    pub fn from_param(pv: &ParamValue) -> Result<Points, String> {
        let ParamValue::List(items) = pv else {
            return Err(format!("needs a list of points, e.g. {EXAMPLE}, got {pv}"));
        };
        let mut points = Vec::with_capacity(items.len());
        for (i, item) in items.iter().enumerate() {
            let at = |m: String| format!("point {}: {m}", i + 1);
            let timed = match item {
                ParamValue::List(pair) if pair.len() == 2 => number(&pair[0]).map(|t| (t, &pair[1])),
                _ => None,
            };
            let (time, place) = timed.unwrap_or((0.0, item));
            let place = Self::place(place).map_err(at)?;
            points.push((time, place));
        }
        Points::new(points)
    }

    fn place(pv: &ParamValue) -> Result<Place, String> {
        if let Some(p) = triple(pv) {
            return Ok(Place::At(p));
        }
        let ParamValue::Call(name, arg) = pv else {
            return Err(format!("a point is (x, y, z), face(F), face(F, (b0, b1, b2)) or (seconds, point), got {pv}"));
        };
        if name != "face" {
            return Err(format!("'{name}(…)' is not a place; write face(F) or (x, y, z)"));
        }
        let face = |v: &ParamValue| match v {
            ParamValue::Int(f) => u32::try_from(*f).map_err(|_| format!("face {f} is not a face index (0 or more)")),
            other => Err(format!("face(…) needs a face index, got {other}")),
        };
        match arg.as_ref() {
            ParamValue::List(a) if a.len() == 2 => {
                let bary = triple(&a[1])
                    .ok_or_else(|| format!("face(F, (b0, b1, b2)) needs three barycentric coordinates, got {}", a[1]))?;
                Ok(Place::Face(face(&a[0])?, Some(bary)))
            }
            other => Ok(Place::Face(face(other)?, None)),
        }
    }

    /// The file form (see [`Points::from_param`]); a point at time 0 is written bare.
    pub fn to_param(&self) -> ParamValue {
        let floats = |p: &[f64; 3]| ParamValue::List(p.iter().map(|x| ParamValue::Float(*x)).collect());
        let entry = |(time, place): &(f64, Place)| {
            let place = match place {
                Place::At(p) => floats(p),
                Place::Face(f, None) => ParamValue::Call("face".into(), Box::new(ParamValue::Int(i64::from(*f)))),
                Place::Face(f, Some(b)) => {
                    ParamValue::Call("face".into(), Box::new(ParamValue::List(vec![ParamValue::Int(i64::from(*f)), floats(b)])))
                }
            };
            if *time == 0.0 { place } else { ParamValue::List(vec![ParamValue::Float(*time), place]) }
        };
        ParamValue::List(self.points.iter().map(entry).collect())
    }

    /// Reads the text form older files hold: entries separated by `;`, each `x y z` or
    /// `face F [b0 b1 b2 | b1 b2]`, optionally followed by `@ seconds`.
    pub fn parse_legacy(text: &str) -> Result<Points, String> {
        let mut points = Vec::new();
        for (k, entry) in text.split(';').map(str::trim).filter(|s| !s.is_empty()).enumerate() {
            let at = |m: String| format!("point {} ('{entry}'): {m}", k + 1);
            let (body, time) = match entry.split_once('@') {
                Some((b, t)) => {
                    let t = t.trim();
                    (b.trim(), t.parse::<f64>().map_err(|_| at(format!("time '{t}' is not a number")))?)
                }
                None => (entry, 0.0),
            };
            let words: Vec<&str> = body.split([' ', ',', '\t']).filter(|w| !w.is_empty()).collect();
            let nums = |ws: &[&str]| -> Result<Vec<f64>, String> {
                ws.iter().map(|w| w.parse::<f64>().map_err(|_| at(format!("'{w}' is not a number")))).collect()
            };
            let place = if words.first() == Some(&"face") {
                let face =
                    words.get(1).and_then(|w| w.parse::<u32>().ok()).ok_or_else(|| at("'face' needs a face index".into()))?;
                let b = nums(&words[2..])?;
                Place::Face(
                    face,
                    match b.len() {
                        0 => None,
                        // Two coordinates are the second and third; the first makes the sum 1.
                        2 => Some([1.0 - b[0] - b[1], b[0], b[1]]),
                        3 => Some([b[0], b[1], b[2]]),
                        m => return Err(at(format!("needs 0, 2 or 3 barycentric coordinates, got {m}"))),
                    },
                )
            } else {
                match nums(&words)?.as_slice() {
                    [x, y, z] => Place::At([*x, *y, *z]),
                    _ => return Err(at("needs 'x y z' or 'face F [b0 b1 b2]'".into())),
                }
            };
            points.push((time, place));
        }
        Points::new(points)
    }

    /// Feeds the points into a hasher.
    pub fn hash_into(&self, h: &mut Fingerprinter) {
        self.points.len().hash(h);
        for (time, place) in &self.points {
            time.to_bits().hash(h);
            match place {
                Place::At(p) => (0u8, p.map(f64::to_bits)).hash(h),
                Place::Face(f, b) => (1u8, f, b.map(|b| b.map(f64::to_bits))).hash(h),
            }
        }
    }

    /// A one-line description, as the file writes it.
    pub fn summary(&self) -> String {
        self.to_param().to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read(text: &str) -> Result<Points, String> {
        Points::from_param(&ron::from_str(text).unwrap())
    }

    #[test]
    fn every_form_reads_and_writes_back() {
        let p = read("[(0.5, 0.2, -0.15), (2, (1.85, 0.1, 0.6)), face(3), (1.0, face(0, (0.2, 0.3, 0.5)))]").unwrap();
        assert_eq!(
            p.points(),
            &[
                (0.0, Place::At([0.5, 0.2, -0.15])),
                (2.0, Place::At([1.85, 0.1, 0.6])),
                (0.0, Place::Face(3, None)),
                (1.0, Place::Face(0, Some([0.2, 0.3, 0.5]))),
            ]
        );
        let written = ron::to_string(&p.to_param()).unwrap();
        assert_eq!(read(&written).unwrap(), p, "{written}");
        assert!(written.contains("face(3)") && written.contains("face(0,(0.2,0.3,0.5))"), "{written}");
    }

    #[test]
    fn legacy_text_reads_as_the_typed_form() {
        let legacy = Points::parse_legacy("-0.45 0.12 0.75; 1.85 0.1 0.6 @ 0.5; face 2 0.25 0.25").unwrap();
        assert_eq!(legacy, read("[(-0.45, 0.12, 0.75), (0.5, (1.85, 0.1, 0.6)), face(2, (0.5, 0.25, 0.25))]").unwrap());
        assert_eq!(Points::parse_legacy("face 0").unwrap(), read("[face(0)]").unwrap());
        assert!(Points::parse_legacy("1 2").unwrap_err().contains("point 1 ('1 2'): needs 'x y z'"));
        assert!(Points::parse_legacy("1 2 3 @ soon").unwrap_err().contains("time 'soon' is not a number"));
        assert!(Points::parse_legacy(" ; ").unwrap_err().contains("at least one point"));
    }

    #[test]
    fn bad_points_are_named() {
        assert!(read("[(0, 0, 0), (1, 2)]").unwrap_err().contains("point 2: a point is (x, y, z)"));
        assert!(read("[(-1, (0, 0, 0))]").unwrap_err().contains("point 1: the time must be"));
        assert!(read("[face(-2)]").unwrap_err().contains("face -2 is not a face index"));
        assert!(read("[face(1, (0.5, 0.5))]").unwrap_err().contains("three barycentric"));
        assert!(read("[keys([(0, 1)])]").unwrap_err().contains("'keys(…)' is not a place"));
        assert!(read("[]").unwrap_err().contains("at least one point"));
        assert!(read("\"0 0 0\"").unwrap_err().contains("needs a list of points"));
    }
}
