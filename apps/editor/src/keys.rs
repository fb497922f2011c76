//! Keyframes of a scalar (Float or Int) parameter as the editor edits them: read from the
//! parameter's [`ParamValue`] (`keys([(frame, value), (frame, value, interpolation), …][,
//! extrapolation[, extrapolation]])`) and written back after an edit. Pure functions, no UI.
//!
//! Rules:
//! - **Kept as written.** Interpolation names (`ease`, `tangent(0.1, -0.2)`) and extrapolations
//!   (`keys([…], cycle)`) are carried over untouched, and so is every key an edit does not touch
//!   (`(0, 1)` stays `(0, 1)`, not `(0, 1.0)`); a key an edit makes or changes is written with a whole frame as
//!   an integer and, for an Int parameter, a whole value as an integer.
//! - **One key per frame.** Setting a key at a frame that has one replaces its value (keeping its
//!   interpolation); moving a key onto a frame another key holds is refused (the error says which);
//!   pasted keys replace the keys at their frames. Keys stay in frame order: a move past a
//!   neighbour reorders them and reports the key's new index.
//! - **First and last key.** Setting a key on a constant parameter makes it `keys([(frame, value)])`;
//!   removing the last key makes the parameter the constant that key held.

use pyrograph_frontend::core::ParamValue;

/// Frames closer than this are the same frame.
pub const SAME_FRAME: f64 = 1e-6;

/// One key as the document holds it.
#[derive(Clone, Debug, PartialEq)]
pub struct KeyDoc {
    /// The frame.
    pub frame: f64,
    /// The value at that frame.
    pub value: f64,
    /// The interpolation as written (`ease`, `tangent(…)`), or `None` for the default (smooth).
    pub interp: Option<ParamValue>,
    /// The key exactly as read, while no edit has changed it (so untouched keys are written back
    /// as they were typed).
    written: Option<ParamValue>,
}

impl KeyDoc {
    /// A new key (written afresh).
    pub fn new(frame: f64, value: f64, interp: Option<ParamValue>) -> Self {
        KeyDoc { frame, value, interp, written: None }
    }

    fn to_param(&self, int: bool) -> ParamValue {
        if let Some(w) = &self.written {
            return w.clone();
        }
        let mut parts = vec![number(self.frame, true), number(self.value, int)];
        parts.extend(self.interp.clone());
        ParamValue::List(parts)
    }
}

/// The keys of one keyed parameter, with its extrapolation arguments as written.
#[derive(Clone, Debug, PartialEq)]
pub struct KeyList {
    /// The keys, in frame order.
    pub keys: Vec<KeyDoc>,
    /// The extrapolations after the key list (`cycle`, or `hold, linear`), as written.
    pub extrap: Vec<ParamValue>,
}

/// A number as written: an integer when `int` and whole, else a float.
fn number(x: f64, int: bool) -> ParamValue {
    if int && x.fract() == 0.0 && x.abs() < 9.0e15 { ParamValue::Int(x as i64) } else { ParamValue::Float(x) }
}

fn as_f64(pv: &ParamValue) -> Option<f64> {
    match pv {
        ParamValue::Int(v) => Some(*v as f64),
        ParamValue::Float(v) => Some(*v),
        _ => None,
    }
}

/// The value of a constant scalar parameter (true/false as 1 and 0).
pub fn constant(pv: &ParamValue) -> Option<f64> {
    match pv {
        ParamValue::Bool(b) => Some(if *b { 1.0 } else { 0.0 }),
        other => as_f64(other),
    }
}

/// Whether `pv` is an expression, `expr("…")`.
pub fn is_expr(pv: &ParamValue) -> bool {
    matches!(pv, ParamValue::Call(name, _) if name == "expr")
}

/// Refuses a frame or value that is not a finite number.
fn finite(frame: f64, value: f64) -> Result<(), String> {
    if !frame.is_finite() {
        return Err(format!("a key's frame must be a number, got {frame}"));
    }
    if !value.is_finite() {
        return Err(format!("a key's value must be a number, got {value}"));
    }
    Ok(())
}

/// Formats a frame for messages: `12`, or `12.5`.
pub fn frame_text(frame: f64) -> String {
    if frame.fract() == 0.0 { format!("{frame:.0}") } else { format!("{frame}") }
}

impl KeyList {
    /// Reads `keys(…)`; `None` for anything else (a constant, an expression, a malformed form).
    pub fn read(pv: &ParamValue) -> Option<KeyList> {
        let ParamValue::Call(name, arg) = pv else { return None };
        if name != "keys" {
            return None;
        }
        let ParamValue::List(items) = &**arg else { return None };
        // As the loader reads it: `keys([k, …])` arrives as the key list, `keys([k, …], cycle)`
        // as [[k, …], cycle].
        let (list, extrap) = match ParamValue::key_args(items) {
            Some((list, extras)) => (list, extras.to_vec()),
            None => (items.as_slice(), Vec::new()),
        };
        let mut keys = Vec::with_capacity(list.len());
        for k in list {
            let ParamValue::List(parts) = k else { return None };
            let (frame, value, interp) = match parts.as_slice() {
                [f, v] => (as_f64(f)?, as_f64(v)?, None),
                [f, v, m] => (as_f64(f)?, as_f64(v)?, Some(m.clone())),
                _ => return None,
            };
            keys.push(KeyDoc { frame, value, interp, written: Some(k.clone()) });
        }
        (!keys.is_empty()).then_some(KeyList { keys, extrap })
    }

    /// The parameter value: `keys([…])` or `keys([…], extrapolations…)`.
    pub fn to_param(&self, int: bool) -> ParamValue {
        let list = ParamValue::List(self.keys.iter().map(|k| k.to_param(int)).collect());
        let arg = if self.extrap.is_empty() {
            list
        } else {
            let mut items = vec![list];
            items.extend(self.extrap.iter().cloned());
            ParamValue::List(items)
        };
        ParamValue::Call("keys".into(), Box::new(arg))
    }

    /// The index of the key at `frame`.
    pub fn find(&self, frame: f64) -> Option<usize> {
        self.keys.iter().position(|k| (k.frame - frame).abs() < SAME_FRAME)
    }

    /// Sets a key at `frame`: replaces the value of the key there (keeping its interpolation) or
    /// inserts a new key in frame order. Returns its index.
    pub fn set(&mut self, frame: f64, value: f64) -> Result<usize, String> {
        finite(frame, value)?;
        if let Some(i) = self.find(frame) {
            let k = &mut self.keys[i];
            if k.value != value {
                *k = KeyDoc::new(k.frame, value, k.interp.clone());
            }
            return Ok(i);
        }
        let i = self.keys.partition_point(|k| k.frame < frame);
        self.keys.insert(i, KeyDoc::new(frame, value, None));
        Ok(i)
    }

    /// Removes key `index`; returns it.
    pub fn remove(&mut self, index: usize) -> Result<KeyDoc, String> {
        if index >= self.keys.len() {
            return Err(format!("there is no key {} (the parameter has {})", index + 1, self.keys.len()));
        }
        Ok(self.keys.remove(index))
    }

    /// Moves key `index` to (`frame`, `value`), keeping frame order: a move past a neighbour
    /// reorders the keys. Refused when another key is at `frame` (two keys never share a frame).
    /// Returns the key's new index.
    pub fn move_to(&mut self, index: usize, frame: f64, value: f64) -> Result<usize, String> {
        finite(frame, value)?;
        let Some(k) = self.keys.get(index) else {
            return Err(format!("there is no key {} (the parameter has {})", index + 1, self.keys.len()));
        };
        if let Some(other) = self.find(frame).filter(|&j| j != index) {
            return Err(format!("key {} is already at frame {}: two keys cannot share a frame", other + 1, frame_text(frame)));
        }
        if (k.frame - frame).abs() < SAME_FRAME && k.value == value {
            return Ok(index);
        }
        let moved = KeyDoc::new(frame, value, k.interp.clone());
        self.keys.remove(index);
        let i = self.keys.partition_point(|k| k.frame < frame);
        self.keys.insert(i, moved);
        Ok(i)
    }

    /// Copies keys `indices` (in frame order), frames relative to the first of them.
    pub fn copy(&self, indices: &[usize]) -> Vec<KeyDoc> {
        let mut picked: Vec<&KeyDoc> = indices.iter().filter_map(|&i| self.keys.get(i)).collect();
        picked.sort_by(|a, b| a.frame.total_cmp(&b.frame));
        picked.dedup_by(|a, b| a.frame == b.frame);
        let Some(first) = picked.first().map(|k| k.frame) else { return Vec::new() };
        picked.into_iter().map(|k| KeyDoc::new(k.frame - first, k.value, k.interp.clone())).collect()
    }

    /// Pastes `copied` (frames relative, as [`KeyList::copy`] gives them) with the first at
    /// `at`; a pasted key replaces the key at its frame, interpolation included. Returns the
    /// pasted keys' indices.
    pub fn paste(&mut self, copied: &[KeyDoc], at: f64) -> Result<Vec<usize>, String> {
        for k in copied {
            finite(at + k.frame, k.value)?;
        }
        let frames: Vec<f64> = copied.iter().map(|k| at + k.frame).collect();
        self.keys.retain(|k| !frames.iter().any(|f| (k.frame - f).abs() < SAME_FRAME));
        for (k, frame) in copied.iter().zip(&frames) {
            let i = self.keys.partition_point(|x| x.frame < *frame);
            self.keys.insert(i, KeyDoc::new(*frame, k.value, k.interp.clone()));
        }
        Ok(frames.iter().filter_map(|f| self.find(*f)).collect())
    }
}

/// The keys of `pv`, or a new list for a constant (`None` for expressions and other forms).
fn keys_or_new(pv: &ParamValue) -> Result<Option<KeyList>, String> {
    if let Some(list) = KeyList::read(pv) {
        return Ok(Some(list));
    }
    if is_expr(pv) {
        return Err("an expression drives this parameter: edit it in the text field, or stop animating it first".into());
    }
    if constant(pv).is_some() {
        return Ok(None);
    }
    Err(format!("keys are set on numbers; this parameter holds {pv}"))
}

/// `pv` with a key at (`frame`, `value`): a constant becomes `keys([(frame, value)])`, a key
/// already at `frame` takes the value. Returns the new value and the key's index.
pub fn set_key(pv: &ParamValue, frame: f64, value: f64, int: bool) -> Result<(ParamValue, usize), String> {
    match keys_or_new(pv)? {
        Some(mut list) => {
            let i = list.set(frame, value)?;
            Ok((list.to_param(int), i))
        }
        None => {
            finite(frame, value)?;
            let list = KeyList { keys: vec![KeyDoc::new(frame, value, None)], extrap: Vec::new() };
            Ok((list.to_param(int), 0))
        }
    }
}

/// `pv` without key `index`; the last key removed leaves the constant it held.
pub fn remove_key(pv: &ParamValue, index: usize, int: bool) -> Result<ParamValue, String> {
    let mut list = KeyList::read(pv).ok_or("the parameter has no keys")?;
    let gone = list.remove(index)?;
    Ok(if list.keys.is_empty() { number(gone.value, int) } else { list.to_param(int) })
}

/// `pv` with key `index` moved to (`frame`, `value`); returns it and the key's new index.
pub fn move_key(pv: &ParamValue, index: usize, frame: f64, value: f64, int: bool) -> Result<(ParamValue, usize), String> {
    let mut list = KeyList::read(pv).ok_or("the parameter has no keys")?;
    let i = list.move_to(index, frame, value)?;
    Ok((list.to_param(int), i))
}

/// `pv` with key `index` given the explicit slope `slope` (value per frame) on both sides:
/// `tangent(slope)`, as a tangent handle dragged in the curve editor writes it.
pub fn set_tangent(pv: &ParamValue, index: usize, slope: f64, int: bool) -> Result<ParamValue, String> {
    if !slope.is_finite() {
        return Err(format!("a tangent's slope must be a finite number, got {slope}"));
    }
    set_interp(pv, index, ParamValue::Call("tangent".into(), Box::new(ParamValue::Float(slope))), int)
}

/// `pv` with key `index` given the interpolation `interp` (`constant`, `tangent(0.1)`, …).
pub fn set_interp(pv: &ParamValue, index: usize, interp: ParamValue, int: bool) -> Result<ParamValue, String> {
    let mut list = KeyList::read(pv).ok_or("the parameter has no keys")?;
    let n = list.keys.len();
    let key = list.keys.get_mut(index).ok_or_else(|| format!("there is no key {} (the curve has {n})", index + 1))?;
    key.interp = Some(interp);
    key.written = None;
    Ok(list.to_param(int))
}

/// `pv` with `copied` keys pasted from frame `at` (a constant becomes keyed).
pub fn paste_keys(pv: &ParamValue, copied: &[KeyDoc], at: f64, int: bool) -> Result<ParamValue, String> {
    if copied.is_empty() {
        return Err("no keys to paste: copy a key first".into());
    }
    let mut list = keys_or_new(pv)?.unwrap_or(KeyList { keys: Vec::new(), extrap: Vec::new() });
    list.paste(copied, at)?;
    Ok(list.to_param(int))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pv(text: &str) -> ParamValue {
        ParamValue::parse_cli(text)
    }

    /// The value as the file would hold it, spaces dropped.
    fn text(v: &ParamValue) -> String {
        v.to_string().replace(' ', "")
    }

    #[test]
    fn a_tangent_is_written_on_its_key_alone() {
        let v = set_tangent(&pv("keys([(0, 0.2), (40, 1.5, ease), (72, 0.4)], cycle)"), 1, 0.05, false).unwrap();
        assert_eq!(text(&v), "keys([(0,0.2),(40,1.5,tangent(0.05)),(72,0.4)],cycle)");
        assert!(set_tangent(&v, 3, 0.1, false).unwrap_err().contains("no key 4"));
        assert!(set_tangent(&v, 0, f64::NAN, false).is_err());
    }

    #[test]
    fn reads_keys_interpolations_and_extrapolations() {
        let list = KeyList::read(&pv("keys([(0, 0.2), (40, 1.5, ease), (72, 0.4, tangent(0.1, -0.2))], hold, linear)")).unwrap();
        let frames: Vec<f64> = list.keys.iter().map(|k| k.frame).collect();
        assert_eq!(frames, [0.0, 40.0, 72.0]);
        assert_eq!(list.keys[1].value, 1.5);
        assert_eq!(list.keys[0].interp, None);
        assert_eq!(list.keys[1].interp, Some(ParamValue::String("ease".into())));
        assert!(matches!(&list.keys[2].interp, Some(ParamValue::Call(n, _)) if n == "tangent"));
        assert_eq!(list.extrap, [ParamValue::String("hold".into()), ParamValue::String("linear".into())]);
        // One key, one extrapolation; not keys at all.
        let one = KeyList::read(&pv("keys([(5, 1)], cycle)")).unwrap();
        assert_eq!((one.keys.len(), one.extrap.len()), (1, 1));
        assert!(KeyList::read(&pv("0.5")).is_none());
        assert!(KeyList::read(&pv("expr(\"sin(time)\")")).is_none());
        assert!(KeyList::read(&pv("keys([(0, \"a\")])")).is_none(), "a key that is not numbers");
    }

    #[test]
    fn unedited_keys_write_back_as_typed() {
        for t in [
            "keys([(0, 0.2), (40, 1.5, ease), (72, 0.4)])",
            "keys([(0, 1), (10, 2, linear)], cycle)",
            "keys([(0, 0.2), (40, 1.5, tangent(0.1, -0.2))], hold, linear)",
            "keys([(2.5, 3)])",
        ] {
            let v = pv(t);
            assert_eq!(KeyList::read(&v).unwrap().to_param(false), v, "{t}");
        }
    }

    #[test]
    fn setting_a_key_on_a_constant_keys_it_and_a_second_key_goes_in_frame_order() {
        let (v, i) = set_key(&ParamValue::Float(0.4), 12.0, 0.4, false).unwrap();
        assert_eq!((text(&v), i), ("keys([(12,0.4)])".into(), 0));
        let (v, i) = set_key(&v, 3.0, 1.0, false).unwrap();
        assert_eq!((text(&v), i), ("keys([(3,1.0),(12,0.4)])".into(), 0));
        let (v, i) = set_key(&v, 30.0, 2.0, false).unwrap();
        assert_eq!((text(&v), i), ("keys([(3,1.0),(12,0.4),(30,2.0)])".into(), 2));
        // Int parameters write whole values as integers; fractional frames stay fractional.
        let (v, _) = set_key(&ParamValue::Int(4), 1.5, 4.0, true).unwrap();
        assert_eq!(text(&v), "keys([(1.5,4)])");
        assert!(set_key(&v, f64::NAN, 1.0, true).is_err());
        assert!(set_key(&ParamValue::Float(0.0), 1.0, f64::INFINITY, false).is_err());
    }

    #[test]
    fn setting_a_key_where_one_is_replaces_its_value_and_keeps_the_rest_as_written() {
        let v = pv("keys([(0, 0.2), (40, 1.5, ease), (72, 0.4)], cycle)");
        let (v, i) = set_key(&v, 40.0, 2.0, false).unwrap();
        assert_eq!(i, 1);
        assert_eq!(text(&v), "keys([(0,0.2),(40,2.0,ease),(72,0.4)],cycle)");
    }

    #[test]
    fn an_expression_or_a_string_takes_no_keys() {
        let e = set_key(&pv("expr(\"sin(time)\")"), 0.0, 1.0, false).unwrap_err();
        assert!(e.contains("expression"), "{e}");
        let e = set_key(&ParamValue::String("x".into()), 0.0, 1.0, false).unwrap_err();
        assert!(e.contains("numbers"), "{e}");
    }

    #[test]
    fn removing_keys_down_to_none_leaves_the_constant_the_last_held() {
        let v = pv("keys([(0, 0.2), (40, 1.5, ease)], cycle)");
        let v = remove_key(&v, 0, false).unwrap();
        assert_eq!(text(&v), "keys([(40,1.5,ease)],cycle)");
        assert_eq!(remove_key(&v, 0, false).unwrap(), ParamValue::Float(1.5));
        assert_eq!(remove_key(&pv("keys([(3, 7)])"), 0, true).unwrap(), ParamValue::Int(7));
        assert!(remove_key(&v, 5, false).unwrap_err().contains("no key 6"));
        assert!(remove_key(&ParamValue::Float(1.0), 0, false).is_err());
    }

    #[test]
    fn moving_a_key_past_a_neighbour_reorders_and_onto_one_is_refused() {
        let v = pv("keys([(0, 0.2), (10, 1.0, ease), (20, 0.4, linear)])");
        let (moved, i) = move_key(&v, 1, 5.0, 0.8, false).unwrap();
        assert_eq!((text(&moved), i), ("keys([(0,0.2),(5,0.8,ease),(20,0.4,linear)])".into(), 1));
        let (moved, i) = move_key(&v, 0, 15.0, 0.3, false).unwrap();
        assert_eq!((text(&moved), i), ("keys([(10,1.0,ease),(15,0.3),(20,0.4,linear)])".into(), 1));
        let (moved, i) = move_key(&v, 0, 25.0, 0.3, false).unwrap();
        assert_eq!((text(&moved), i), ("keys([(10,1.0,ease),(20,0.4,linear),(25,0.3)])".into(), 2));
        let e = move_key(&v, 0, 20.0, 0.3, false).unwrap_err();
        assert!(e.contains("key 3 is already at frame 20"), "{e}");
        // Moving onto its own frame changes the value only; no change changes nothing.
        let (moved, i) = move_key(&v, 2, 20.0, 0.5, false).unwrap();
        assert_eq!((text(&moved), i), ("keys([(0,0.2),(10,1.0,ease),(20,0.5,linear)])".into(), 2));
        assert_eq!(move_key(&v, 2, 20.0, 0.4, false).unwrap(), (v.clone(), 2));
        assert!(move_key(&v, 3, 1.0, 1.0, false).is_err());
    }

    #[test]
    fn copied_keys_paste_relative_to_the_playhead_and_replace_keys_at_their_frames() {
        let v = pv("keys([(0, 0.2), (10, 1.0, ease), (20, 0.4)])");
        let list = KeyList::read(&v).unwrap();
        let copied = list.copy(&[2, 1]);
        assert_eq!(copied, [KeyDoc::new(0.0, 1.0, Some(ParamValue::String("ease".into()))), KeyDoc::new(10.0, 0.4, None)]);
        let pasted = paste_keys(&v, &copied, 20.0, false).unwrap();
        assert_eq!(text(&pasted), "keys([(0,0.2),(10,1.0,ease),(20,1.0,ease),(30,0.4)])");
        // Onto a constant: it becomes keyed.
        let pasted = paste_keys(&ParamValue::Float(3.0), &copied, 4.0, false).unwrap();
        assert_eq!(text(&pasted), "keys([(4,1.0,ease),(14,0.4)])");
        assert!(paste_keys(&v, &[], 0.0, false).is_err());
    }
}
