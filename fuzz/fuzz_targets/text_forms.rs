//! The old text forms of point lists and ramps, and the frame grammar (`0-99:2,120`).
#![no_main]

use std::str::FromStr;

use libfuzzer_sys::fuzz_target;
use pyrograph_core::FrameSet;
use pyrograph_core::value::{Points, RampKeys};

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        let _ = Points::parse_legacy(text);
        let _ = RampKeys::parse_legacy(text, 4);
        let _ = RampKeys::parse_legacy(text, 1);
        let _ = FrameSet::from_str(text);
    }
});
