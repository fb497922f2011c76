use super::*;
use crate::value::{PortType, Value};

fn pv(text: &str) -> ParamValue {
    ron::from_str(text).unwrap()
}

fn animated(text: &str, ty: PortType) -> Animated {
    crate::value::animated_param(&pv(text), &ty).unwrap().unwrap()
}

fn from_param(pv: &ParamValue, ty: &PortType) -> Result<Option<Animated>, String> {
    crate::value::animated_param(pv, ty)
}

#[test]
fn constants_are_not_animated_and_forms_are() {
    assert_eq!(from_param(&pv("0.5"), &PortType::Float).unwrap(), None);
    assert_eq!(from_param(&pv("(1, 2, 3)"), &PortType::Vec3).unwrap(), None);
    assert!(from_param(&pv("keys([(0, 1.0), (10, 2.0)])"), &PortType::Float).unwrap().is_some());
    assert!(from_param(&pv("expr(\"frame\")"), &PortType::Float).unwrap().is_some());
}

#[test]
fn vectors_animate_per_component_and_keep_their_constants() {
    let a = animated("(keys([(0, 0.0), (10, 2.0, linear)]), 0.5, expr(\"frame * 2\"))", PortType::Vec3);
    assert_eq!(a.tracks().len(), 3);
    let Value::Vec3(v) = a.sample(5.0, 24.0).unwrap() else { panic!() };
    assert_eq!(v, [1.0, 0.5, 10.0]);
    // A colour of three components gets an opaque alpha.
    let c = animated("(keys([(0, 0.0), (4, 1.0, linear)]), 0, 0)", PortType::Color);
    assert_eq!(c.sample(2.0, 24.0).unwrap().summary(), "(0.5, 0, 0, 1)");
}

#[test]
fn ints_round_and_bools_step() {
    let i = animated("keys([(0, 0), (10, 10, linear)])", PortType::Int);
    assert!(matches!(i.sample(4.4, 24.0).unwrap(), Value::Int(4)));
    assert!(matches!(i.sample(4.6, 24.0).unwrap(), Value::Int(5)));
    let b = animated("keys([(0, false), (10, true)])", PortType::Bool);
    assert!(matches!(b.sample(9.0, 24.0).unwrap(), Value::Bool(false)));
    assert!(matches!(b.sample(10.0, 24.0).unwrap(), Value::Bool(true)));
    let e = animated("expr(\"frame > 3\")", PortType::Bool);
    assert!(matches!(e.sample(4.0, 24.0).unwrap(), Value::Bool(true)));
}

#[test]
fn extrapolation_is_read_for_both_sides_or_each() {
    let both = animated("keys([(0, 0.0, linear), (10, 1.0)], cycle)", PortType::Float);
    let Track::Keys(c) = &both.tracks()[0] else { panic!() };
    assert_eq!((c.before(), c.after()), (Extrap::Cycle, Extrap::Cycle));
    let each = animated("keys([(0, 0.0, linear), (10, 1.0)], hold, linear)", PortType::Float);
    let Track::Keys(c) = &each.tracks()[0] else { panic!() };
    assert_eq!((c.before(), c.after()), (Extrap::Hold, Extrap::Linear));
    let Value::Float(x) = each.sample(20.0, 24.0).unwrap() else { panic!() };
    assert!((x - 2.0).abs() < 1e-9, "{x}");
}

#[test]
fn bad_forms_name_the_key_component_and_column() {
    let err = |text: &str, ty: PortType| from_param(&pv(text), &ty).unwrap_err();
    let e = err("keys([(0, 1.0), (40, 2.0), (20, 3.0)])", PortType::Float);
    assert!(e.contains("key 3") && e.contains("frame 20"), "{e}");
    let e = err("keys([(0, 1.0), (40, 2.0), (40, 3.0)])", PortType::Float);
    assert!(e.contains("40"), "{e}");
    let e = err("keys([(0, 1.0), (40, 2.0, wobble)])", PortType::Float);
    assert!(e.contains("key 2") && e.contains("wobble") && e.contains("smooth"), "{e}");
    let e = err("(0, keys([(0, \"x\")]), 0)", PortType::Vec3);
    assert!(e.contains("component 2 (y)") && e.contains("key 1"), "{e}");
    let e = err("expr(\"1 +* 2\")", PortType::Float);
    assert!(e.contains("column 4"), "{e}");
    let e = err("expr(\"framee\")", PortType::Float);
    assert!(e.contains("framee"), "{e}");
    let e = err("wiggle(3)", PortType::Float);
    assert!(e.contains("unknown form 'wiggle"), "{e}");
    let e = err("keys([(0, 1.0)])", PortType::String);
    assert!(e.contains("cannot be animated"), "{e}");
    let e = err("keys([(0, 1.0)])", PortType::Vec3);
    assert!(e.contains("per component"), "{e}");
    let e = err("(keys([(0, 1.0)]), 0)", PortType::Vec3);
    assert!(e.contains("3 components, got 2"), "{e}");
}

#[test]
fn a_sample_outside_the_range_names_the_frame() {
    let a = animated("keys([(0, 0.5, linear), (10, 0.5, linear), (20, 1.0)], hold, linear)", PortType::Float);
    assert!(a.sample_in(15.0, 24.0, Some((0.0, 1.0))).is_ok());
    let e = a.sample_in(30.0, 24.0, Some((0.0, 1.0))).unwrap_err();
    assert!(e.contains("at frame 30") && e.contains("1.5") && e.contains("0..=1"), "{e}");
    let nan = animated("expr(\"ln(frame - 10)\")", PortType::Float);
    let e = nan.sample_in(2.0, 24.0, None).unwrap_err();
    assert!(e.contains("frame 2"), "{e}");
}

#[test]
fn an_expression_nested_100000_deep_is_an_error_not_a_stack_overflow() {
    let deep = format!("expr(\"{}1{}\")", "(".repeat(100_000), ")".repeat(100_000));
    let e = from_param(&ParamValue::parse_cli(&deep), &PortType::Float).unwrap_err();
    assert!(e.contains("expression"), "{}", &e[..e.len().min(200)]);
}

#[test]
fn written_values_round_trip_through_a_document() {
    let text = "(keys([(0, 0.0), (40, 2.5, ease), (72, 0.4, tangent(0.1, -0.2))], hold, cycle), 0, expr(\"sin(time)\"))";
    let a = animated(text, PortType::Vec3);
    let again = animated(&ron::to_string(a.written()).unwrap(), PortType::Vec3);
    assert_eq!(a, again);
}
