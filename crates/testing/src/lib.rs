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
}
