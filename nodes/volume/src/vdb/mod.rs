//! OpenVDB files (format version 224, as OpenVDB 4 – 12 write it), written and read by hand:
//! no Rust crate reads or writes the format (the `vdb-rs` crate reads some files and writes none),
//! and linking the C++ library would put a C++ toolchain and Boost between a fresh machine and the
//! README's two commands. The layout follows OpenVDB's `io/Archive.cc`, `tree/RootNode.h`,
//! `tree/InternalNode.h`, `tree/LeafNode.h` and `io/Compression.h`; the tests check it against the
//! reference library (Debian's `python3-openvdb`).
//!
//! A volume's field is one grid: a float grid (`Tree_float_5_4_3`, or `…_HalfFloat` to halve
//! the file) or a vec3 grid (`Tree_vec3s_5_4_3`), with its transform as a
//! `UniformScaleTranslateMap`. Every voxel of an active brick is an active voxel of a leaf node, so
//! a file read back gives the same bricks and values. Reading takes float, double, half and vec3
//! grids, every compression OpenVDB writes (none, zlib, Blosc-LZ4, active-mask) and active tiles,
//! and refuses absurd sizes before allocating.

pub mod bytes;
pub mod codec;
pub mod nodes;
pub mod read;
pub mod sim_cache;
pub mod stage;
pub mod tree;
pub mod write;

pub use read::{ReadOptions, read_volume};
#[cfg(test)]
pub(crate) mod tests;
pub use write::{Compression, WriteOptions, write_volume};

/// The format version written (OpenVDB's `OPENVDB_FILE_VERSION` from 4.0 to 12).
pub const FILE_VERSION: u32 = 224;
/// The file's first eight bytes.
pub const MAGIC: [u8; 8] = [0x20, 0x42, 0x44, 0x56, 0, 0, 0, 0];
/// Value arrays are zlib streams.
pub const COMPRESS_ZIP: u32 = 1;
/// Value arrays hold active values only, after a byte saying what the inactive ones are.
pub const COMPRESS_ACTIVE_MASK: u32 = 2;
/// Value arrays are Blosc frames.
pub const COMPRESS_BLOSC: u32 = 4;

/// What is wrong with a file's content (the node adds the file's path).
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum VdbError {
    /// The file ends too early.
    #[error("the file is truncated: it ends at byte {at} inside {what}")]
    Truncated {
        /// Where.
        at: usize,
        /// Inside what.
        what: String,
    },
    /// The bytes are not a valid OpenVDB file.
    #[error("{0}")]
    Invalid(String),
    /// The file is valid but holds what pyrograph cannot use.
    #[error("{0}")]
    Unsupported(String),
    /// The file declares more voxels than the budget.
    #[error("{0}")]
    TooBig(String),
}
