//! The graph document loader (every version's shape, migrations, animated parameters, point
//! lists, ramps, presets, groups) on arbitrary text.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        let _ = pyrograph_core::GraphDoc::from_ron(text);
    }
});
