//! Test support shared by pyrograph's tests and benches: workspace and footage paths, seeded generators.
#![deny(missing_docs)]

use std::path::{Path, PathBuf};

/// The workspace root (the folder of the root `Cargo.toml`), for tests that read `graphs/`,
/// `docs/` or the sources.
pub fn workspace() -> PathBuf {
    // This crate lives at `<workspace>/crates/testing`.
    let here = Path::new(env!("CARGO_MANIFEST_DIR"));
    here.parent().and_then(Path::parent).expect("crates/testing lies two folders below the workspace root").to_path_buf()
}

/// A Python that has numpy, for the plugin tests: `PYROGRAPH_PYTHON`, `/usr/bin/python3`, then
/// `python3`, the first that imports numpy.
///
/// # Panics
/// When none does: those tests are ignored by default and run where `.ci/run` installed it.
pub fn python_with_numpy() -> std::ffi::OsString {
    let candidates = std::env::var_os("PYROGRAPH_PYTHON").into_iter().chain(["/usr/bin/python3".into(), "python3".into()]);
    for p in candidates {
        let ok = std::process::Command::new(&p).args(["-c", "import numpy"]).output().is_ok_and(|o| o.status.success());
        if ok {
            return p;
        }
    }
    panic!("needs python3 with numpy: none of PYROGRAPH_PYTHON, /usr/bin/python3, python3 imports it");
}

/// Whether a picture made now still matches its committed copy (thumbnails, node pictures): both
/// 8-bit RGBA, the same size, the mean difference under 1/255 and at most 0.5 % of samples more
/// than 8/255 apart, so float sums in another order or another libm do not count as a change.
pub fn pictures_match(made: &[u8], made_size: (u32, u32), want: &[u8], want_size: (u32, u32)) -> Result<(), String> {
    if made_size != want_size {
        return Err(format!("size {made_size:?}, committed {want_size:?}"));
    }
    if made.len() != want.len() || made.is_empty() {
        return Err(format!("{} samples against {}", made.len(), want.len()));
    }
    let far = made.iter().zip(want).filter(|(a, b)| a.abs_diff(**b) > 8).count() as f64 / made.len() as f64;
    let mean = made.iter().zip(want).map(|(a, b)| f64::from(a.abs_diff(*b))).sum::<f64>() / made.len() as f64;
    if mean > 1.0 || far > 0.005 {
        return Err(format!("mean difference {mean:.2}/255, {:.2} % of samples more than 8/255 apart", far * 100.0));
    }
    Ok(())
}

/// The real flame footage (never committed to the repository): `PYROGRAPH_FOOTAGE` when set,
/// else `<workspace>/../shared/footage`.
pub fn footage() -> PathBuf {
    std::env::var_os("PYROGRAPH_FOOTAGE").map(PathBuf::from).unwrap_or_else(|| {
        let ws = workspace();
        ws.parent().unwrap_or(&ws).join("shared").join("footage")
    })
}

/// A seeded linear congruential generator (Knuth's MMIX constants): the test data of every
/// crate's tests, reproducible without a random-number crate.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Lcg(pub u64);

impl Lcg {
    /// A generator whose state is `seed`.
    pub fn new(seed: u64) -> Self {
        Self(seed)
    }

    /// Advances the state and returns it.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        self.0
    }

    /// The next value in `[0, 1)`, from the top 24 bits of the state (the same sequence as [`lcg`]).
    pub fn next_f32(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32
    }

    /// The next value in `[0, 1)`, from the top 53 bits of the state.
    pub fn next_f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// One step of [`Lcg`] on a bare state: the next value in `[0, 1)` from the top 24 bits.
pub fn lcg(state: &mut u64) -> f32 {
    let mut g = Lcg(*state);
    let x = g.next_f32();
    *state = g.0;
    x
}

/// Marsaglia's xorshift64 (shifts 13, 7, 17): the synthetic frames of the eigen and imaging
/// benches. A different sequence from [`Lcg`]'s; the state must not be zero.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct XorShift(pub u64);

impl XorShift {
    /// Advances the state and returns it.
    pub fn next_u64(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }

    /// The next value in `[0, 1)`, from the top 24 bits of the state.
    pub fn next_f32(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32
    }
}

/// The bytes of a PNG file whose header declares `w` × `h` RGB pixels and which holds none: a
/// decompression bomb's header, for tests of the pixel budget.
pub fn png_declaring(w: u32, h: u32) -> Vec<u8> {
    // CRC-32 of a chunk's type and data, bit by bit: the test needs three small chunks.
    fn crc32(bytes: &[u8]) -> u32 {
        let mut c = !0u32;
        for b in bytes {
            c ^= u32::from(*b);
            for _ in 0..8 {
                c = if c & 1 == 1 { 0xEDB8_8320 ^ (c >> 1) } else { c >> 1 };
            }
        }
        !c
    }
    let chunk = |kind: &[u8], data: &[u8]| {
        let body = [kind, data].concat();
        [&(data.len() as u32).to_be_bytes()[..], &body, &crc32(&body).to_be_bytes()].concat()
    };
    let ihdr = [&w.to_be_bytes()[..], &h.to_be_bytes(), &[8, 2, 0, 0, 0]].concat();
    [&b"\x89PNG\r\n\x1a\n"[..], &chunk(b"IHDR", &ihdr), &chunk(b"IDAT", &[]), &chunk(b"IEND", &[])].concat()
}

/// Files f0 … f{levels}: each includes the next twice and adds their values; the last is one
/// node (`broken`: one with an unknown type). f0 flattens to 2^(levels + 1) − 1 nodes.
pub fn include_bomb(dir: &std::path::Path, levels: usize, broken: bool) -> std::path::PathBuf {
    for k in 0..=levels {
        let text = if k == levels {
            let ty = if broken { "math.nope" } else { "math.add" };
            format!(
                r#"(version: 1, interface: (outputs: {{"value": "x.value"}}), nodes: {{"x": (type: "{ty}", params: {{"a": 1.0}})}}, edges: [])"#
            )
        } else {
            let inc = |id: &str| format!(r#""{id}": (type: "graph.include", params: {{"path": "f{}.ron"}})"#, k + 1);
            format!(
                r#"(version: 1, interface: (outputs: {{"value": "s.value"}}), nodes: {{{}, {}, "s": (type: "math.add")}},
                    edges: [("a.value", "s.a"), ("b.value", "s.b")])"#,
                inc("a"),
                inc("b")
            )
        };
        std::fs::write(dir.join(format!("f{k}.ron")), text).unwrap();
    }
    dir.join("f0.ron")
}

/// A graph file's text: `math.add` nodes n0 → n1 → … → n{len − 1}, each adding 1 (so n{k}
/// cooks to k + 1), written the way a generator script writes it.
pub fn chain_ron(len: usize) -> String {
    let mut text = String::from("(version: 4, nodes: {\n");
    for i in 0..len {
        text.push_str(&format!("\"n{i}\": (type: \"math.add\", params: {{\"b\": 1.0}}),\n"));
    }
    text.push_str("}, edges: [\n");
    for i in 1..len {
        text.push_str(&format!("(\"n{}.value\", \"n{i}.a\"),\n", i - 1));
    }
    text.push_str("])\n");
    text
}

/// `seed` changed by one to six random edits drawn from `alphabet` (a character inserted, removed
/// or replaced, a run duplicated, the text cut short), for bounded fuzzing without a fuzzing
/// crate: the same kinds of edit as the proptest targets of `crates/core/tests/fuzz.rs`.
/// `alphabet` must not be empty.
pub fn mutated(seed: &str, alphabet: &str, rng: &mut XorShift) -> String {
    let alphabet: Vec<char> = alphabet.chars().collect();
    let mut text: Vec<char> = seed.chars().collect();
    let edits = 1 + (rng.next_u64() % 6) as usize;
    for _ in 0..edits {
        let at = if text.is_empty() { 0 } else { (rng.next_u64() % (text.len() as u64 + 1)) as usize };
        let pick = alphabet[(rng.next_u64() % alphabet.len() as u64) as usize];
        match rng.next_u64() % 5 {
            0 => text.insert(at, pick),
            1 if at < text.len() => {
                text.remove(at);
            }
            2 if at < text.len() => text[at] = pick,
            3 if at < text.len() => {
                let end = (at + 1 + (rng.next_u64() % 16) as usize).min(text.len());
                let run: Vec<char> = text[at..end].to_vec();
                let times = 1 + (rng.next_u64() % 64) as usize;
                for _ in 0..times {
                    text.splice(at..at, run.iter().copied());
                }
            }
            _ => text.truncate(at),
        }
    }
    text.into_iter().collect()
}

/// `code` (Rust source) with every `#[cfg(test)]` item blanked to spaces, newlines kept so line
/// numbers still match: a `mod tests;` line, a `mod tests { .. }` block, a test-only `use`,
/// wherever it stands. The source scans (layout, registration, port names) read shipped code
/// only; cutting a file at its first `#[cfg(test)]` would skip what follows a test module
/// declared mid-file. Braces inside strings, char literals and comments do not count.
pub fn without_test_items(code: &str) -> String {
    const ATTR: &str = "#[cfg(test)]";
    let mut out: Vec<u8> = code.as_bytes().to_vec();
    let mut from = 0;
    while let Some(at) = code[from..].find(ATTR).map(|i| from + i) {
        let end = item_end(code, at + ATTR.len());
        for b in &mut out[at..end] {
            if *b != b'\n' {
                *b = b' ';
            }
        }
        from = end;
    }
    // Only ASCII spaces replaced whole items, so this is valid UTF-8 unless an item split a
    // character, which `item_end` never does (it stops after an ASCII `;` or `}`).
    String::from_utf8(out).unwrap_or_else(|e| String::from_utf8_lossy(e.as_bytes()).into_owned())
}

/// Where the item starting at `from` ends: after its first `;` outside brackets, or after the
/// brace that closes its first `{`; skipping strings, char literals and comments.
fn item_end(code: &str, from: usize) -> usize {
    let b = code.as_bytes();
    let (mut i, mut brackets, mut braces) = (from, 0i32, 0i32);
    while i < b.len() {
        match b[i] {
            b'/' if b.get(i + 1) == Some(&b'/') => {
                i = code[i..].find('\n').map_or(b.len(), |n| i + n);
                continue;
            }
            b'"' => {
                i += 1;
                while i < b.len() && b[i] != b'"' {
                    i += if b[i] == b'\\' { 2 } else { 1 };
                }
            }
            b'r' if matches!(b.get(i + 1), Some(b'"' | b'#'))
                && !b[..i].last().is_some_and(|c| c.is_ascii_alphanumeric() || *c == b'_') =>
            {
                let hashes = b[i + 1..].iter().take_while(|&&c| c == b'#').count();
                if b.get(i + 1 + hashes) == Some(&b'"') {
                    let close = format!("\"{}", "#".repeat(hashes));
                    i = code[i + 2 + hashes..].find(&close).map_or(b.len(), |n| i + 2 + hashes + n + close.len());
                    continue;
                }
            }
            // A char literal ('{', '\''); a lifetime has no closing quote this close.
            b'\'' => {
                let len = if b.get(i + 1) == Some(&b'\\') { 3 } else { 2 };
                if b.get(i + len) == Some(&b'\'') {
                    i += len;
                }
            }
            b'(' | b'[' => brackets += 1,
            b')' | b']' => brackets -= 1,
            b';' if brackets == 0 && braces == 0 => return i + 1,
            b'{' if brackets == 0 => braces += 1,
            b'}' if brackets == 0 => {
                braces -= 1;
                if braces == 0 {
                    return i + 1;
                }
            }
            _ => {}
        }
        i += 1;
    }
    b.len()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_workspace_root_holds_the_root_manifest_and_no_dot_dot() {
        let ws = workspace();
        assert!(ws.join("Cargo.toml").is_file() && ws.join("crates/testing").is_dir(), "{}", ws.display());
        assert!(ws.components().all(|c| c != std::path::Component::ParentDir), "{}", ws.display());
    }

    #[test]
    fn footage_has_no_dot_dot() {
        let f = footage();
        assert!(std::env::var_os("PYROGRAPH_FOOTAGE").is_some() || f.ends_with("shared/footage"), "{}", f.display());
        if std::env::var_os("PYROGRAPH_FOOTAGE").is_none() {
            assert!(f.components().all(|c| c != std::path::Component::ParentDir), "{}", f.display());
            assert_eq!(f.parent().and_then(Path::parent), workspace().parent());
        }
    }

    #[test]
    fn lcg_keeps_the_sequence_of_the_copies_it_replaced() {
        // The formula the tests carried, written out.
        let copy = |s: &mut u64| {
            *s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((*s >> 40) as f32) / (1u64 << 24) as f32
        };
        let (mut a, mut b, mut g) = (4u64, 4u64, Lcg::new(4));
        for _ in 0..1000 {
            let x = copy(&mut a);
            assert_eq!(lcg(&mut b).to_bits(), x.to_bits());
            assert_eq!(g.next_f32().to_bits(), x.to_bits());
            assert!((0.0..1.0).contains(&x));
        }
        assert_eq!((a, b, g.0), (a, a, a));
    }

    #[test]
    fn xorshift_keeps_the_benches_sequence() {
        let (mut s, mut g) = (0x2545_F491_4F6C_DD1D_u64, XorShift(0x2545_F491_4F6C_DD1D));
        for _ in 0..1000 {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            assert_eq!(g.next_f32().to_bits(), ((s >> 40) as f32 / (1u64 << 24) as f32).to_bits());
        }
    }

    #[test]
    fn test_items_are_blanked_wherever_they_stand_and_lines_are_kept() {
        let code = "pub fn a() {}\n#[cfg(test)]\nmod tests;\npub fn b() { '{'; }\n#[cfg(test)]\nmod t {\n    fn s() -> &'static str { \"}\" } // }\n}\npub fn c() {}\n";
        let kept = without_test_items(code);
        assert_eq!(kept.lines().count(), code.lines().count());
        assert!(kept.contains("pub fn a()") && kept.contains("pub fn b()") && kept.contains("pub fn c()"), "{kept}");
        assert!(!kept.contains("mod") && !kept.contains("fn s"), "{kept}");
    }
}
