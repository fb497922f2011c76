use std::sync::Arc;

use super::*;
use crate::TimeDep;

crate::choice! {
    /// A test enumeration.
    pub enum Shade {
        /// Light.
        Light = "light",
        /// Dark.
        Dark = "dark",
    }
}

crate::ports! {
    /// A shared group.
    pub struct Pair {
        /// Left.
        #[range(0, 10)]
        left: u32 = 3,
        /// Right.
        right: bool = true,
    }
}

crate::node! {
    /// Summary line that wraps
    /// onto a second line.
    ///
    /// Second paragraph.
    #[node("test.declared", "Tests", PerFrame)]
    pub struct Declared1 {
        /// The image.
        image: Arc<Image>,
        /// A gain.
        #[range(0.0, 2.0)]
        gain: f32 = 0.5,
        /// A shade.
        shade: Shade = Shade::Dark,
        /// The pair.
        pair: Pair,
        /// A keyword-named port.
        r#type: String = "x".to_string(),
        /// Where to write.
        out: OutputPath = "a.png".into(),
    }
    pub struct Declared1Out {
        /// The gain, back.
        gain: f64,
        /// The frames.
        frames: ClipOf<Arc<Image>>,
    }
}

fn defaults(desc: &NodeDesc, image: Value) -> Vec<Value> {
    desc.inputs.iter().map(|p| p.default.clone().unwrap_or_else(|| image.clone())).collect()
}

#[test]
fn the_declaration_gives_the_description() {
    let d = Declared1::desc();
    assert_eq!(d.type_name, "test.declared");
    assert_eq!(d.time, TimeDep::PerFrame);
    assert_eq!(d.doc, "Summary line that wraps onto a second line.\n\nSecond paragraph.");
    assert_eq!(d.summary(), "Summary line that wraps onto a second line.");
    let names: Vec<_> = d.inputs.iter().map(|p| p.name.as_str()).collect();
    assert_eq!(names, ["image", "gain", "shade", "left", "right", "type", "out"]);
    assert!(d.inputs[0].is_required());
    assert_eq!(d.inputs[0].ty, PortType::Image);
    assert_eq!(d.inputs[1].range, Some((0.0, 2.0)));
    assert!(matches!(d.inputs[1].default, Some(Value::Float(v)) if v == 0.5));
    assert_eq!(d.inputs[2].options, ["light", "dark"]);
    assert!(matches!(&d.inputs[2].default, Some(Value::Enum(s)) if s == "dark"));
    assert_eq!(d.inputs[3].range, Some((0.0, 10.0)));
    assert_eq!(d.inputs[3].doc, "Left.");
    assert_eq!(d.inputs[6].path_role, Some(PathRole::Output));
    let outs: Vec<_> = d.outputs.iter().map(|p| (p.name.as_str(), p.ty.clone())).collect();
    assert_eq!(outs, [("gain", PortType::Float), ("frames", PortType::clip_of(PortType::Image))]);
}

#[test]
fn the_reader_types_every_field() {
    let d = Declared1::desc();
    let img = Value::Image(Arc::new(Image::new(2, 1, crate::Channels::Gray)));
    let values = defaults(&d, img);
    let p = Declared1::read(&Inputs::new(&d, &values)).unwrap();
    assert_eq!(p.gain, 0.5f32);
    assert_eq!(p.shade, Shade::Dark);
    assert_eq!((p.pair.left, p.pair.right), (3, true));
    assert_eq!(p.r#type, "x");
    assert_eq!(&*p.out, std::path::Path::new("a.png"));
    assert_eq!(p.image.width(), 2);
}

#[test]
fn a_bad_value_names_its_port() {
    let d = Declared1::desc();
    let img = Value::Image(Arc::new(Image::new(2, 1, crate::Channels::Gray)));
    let mut values = defaults(&d, img);
    values[3] = Value::Int(-1);
    let e = Declared1::read(&Inputs::new(&d, &values)).unwrap_err().to_string();
    assert!(e.contains("left") && e.contains("-1 is outside the range 0..=10"), "{e}");
    values[3] = Value::Int(1);
    values[2] = Value::Enum("dim".into());
    let e = Declared1::read(&Inputs::new(&d, &values)).unwrap_err().to_string();
    assert!(e.contains("shade") && e.contains("unknown option 'dim' (light, dark)"), "{e}");
    values[2] = Value::Enum("light".into());
    values[1] = Value::Bool(true);
    let e = Declared1::read(&Inputs::new(&d, &values)).unwrap_err().to_string();
    assert!(e.contains("gain") && e.contains("needs Float, got Bool"), "{e}");
}

#[test]
fn a_value_over_an_edge_is_range_checked_like_one_from_the_file() {
    let d = Declared1::desc();
    let img = Value::Image(Arc::new(Image::new(2, 1, crate::Channels::Gray)));
    let mut values = defaults(&d, img);
    for (bad, shown) in [(Value::Float(3.0), "3"), (Value::Float(f64::NAN), "NaN"), (Value::Int(-1), "-1")] {
        values[1] = bad;
        let e = Declared1::read(&Inputs::new(&d, &values)).unwrap_err().to_string();
        assert!(e.contains("port 'gain'") && e.contains(&format!("{shown} is outside the range 0..=2")), "{e}");
    }
    values[1] = Value::Float(2.0);
    assert!(Declared1::read(&Inputs::new(&d, &values)).is_ok(), "the ends of the range are in it");
}

#[test]
fn port_names_a_field() {
    assert_eq!(crate::port!(Declared1, gain), "gain");
    assert_eq!(crate::port!(Declared1, r#type), "type");
    assert_eq!(crate::port!(Pair, left), "left");
}

#[test]
fn an_int_on_a_float_port_widens() {
    assert_eq!(f32::from_value(&Value::Int(3)), Ok(3.0));
    assert_eq!(u8::from_value(&Value::Int(256)), Err("256 is outside 0..=255".to_string()));
}

#[test]
fn f32_defaults_print_as_written() {
    assert!(matches!(0.1f32.into_value(), Value::Float(v) if v == 0.1));
    assert!(matches!([0.3f32, 1.0, -2.5].into_value(), Value::Vec3(v) if v == [0.3, 1.0, -2.5]));
    for x in [0.1f32, 1e-7, 3.4e38, -0.0, 123.456] {
        assert_eq!(f32::from_value(&x.into_value()), Ok(x));
    }
}

#[test]
fn doc_text_joins_lines_and_keeps_paragraphs() {
    assert_eq!(doc_text(&[" a", " b", "", "", " c  "]), "a b\n\nc");
    assert_eq!(doc_text(&[]), "");
}
