//! A scratch file of training frames for out-of-core Eigenfires training ([`crate::pca::blocks`]).
//!
//! The block-wise Gram matrix reads every block of frames `B(B+1)/2 + 2B` times (B blocks). When
//! the frames come from a video or a chain of nodes, each read decodes or cooks them again: for
//! 10,000 frames of 410×670 in 21 blocks that is 133,000 decoded frames. So the first pass writes
//! the frames, exactly as read, to an unnamed temporary file (deleted by the system when it is
//! closed, even after a crash), and the later passes read them back from it.
//!
//! Plain positioned reads into the block buffers, not a memory map (memmap2): a mapped file's
//! pages count as the process's resident memory while they are cached, so mapping 11 GB of frames
//! would show up as 11 GB of RSS, while `read` into the two block buffers keeps the process at its
//! working set and leaves caching to the system's page cache.

use std::fs::File;
use std::io::{Read, Seek, SeekFrom, Write};
use std::ops::Range;
use std::path::Path;
use std::sync::Mutex;

/// Frames of `n` f32 samples each, stored by index in a temporary file.
pub struct FrameStore {
    file: Mutex<File>,
    n: usize,
}

impl FrameStore {
    /// An empty store in `dir` for frames of `n` samples.
    pub fn new(dir: &Path, n: usize) -> std::io::Result<FrameStore> {
        Ok(FrameStore { file: Mutex::new(tempfile::tempfile_in(dir)?), n })
    }

    fn file(&self) -> std::sync::MutexGuard<'_, File> {
        // Every use seeks before it reads or writes, so a poisoned file is still consistent.
        self.file.lock().unwrap_or_else(|p| p.into_inner())
    }

    fn offset(&self, frame: usize) -> u64 {
        (frame * self.n * 4) as u64
    }

    /// Stores frames `range` (`frames` holds them one after another).
    pub fn write(&self, range: Range<usize>, frames: &[f32]) -> std::io::Result<()> {
        debug_assert_eq!(frames.len(), range.len() * self.n);
        let mut f = self.file();
        f.seek(SeekFrom::Start(self.offset(range.start)))?;
        f.write_all(bytemuck::cast_slice(frames))
    }

    /// Reads frames `range` back into `out`, bit for bit as written.
    pub fn read(&self, range: Range<usize>, out: &mut [f32]) -> std::io::Result<()> {
        debug_assert_eq!(out.len(), range.len() * self.n);
        let mut f = self.file();
        f.seek(SeekFrom::Start(self.offset(range.start)))?;
        f.read_exact(bytemuck::cast_slice_mut(out))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_come_back_bit_for_bit_in_any_order() {
        let dir = tempfile::tempdir().unwrap();
        let store = FrameStore::new(dir.path(), 3).unwrap();
        let frames: Vec<f32> = (0..15).map(|i| i as f32 * 0.1 - 0.7).chain([f32::NAN, -0.0, 1e-40]).collect();
        store.write(0..4, &frames[..12]).unwrap();
        store.write(4..6, &frames[12..]).unwrap();
        let mut out = vec![0.0; 6];
        store.read(3..5, &mut out).unwrap();
        assert!(out.iter().zip(&frames[9..15]).all(|(a, b)| a.to_bits() == b.to_bits()));
        let mut last = vec![0.0; 3];
        store.read(5..6, &mut last).unwrap();
        assert!(last.iter().zip(&frames[15..]).all(|(a, b)| a.to_bits() == b.to_bits()));
        // Past what was written is an error, not zeros.
        assert!(store.read(6..7, &mut last).is_err());
        // The file has no name: nothing is left in the folder.
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    }
}
