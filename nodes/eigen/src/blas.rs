//! The system's OpenBLAS, when one is installed, for the two products where faer trails it: the
//! training's Gram matrix (eq. 16, a `syrk`) and batch reconstruction (eq. 22, a `gemm`). faer
//! stays the default and the fallback: nothing links against OpenBLAS, the library is opened at
//! run time, so a machine without it builds, runs and gets the same results from faer.
//!
//! Why: at the thesis sizes faer's f32 kernels ran 10 % (Intel, AVX-512) to 50 % (AMD Zen 3,
//! AVX2) slower than OpenBLAS's (BENCHMARKS.md, § Products at BLAS speed), and no maintained
//! pure-Rust kernel crate was faster than faer here (`gemm` and `matrixmultiply` were slower
//! still on the reconstruction's shape). `PYROGRAPH_BLAS` chooses: unset tries the usual names
//! of the OpenBLAS library; `off` keeps faer; a path opens that library. Only OpenBLAS is used
//! (it must export `openblas_get_config`): a reference BLAS, often the system's `libblas.so.3`,
//! is slower than faer.

use std::ffi::{CStr, c_char, c_int};
use std::sync::{Mutex, OnceLock};

use libloading::Library;

type Sgemm = unsafe extern "C" fn(
    c_int,
    c_int,
    c_int,
    c_int,
    c_int,
    c_int,
    f32,
    *const f32,
    c_int,
    *const f32,
    c_int,
    f32,
    *mut f32,
    c_int,
);
type Ssyrk = unsafe extern "C" fn(c_int, c_int, c_int, c_int, c_int, f32, *const f32, c_int, f32, *mut f32, c_int);
type SetThreads = unsafe extern "C" fn(c_int);
type GetConfig = unsafe extern "C" fn() -> *const c_char;

// CBLAS's enumerations (cblas.h).
const COL_MAJOR: c_int = 102;
const NO_TRANS: c_int = 111;
const TRANS: c_int = 112;
const LOWER: c_int = 122;

/// An opened OpenBLAS: its CBLAS products and its thread count.
pub struct OpenBlas {
    sgemm: Sgemm,
    ssyrk: Ssyrk,
    set_threads: SetThreads,
    /// `openblas_get_config()`: version, build options and the kernel it picked for this CPU.
    pub config: String,
    /// Held while a product runs: OpenBLAS's thread count is process-wide, and one product
    /// already uses every thread it is given.
    lock: Mutex<()>,
    // Last, so the symbols above are dropped first (the library is never unloaded anyway).
    _lib: Library,
}

/// The system's OpenBLAS, opened on first use, or `None` (not installed, or `PYROGRAPH_BLAS=off`).
pub fn openblas() -> Option<&'static OpenBlas> {
    static BLAS: OnceLock<Option<OpenBlas>> = OnceLock::new();
    BLAS.get_or_init(|| {
        let choice = std::env::var_os("PYROGRAPH_BLAS");
        let names: Vec<std::ffi::OsString> = match &choice {
            Some(v) if v == "off" || v == "faer" || v.is_empty() => return None,
            Some(path) => vec![path.clone()],
            None => [
                "libopenblas.so.0",
                "libopenblas.so",
                "libopenblas.0.dylib",
                "libopenblas.dylib",
                "libopenblas.dll",
                "openblas.dll",
            ]
            .iter()
            .map(Into::into)
            .collect(),
        };
        names.iter().find_map(|name| open(name))
    })
    .as_ref()
}

fn open(name: &std::ffi::OsStr) -> Option<OpenBlas> {
    // SAFETY: loading OpenBLAS runs its initialisers, which only set up its thread pool and
    // detect the CPU; the symbols are looked up with their CBLAS signatures (cblas.h, LP64: the
    // ILP64 build is a separate library, `libopenblas64`).
    unsafe {
        let lib = Library::new(name).ok()?;
        let get_config = *lib.get::<GetConfig>(b"openblas_get_config\0").ok()?;
        let sgemm = *lib.get::<Sgemm>(b"cblas_sgemm\0").ok()?;
        let ssyrk = *lib.get::<Ssyrk>(b"cblas_ssyrk\0").ok()?;
        let set_threads = *lib.get::<SetThreads>(b"openblas_set_num_threads\0").ok()?;
        let config = get_config();
        let config = if config.is_null() { String::new() } else { CStr::from_ptr(config).to_string_lossy().into_owned() };
        // An ILP64 build (64-bit integers, named in its configuration) would read these
        // declarations' 32-bit sizes wrongly.
        if config.contains("USE64BITINT") {
            return None;
        }
        Some(OpenBlas { sgemm, ssyrk, set_threads, config, lock: Mutex::new(()), _lib: lib })
    }
}

/// A dimension as CBLAS's `int`, or `None` past its range (the caller then uses faer).
fn dim(x: usize) -> Option<c_int> {
    c_int::try_from(x).ok().filter(|&d| d > 0)
}

impl OpenBlas {
    /// Runs `f` with OpenBLAS on as many threads as the current rayon pool has, so the
    /// products follow `RAYON_NUM_THREADS` like the rest of pyrograph.
    fn with_threads<R>(&self, f: impl FnOnce() -> R) -> R {
        let _held = self.lock.lock().unwrap_or_else(|e| e.into_inner());
        let threads = c_int::try_from(rayon::current_num_threads()).unwrap_or(1);
        // SAFETY: plain setter of OpenBLAS's thread count.
        unsafe { (self.set_threads)(threads) };
        f()
    }

    /// `c = a · b + c` in column-major storage: `a` is `m × k` with `m = a.len() / k`
    /// (`lda = m`), `b` is `k × n` (column stride `ldb`, its first `k` rows used), `c` is
    /// `m × n` (`ldc = m`). Returns `false`, doing nothing, when a size does not fit CBLAS's
    /// `int` or is zero.
    pub fn gemm_add(&self, a: &[f32], k: usize, b: &[f32], ldb: usize, n: usize, c: &mut [f32]) -> bool {
        let m = a.len().checked_div(k).unwrap_or(0);
        let (Some(mi), Some(ni), Some(ki), Some(ldbi)) = (dim(m), dim(n), dim(k), dim(ldb)) else {
            return false;
        };
        assert!(a.len() == m * k && ldb >= k && b.len() >= ldb * (n - 1) + k && c.len() >= m * n, "gemm_add: slices too short");
        self.with_threads(|| {
            // SAFETY: the slices hold the sizes asserted above, and CBLAS reads and writes
            // nothing outside them; `c` is borrowed mutably, so nothing else aliases it.
            unsafe {
                (self.sgemm)(
                    COL_MAJOR,
                    NO_TRANS,
                    NO_TRANS,
                    mi,
                    ni,
                    ki,
                    1.0,
                    a.as_ptr(),
                    mi,
                    b.as_ptr(),
                    ldbi,
                    1.0,
                    c.as_mut_ptr(),
                    mi,
                )
            }
        });
        true
    }

    /// The lower triangle of `g = aᵀ a` for `a` of `k × n` in column-major storage (`lda = k`),
    /// into `g` (`n × n`, column-major; the upper triangle is left as it was). Returns `false`,
    /// doing nothing, when a size does not fit CBLAS's `int`.
    pub fn gram_lower(&self, k: usize, n: usize, a: &[f32], g: &mut [f32]) -> bool {
        let (Some(ki), Some(ni)) = (dim(k), dim(n)) else {
            return false;
        };
        assert!(a.len() >= k * n && g.len() >= n * n, "gram_lower: slices too short");
        self.with_threads(|| {
            // SAFETY: as in `gemm_add`.
            unsafe { (self.ssyrk)(COL_MAJOR, LOWER, TRANS, ni, ki, 1.0, a.as_ptr(), ki, 0.0, g.as_mut_ptr(), ni) }
        });
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// When OpenBLAS is installed (CI installs it), its products equal plain sums.
    #[test]
    fn openblas_products_equal_plain_sums_when_it_is_installed() {
        let Some(blas) = openblas() else {
            eprintln!("OpenBLAS is not installed here: faer does every product");
            return;
        };
        assert!(blas.config.contains("OpenBLAS"), "{}", blas.config);
        let (m, n, k, ldb) = (37, 5, 11, 13);
        let a: Vec<f32> = (0..m * k).map(|i| ((i * 31) % 17) as f32 - 8.0).collect();
        let b: Vec<f32> = (0..ldb * n).map(|i| ((i * 7) % 5) as f32 - 2.0).collect();
        let mut c: Vec<f32> = (0..m * n).map(|i| i as f32).collect();
        assert!(blas.gemm_add(&a, k, &b, ldb, n, &mut c));
        for j in 0..n {
            for i in 0..m {
                let want = (i + j * m) as f32 + (0..k).map(|l| a[i + l * m] * b[l + j * ldb]).sum::<f32>();
                assert_eq!(c[i + j * m], want, "({i}, {j})");
            }
        }
        let mut g = vec![f32::NAN; n * n];
        assert!(blas.gram_lower(k, n, &b[..k * n], &mut g));
        for j in 0..n {
            for i in j..n {
                let want: f32 = (0..k).map(|l| b[l + i * k] * b[l + j * k]).sum();
                assert_eq!(g[i + j * n], want, "({i}, {j})");
            }
        }
        assert!(!blas.gemm_add(&a, 0, &b, ldb, n, &mut c), "an empty product is left to the caller");
    }
}
