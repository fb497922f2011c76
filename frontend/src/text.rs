//! Front-end output made safe to show: [`printable_json`] for `--json` and the like, beside
//! core's [`printable`] for text (control characters escaped, overlong runs cut).

pub use pyrograph_core::text::printable;

/// Every string in a JSON value (keys too) made [`printable`], for a front end's `--json`
/// output: a consumer that prints a field shows no raw control character either. Walks the value
/// with its own stack, not by recursion.
pub fn printable_json(mut value: serde_json::Value) -> serde_json::Value {
    use serde_json::Value;
    let mut stack: Vec<&mut Value> = vec![&mut value];
    while let Some(v) = stack.pop() {
        match v {
            Value::String(s) => {
                if let std::borrow::Cow::Owned(clean) = printable(s.as_str()) {
                    *s = clean;
                }
            }
            Value::Array(items) => stack.extend(items.iter_mut()),
            Value::Object(map) => {
                if map.keys().any(|k| matches!(printable(k.as_str()), std::borrow::Cow::Owned(_))) {
                    let old = std::mem::take(map);
                    *map = old.into_iter().map(|(k, v)| (printable(k.as_str()).into_owned(), v)).collect();
                }
                stack.extend(map.values_mut());
            }
            _ => {}
        }
    }
    value
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn json_strings_and_keys_are_made_printable() {
        let v = serde_json::json!({"node": "a\u{1b}b", "list": [{"k\u{7}": "ok"}], "n": 1});
        let clean = printable_json(v);
        assert_eq!(clean["node"], "a\\u{1b}b");
        assert_eq!(clean["list"][0]["k\\u{7}"], "ok");
        assert_eq!(clean["n"], 1);
    }
}
