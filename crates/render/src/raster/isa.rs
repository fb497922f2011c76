//! The instruction sets a band is rasterized with, and the token that proves AVX2 may be used.
//!
//! The rasterizer's safe functions are generic over [`Isa`] and reach an AVX2 kernel (the
//! `avx2` module) only through the token `Isa::avx2` gives them: [`Avx2`], a zero-sized token
//! that [`Avx2::detect`] alone creates, after checking the CPU; holding one is the proof. So the
//! AVX2 path cannot be taken without detection (it used to be chosen by a `const AVX2: bool`
//! parameter, whose soundness rested on every caller setting it only after checking). This file
//! is the bottom layer of the rasterizer: it knows nothing of what the kernels compute.

/// The instruction set a band is rasterized with: [`Portable`] code, or AVX2 kernels given the
/// [`Avx2`] proof. A type parameter rather than a run-time flag so that each path is compiled
/// on its own: the portable one without the kernels, the AVX2 one inlined into a
/// `#[target_feature(enable = "avx2")]` function (see [`Avx2::raster_band`]), where the
/// compiler may use AVX2 for the portable code around the kernels too.
pub(super) trait Isa: Copy {
    /// The proof that the AVX2 kernels may run, on the AVX2 path.
    fn avx2(self) -> Option<Avx2>;
}

/// Portable code only (SSE2 on x86-64).
#[derive(Clone, Copy, Debug)]
pub(super) struct Portable;

impl Isa for Portable {
    #[inline(always)]
    fn avx2(self) -> Option<Avx2> {
        None
    }
}

/// Proof that the CPU running this process supports AVX2: the private field keeps it from
/// being made anywhere but [`Avx2::detect`], which checks first.
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy, Debug)]
pub(super) struct Avx2 {
    _checked: (),
}

/// Proof that the CPU supports AVX2, which on this architecture cannot exist: no value, and the
/// kernels are not compiled.
#[cfg(not(target_arch = "x86_64"))]
#[derive(Clone, Copy, Debug)]
pub(super) enum Avx2 {}

impl Isa for Avx2 {
    #[inline(always)]
    fn avx2(self) -> Option<Avx2> {
        Some(self)
    }
}

impl Avx2 {
    /// The proof, if this CPU supports AVX2 (after the first call, a cached flag is read).
    #[inline]
    pub(super) fn detect() -> Option<Avx2> {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // The one place a token is made: just after the check.
            return Some(Avx2 { _checked: () });
        }
        None
    }
}
