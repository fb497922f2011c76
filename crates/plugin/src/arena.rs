//! The file a worker and pyrograph share for pixels: pyrograph writes a cook's input arrays into
//! it, Python maps it and views them as numpy arrays without a copy, writes its outputs after
//! them (growing the file when short) and pyrograph reads them back. A plain file in `/dev/shm`
//! (memory, on Linux) rather than `multiprocessing.shared_memory`, whose resource tracker
//! unlinks segments a worker merely attached to (cpython gh-82300). The path is unlinked once
//! the worker has opened it, so a crash on either side leaves nothing behind.

use std::fs::{File, OpenOptions};
use std::io;
use std::os::unix::fs::{FileExt, OpenOptionsExt};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// Array starts are multiples of this, so numpy's views are aligned for any dtype.
pub const ALIGN: u64 = 64;

/// One worker's shared file.
pub struct Arena {
    file: File,
    path: Option<PathBuf>,
}

impl Arena {
    /// Creates a fresh file only this user can read, in memory where the system has it.
    pub fn create() -> io::Result<Arena> {
        static NEXT: AtomicU64 = AtomicU64::new(0);
        let shm = Path::new("/dev/shm");
        let dir = if shm.is_dir() { shm.to_path_buf() } else { std::env::temp_dir() };
        let name = format!("pyrograph-{}-{}", std::process::id(), NEXT.fetch_add(1, Ordering::Relaxed));
        let path = dir.join(name);
        let file = OpenOptions::new().read(true).write(true).create_new(true).mode(0o600).open(&path)?;
        Ok(Arena { file, path: Some(path) })
    }

    /// The file's path, until [`Arena::unlink`].
    pub fn path(&self) -> Option<&Path> {
        self.path.as_deref()
    }

    /// Removes the file's name once the worker holds it open.
    pub fn unlink(&mut self) {
        if let Some(p) = self.path.take() {
            let _ = std::fs::remove_file(p);
        }
    }

    /// Writes `bytes` at `offset`, growing the file as needed.
    pub fn put(&self, offset: u64, bytes: &[u8]) -> io::Result<()> {
        let end = offset + bytes.len() as u64;
        if self.file.metadata()?.len() < end {
            self.file.set_len(end)?;
        }
        self.file.write_all_at(bytes, offset)
    }

    /// Reads `len` bytes at `offset` into `out`; an error when the file is shorter.
    pub fn get_into(&self, offset: u64, out: &mut [u8]) -> io::Result<()> {
        let size = self.file.metadata()?.len();
        if offset.checked_add(out.len() as u64).is_none_or(|end| end > size) {
            return Err(io::Error::new(
                io::ErrorKind::UnexpectedEof,
                format!("{} bytes at {offset} lie past the end of the {size}-byte shared file", out.len()),
            ));
        }
        self.file.read_exact_at(out, offset)
    }
}

impl Drop for Arena {
    fn drop(&mut self) {
        self.unlink();
    }
}

/// `offset` rounded up to [`ALIGN`].
pub fn aligned(offset: u64) -> u64 {
    offset.div_ceil(ALIGN) * ALIGN
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bytes_go_in_and_out_and_the_name_goes_away() {
        let mut a = Arena::create().unwrap();
        let path = a.path().unwrap().to_path_buf();
        a.put(128, &[1, 2, 3]).unwrap();
        let mut out = [0u8; 3];
        a.get_into(128, &mut out).unwrap();
        assert_eq!(out, [1, 2, 3]);
        assert!(a.get_into(130, &mut out).is_err(), "reading past the end is an error");
        a.unlink();
        assert!(!path.exists());
        a.put(0, &[9]).unwrap();
        a.get_into(0, &mut out[..1]).unwrap();
        assert_eq!(out[0], 9, "the open file still works without its name");
        assert_eq!((aligned(0), aligned(1), aligned(64), aligned(65)), (0, 64, 64, 128));
    }
}
