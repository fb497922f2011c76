//! Reading and writing [`ParamValue`]: a form (`keys(…)`, `expr(…)`) arrives from RON as a
//! one-entry map and becomes [`ParamValue::Call`], and is written back as `keys([(0, 0.2), (40, 1.5, ease)])` — a named tuple
//! with bare interpolation names — so animated parameters stay as readable in a saved file as
//! they were typed.

use serde::de;
use serde::ser::{SerializeTuple, SerializeTupleVariant};
use serde::{Deserialize, Deserializer, Serialize, Serializer};

use super::ParamValue;

impl<'de> Deserialize<'de> for ParamValue {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        Raw::deserialize(d)?.into_param().map_err(de::Error::custom)
    }
}

/// What a file holds, read through serde's untagged machinery: RON gives that machinery (and
/// only it) the names of `keys(…)` and of bare identifiers such as `ease`, as one-entry maps
/// and strings; a hand-written visitor would be handed the bare contents without the name.
#[derive(Deserialize)]
#[serde(untagged)]
enum Raw {
    Bool(bool),
    Int(i64),
    Float(f64),
    String(String),
    List(Vec<Raw>),
    Map(std::collections::BTreeMap<String, Raw>),
}

impl Raw {
    fn into_param(self) -> Result<ParamValue, String> {
        Ok(match self {
            Raw::Bool(v) => ParamValue::Bool(v),
            Raw::Int(v) => ParamValue::Int(v),
            Raw::Float(v) => ParamValue::Float(v),
            Raw::String(v) => ParamValue::String(v),
            Raw::List(items) => ParamValue::List(items.into_iter().map(Raw::into_param).collect::<Result<_, _>>()?),
            Raw::Map(map) => {
                let mut entries = map.into_iter();
                match (entries.next(), entries.next()) {
                    (Some((name, arg)), None) => ParamValue::Call(name, Box::new(arg.into_param()?)),
                    (None, _) => {
                        return Err("an empty map is not a parameter value; write e.g. keys([(0, 1.0), (24, 2.0)])".into());
                    }
                    (Some((name, _)), Some(_)) => {
                        return Err(format!(
                            "a parameter value is one form such as keys([...]) or expr(\"...\"), not a map (found '{name}' and more)"
                        ));
                    }
                }
            }
        })
    }
}

/// Names written bare (as RON identifiers) inside a form: the interpolation and extrapolation
/// modes and the form names. Serde names variants with `&'static str`, so the set is closed.
const IDENTIFIERS: &[&str] = &["constant", "linear", "smooth", "ease", "hold", "cycle", "keys", "expr", "tangent", "face"];

fn identifier(name: &str) -> Option<&'static str> {
    IDENTIFIERS.iter().copied().find(|i| *i == name)
}

impl Serialize for ParamValue {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            ParamValue::Bool(v) => s.serialize_bool(*v),
            ParamValue::Int(v) => s.serialize_i64(*v),
            ParamValue::Float(v) => s.serialize_f64(*v),
            ParamValue::String(v) => s.serialize_str(v),
            ParamValue::List(items) => items.serialize(s),
            ParamValue::Call(name, arg) => serialize_form(name, arg, s),
        }
    }
}

fn serialize_form<S: Serializer>(name: &str, arg: &ParamValue, s: S) -> Result<S::Ok, S::Error> {
    let Some(variant) = identifier(name) else {
        // An unknown form (it fails validation) is kept as the map it was read as.
        return std::collections::BTreeMap::from([(name, arg)]).serialize(s);
    };
    match arg {
        // `keys([...], cycle)`: several arguments.
        ParamValue::List(items) if name != "keys" || ParamValue::key_args(items).is_some() => {
            let mut t = s.serialize_tuple_variant("ParamValue", 0, variant, items.len())?;
            for item in items {
                t.serialize_field(&Inner(item))?;
            }
            t.end()
        }
        other => s.serialize_newtype_variant("ParamValue", 0, variant, &Inner(other)),
    }
}

/// A value inside a form: lists are written as tuples (`(40, 1.5, ease)`) and mode names bare.
struct Inner<'a>(&'a ParamValue);

impl Serialize for Inner<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self.0 {
            ParamValue::String(text) => match identifier(text) {
                Some(name) => s.serialize_unit_variant("ParamValue", 0, name),
                None => s.serialize_str(text),
            },
            ParamValue::List(items) if items.iter().all(|i| !matches!(i, ParamValue::List(_))) => {
                let mut t = s.serialize_tuple(items.len())?;
                for item in items {
                    t.serialize_element(&Inner(item))?;
                }
                t.end()
            }
            ParamValue::List(items) => s.collect_seq(items.iter().map(Inner)),
            other => other.serialize(s),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> ParamValue {
        ron::from_str(text).unwrap()
    }

    #[test]
    fn forms_read_as_calls_and_write_back_as_typed() {
        for text in [
            "keys([(0, 0.2), (40, 1.5, ease), (72, 0.4)])",
            "keys([(0, 0.2), (40, 1.5, tangent(0.1, -0.2))], cycle)",
            "keys([(0, 0.2), (40, 1.5)], hold, linear)",
            "expr(\"0.5 + 0.2 * sin(time)\")",
        ] {
            let v = parse(text);
            assert!(matches!(v, ParamValue::Call(..)), "{text}: {v:?}");
            let written = ron::to_string(&v).unwrap();
            assert_eq!(written.replace(' ', ""), text.replace(' ', ""), "written as read");
            assert_eq!(parse(&written), v, "reads back the same");
        }
        let tuple = parse("(keys([(0, 0.0), (40, 2.5)]), 0, 0.5)");
        let ParamValue::List(items) = &tuple else { panic!("{tuple:?}") };
        assert!(matches!(&items[0], ParamValue::Call(n, _) if n == "keys"));
        assert_eq!(parse(&ron::to_string(&tuple).unwrap()), tuple);
    }

    #[test]
    fn literals_read_as_before_and_maps_are_refused() {
        assert_eq!(parse("7"), ParamValue::Int(7));
        assert_eq!(parse("0.5"), ParamValue::Float(0.5));
        assert_eq!(parse("true"), ParamValue::Bool(true));
        assert_eq!(parse("\"a\""), ParamValue::String("a".into()));
        assert_eq!(parse("ease"), ParamValue::String("ease".into()));
        assert_eq!(parse("(1, 2)"), ParamValue::List(vec![ParamValue::Int(1), ParamValue::Int(2)]));
        let err = ron::from_str::<ParamValue>("{\"a\": 1, \"b\": 2}").unwrap_err().to_string();
        assert!(err.contains("not a map"), "{err}");
    }
}
