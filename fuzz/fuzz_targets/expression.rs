//! The expression parser, and an evaluation of what parses.
#![no_main]

use libfuzzer_sys::fuzz_target;
use pyrograph_core::anim::Expr;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data)
        && let Ok(e) = Expr::parse(text)
    {
        let _ = e.eval(12.5, 24.0);
    }
});
