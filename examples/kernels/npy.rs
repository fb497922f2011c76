//! `.npy` in and out (npyz): the harness's exchange format with numpy.

use std::fs::File;
use std::io::{BufReader, BufWriter};
use std::path::Path;

use npyz::WriterBuilder;

/// A float32 array and its shape.
pub struct Array {
    pub shape: Vec<usize>,
    pub data: Vec<f32>,
}

/// Reads a float32 `.npy` (C order).
pub fn read_f32(path: &Path) -> Result<Array, String> {
    let file = File::open(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let npy = npyz::NpyFile::new(BufReader::new(file)).map_err(|e| format!("{}: {e}", path.display()))?;
    if npy.order() != npyz::Order::C {
        return Err(format!("{}: not in C order", path.display()));
    }
    let shape = npy.shape().iter().map(|&s| s as usize).collect();
    let data = npy.into_vec::<f32>().map_err(|e| format!("{}: {e} (want float32)", path.display()))?;
    Ok(Array { shape, data })
}

/// Writes `data` with `shape` as a `.npy` of `T` (f32 or f64).
pub fn write<T: npyz::AutoSerialize + Copy>(path: &Path, shape: &[usize], data: &[T]) -> Result<(), String> {
    let file = File::create(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let shape: Vec<u64> = shape.iter().map(|&s| s as u64).collect();
    let mut w = npyz::WriteOptions::new()
        .default_dtype()
        .shape(&shape)
        .writer(BufWriter::new(file))
        .begin_nd()
        .map_err(|e| format!("{}: {e}", path.display()))?;
    w.extend(data.iter().copied()).map_err(|e| format!("{}: {e}", path.display()))?;
    w.finish().map_err(|e| format!("{}: {e}", path.display()))
}

/// Checks an array's rank and returns its shape.
pub fn expect_rank<'a>(a: &'a Array, rank: usize, what: &str) -> Result<&'a [usize], String> {
    if a.shape.len() == rank { Ok(&a.shape) } else { Err(format!("{what}: expected {rank} dimensions, got shape {:?}", a.shape)) }
}
