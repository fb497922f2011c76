//! Bounded fuzzing of the wedge parser (`render --wedge`, `--wedge-zip`, `job --wedge`): mutated
//! wedge arguments must parse or be refused, never panic, take under a second, or list more
//! variants than the limit. `PYROGRAPH_FUZZ_CASES` sets the count (100,000 by default), as for
//! the parsers of `crates/core/tests/fuzz.rs`.

use std::time::{Duration, Instant};

use pyrograph::wedge::{MAX_VARIANTS, Wedges};
use pyrograph_testing::{XorShift, mutated};

const SEEDS: &[&str] = &[
    "spread.K=0.5,1,2",
    "b.y=(1, 0, 0),(0, 1, 0),\"p,q\"",
    "flame.ramp=[(0, (1, 0, 0, 1)), (1, (1, 1, 0, 0))],keys([(0, 1.0), (24, 2.0)])",
    "a.x=1,2,3,4,5,6,7,8,9,10,11,12,13,14,15,16,17,18,19,20",
];
const ALPHABET: &str = "abcxyz.=,()[]{}\"'\\ 0123456789-+eE_keysexprface";

#[test]
fn the_wedge_parser_never_panics() {
    let cases: usize = std::env::var("PYROGRAPH_FUZZ_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(100_000);
    let mut rng = XorShift(0x5eed_f00d);
    let started = Instant::now();
    for i in 0..cases {
        let pick = |rng: &mut XorShift| mutated(SEEDS[(rng.next_u64() % SEEDS.len() as u64) as usize], ALPHABET, rng);
        // One to four axes and zero to two zipped parameters, some repeated whole.
        let wedge: Vec<String> = (0..1 + rng.next_u64() % 4).map(|_| pick(&mut rng)).collect();
        let zip: Vec<String> = (0..rng.next_u64() % 3).map(|_| pick(&mut rng)).collect();
        let t = Instant::now();
        if let Ok(w) = Wedges::parse(&wedge, &zip) {
            assert!(w.variants().len() <= MAX_VARIANTS, "case {i}: {wedge:?} {zip:?}");
        }
        assert!(t.elapsed() < Duration::from_secs(1), "case {i} took {:?}: {wedge:?} {zip:?}", t.elapsed());
    }
    println!("Wedges::parse: {cases} inputs in {:.1} s", started.elapsed().as_secs_f64());
}
