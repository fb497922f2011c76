//! Ramps as typed document values: keys of a position in 0..1 and `width` components (a colour
//! ramp has four, a scalar curve over a particle's age one), written in a graph file as
//! `[(0.0, (1.0, 0.5, 0.0, 1.0)), (1.0, (1.0, 0.0, 0.0, 0.0))]` or `[(0, 0.67), (0.5, 1.07)]`.
//! They replace the text mini-language `"0: 1 0.5 0 1; 1: 1 0 0 0"`, which is still read from
//! older files.

use std::hash::Hash;

use crate::document::ParamValue;
use crate::fingerprint::Fingerprinter;

/// A ramp's keys, in position order: `(position, components)`, the unused components 0.
#[derive(Clone, Debug, PartialEq)]
pub struct RampKeys {
    width: usize,
    keys: Vec<(f64, [f64; 4])>,
}

impl RampKeys {
    /// Keys of `width` components (1 to 4); errors name the key (counted from 1).
    pub fn new(width: usize, keys: Vec<(f64, [f64; 4])>) -> Result<RampKeys, String> {
        if keys.is_empty() {
            return Err("a ramp needs at least one key, e.g. [(0.0, 1.0), (1.0, 0.0)]".into());
        }
        for (i, (pos, v)) in keys.iter().enumerate() {
            if !pos.is_finite() || v[..width].iter().any(|x| !x.is_finite()) {
                return Err(format!("key {}: positions and values must be finite numbers", i + 1));
            }
            if i > 0 && *pos < keys[i - 1].0 {
                return Err(format!(
                    "key {} at {pos} comes before key {} at {}: write keys in position order",
                    i + 1,
                    i,
                    keys[i - 1].0
                ));
            }
        }
        Ok(RampKeys { width, keys })
    }

    /// Components per key.
    pub fn width(&self) -> usize {
        self.width
    }

    /// The keys, in position order.
    pub fn keys(&self) -> &[(f64, [f64; 4])] {
        &self.keys
    }

    /// Reads the file form: a list of `(position, value)` keys, the value a number (one
    /// component) or a tuple of `width` numbers.
    pub fn from_param(pv: &ParamValue, width: usize) -> Result<RampKeys, String> {
        let example = if width == 1 { "[(0.0, 0.5), (1.0, 1.0)]" } else { "[(0.0, (1, 0.5, 0, 1)), (1.0, (1, 0, 0, 0))]" };
        let ParamValue::List(items) = pv else {
            return Err(format!("needs a list of (position, value) keys, e.g. {example}, got {pv}"));
        };
        let number = |v: &ParamValue| match v {
            ParamValue::Int(i) => Some(*i as f64),
            ParamValue::Float(x) => Some(*x),
            _ => None,
        };
        let mut keys = Vec::with_capacity(items.len());
        for (i, item) in items.iter().enumerate() {
            let at = |m: String| format!("key {}: {m}", i + 1);
            let ParamValue::List(pair) = item else { return Err(at(format!("a key is (position, value), got {item}"))) };
            let [pos, value] = pair.as_slice() else { return Err(at(format!("a key is (position, value), got {item}"))) };
            let pos = number(pos).ok_or_else(|| at(format!("the position must be a number, got {pos}")))?;
            let mut v = [0.0; 4];
            match (value, width) {
                (ParamValue::List(c), _) if c.len() == width => {
                    for (slot, x) in v.iter_mut().zip(c) {
                        *slot = number(x).ok_or_else(|| at(format!("{x} is not a number")))?;
                    }
                }
                (x, 1) => v[0] = number(x).ok_or_else(|| at(format!("the value must be a number, got {x}")))?,
                (x, _) => return Err(at(format!("the value needs {width} numbers, got {x}"))),
            }
            keys.push((pos, v));
        }
        RampKeys::new(width, keys)
    }

    /// The file form (see [`RampKeys::from_param`]).
    pub fn to_param(&self) -> ParamValue {
        let value = |v: &[f64; 4]| match self.width {
            1 => ParamValue::Float(v[0]),
            n => ParamValue::List(v[..n].iter().map(|x| ParamValue::Float(*x)).collect()),
        };
        ParamValue::List(self.keys.iter().map(|(p, v)| ParamValue::List(vec![ParamValue::Float(*p), value(v)])).collect())
    }

    /// Reads the text form older files hold, `"pos: v…; pos: v…"` (keys sorted by position, as
    /// that form's reader did).
    pub fn parse_legacy(text: &str, width: usize) -> Result<RampKeys, String> {
        let mut keys = Vec::new();
        for part in text.split(';').map(str::trim).filter(|s| !s.is_empty()) {
            let (pos, vals) =
                part.split_once(':').ok_or_else(|| format!("key '{part}' is not of the form 'position: values'"))?;
            let pos: f64 = pos.trim().parse().map_err(|_| format!("'{}' is not a number", pos.trim()))?;
            let nums: Vec<f64> = vals
                .split([' ', ','])
                .filter(|s| !s.is_empty())
                .map(|s| s.parse::<f64>().map_err(|_| format!("'{s}' is not a number")))
                .collect::<Result<_, _>>()?;
            if nums.len() != width {
                return Err(format!("key at {pos} has {} values, needs {width}", nums.len()));
            }
            let mut v = [0.0; 4];
            v[..width].copy_from_slice(&nums);
            keys.push((pos, v));
        }
        keys.sort_by(|a, b| a.0.total_cmp(&b.0));
        RampKeys::new(width, keys)
    }

    /// Feeds the keys into a hasher.
    pub fn hash_into(&self, h: &mut Fingerprinter) {
        self.width.hash(h);
        for (p, v) in &self.keys {
            p.to_bits().hash(h);
            v[..self.width].iter().for_each(|x| x.to_bits().hash(h));
        }
    }

    /// A one-line description, as the file writes it: `[(0, (1, 0.5, 0, 1)), (1, (1, 0, 0, 0))]`.
    pub fn summary(&self) -> String {
        let keys: Vec<String> = match self.to_param() {
            ParamValue::List(keys) => keys.iter().map(ToString::to_string).collect(),
            other => vec![other.to_string()],
        };
        format!("[{}]", keys.join(", "))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn legacy_text_and_keys_read_the_same() {
        let legacy = RampKeys::parse_legacy("1: 0 0 0 0; 0: 1 0.5 0 1", 4).unwrap();
        let typed: ParamValue = ron::from_str("[(0.0, (1, 0.5, 0, 1)), (1.0, (0, 0, 0, 0))]").unwrap();
        assert_eq!(RampKeys::from_param(&typed, 4).unwrap(), legacy);
        assert_eq!(RampKeys::from_param(&legacy.to_param(), 4).unwrap(), legacy);
        let curve: ParamValue = ron::from_str("[(0, 0.67), (0.5, 1.07), (1, 0.67)]").unwrap();
        assert_eq!(RampKeys::from_param(&curve, 1).unwrap(), RampKeys::parse_legacy("0: 0.67; 0.5: 1.07; 1: 0.67", 1).unwrap());
    }

    #[test]
    fn bad_keys_are_named() {
        let err = |text: &str, w: usize| RampKeys::from_param(&ron::from_str(text).unwrap(), w).unwrap_err();
        assert!(err("[(0, (1, 0, 0, 1)), (1, (1, 0))]", 4).contains("key 2: the value needs 4 numbers"));
        assert!(err("[(0.5, 1), (0.2, 0)]", 1).contains("key 2 at 0.2 comes before key 1"));
        assert!(err("[(\"a\", 1)]", 1).contains("key 1: the position must be a number"));
        assert!(err("[]", 1).contains("at least one key"));
        assert!(err("\"0: 1\"", 1).contains("needs a list"));
    }
}
