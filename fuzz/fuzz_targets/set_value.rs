//! The `--set` value parser, and the typed forms read from its result: point lists, ramps and
//! animated parameters of one and three components.
#![no_main]

use libfuzzer_sys::fuzz_target;
use pyrograph_core::ParamValue;
use pyrograph_core::anim::{Shape, from_param};
use pyrograph_core::value::{Points, RampKeys};

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        let v = ParamValue::parse_cli(text);
        let _ = Points::from_param(&v);
        let _ = RampKeys::from_param(&v, 4);
        let _ = from_param(&v, Shape::Float);
        let _ = from_param(&v, Shape::Vec3);
    }
});
