//! The Eigenfires database on disk (thesis §4.1 off-line mode, §4.8 packs).
//!
//! A database is a folder: `database.ron`, a versioned RON header (sizes, eigenvalues, frame
//! sources, and the length and checksum of every binary file), `mean.bin` (the mean image) and
//! `pack_001.bin`, `pack_002.bin`, … Each pack holds `pack_size` consecutive eigenfires (`N`
//! little-endian f32 each) followed by the training weights of those components (`M` f32 per
//! component). Dropping the last packs (§4.8: "ignore, remove or truncate the packages") leaves a
//! smaller valid database: loading stops at the first missing pack, or loads only the first `E`
//! components when asked. Every file is written atomically and the header last; a truncated,
//! altered or foreign file is a clear error.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use pyrograph_core::declare::{Cook, InputPath, OutputPath};
use pyrograph_core::document::write_atomic;
use pyrograph_core::{CookCtx, NodeError, port};
use serde::{Deserialize, Serialize};

use crate::pca::Database;
use crate::values::{Basis, FrameRef, Weights};

/// The `format` string of a header.
pub const FORMAT: &str = "pyrograph-eigenfires";
/// The current on-disk version.
pub const VERSION: u32 = 1;
/// The header's file name inside the database folder.
pub const HEADER: &str = "database.ron";
/// The checksum algorithm named in headers.
pub const CHECKSUM: &str = "fnv1a64-words";

/// One binary file of a database.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FileEntry {
    /// File name inside the folder.
    pub file: String,
    /// Its exact length in bytes.
    pub bytes: u64,
    /// [`checksum`] of its bytes.
    pub checksum: u64,
}

/// A pack of consecutive eigenfires and their weight columns.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PackEntry {
    /// First component (0-based).
    pub first: usize,
    /// Number of components.
    pub count: usize,
    /// The file.
    pub data: FileEntry,
}

/// The RON header (`database.ron`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Header {
    /// Always [`FORMAT`].
    pub format: String,
    /// On-disk version ([`VERSION`]).
    pub version: u32,
    /// Frame width.
    pub width: u32,
    /// Frame height.
    pub height: u32,
    /// Training frames `M`.
    pub frames: usize,
    /// Eigenfires `E` in all packs.
    pub components: usize,
    /// Components per pack.
    pub pack_size: usize,
    /// Checksum algorithm ([`CHECKSUM`]).
    pub checksum: String,
    /// Eigenvalues, largest first.
    pub eigenvalues: Vec<f64>,
    /// Source clip and frame of each training frame.
    pub sources: Vec<(u32, u32)>,
    /// The mean image file.
    pub mean: FileEntry,
    /// The packs, in component order.
    pub packs: Vec<PackEntry>,
}

/// FNV-1a over little-endian 64-bit words (the tail zero-padded), then the length.
pub fn checksum(bytes: &[u8]) -> u64 {
    const PRIME: u64 = 0x0000_0100_0000_01B3;
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let mut chunks = bytes.chunks_exact(8);
    for c in &mut chunks {
        let mut w = [0u8; 8];
        w.copy_from_slice(c);
        h = (h ^ u64::from_le_bytes(w)).wrapping_mul(PRIME);
    }
    let rest = chunks.remainder();
    if !rest.is_empty() {
        let mut w = [0u8; 8];
        w[..rest.len()].copy_from_slice(rest);
        h = (h ^ u64::from_le_bytes(w)).wrapping_mul(PRIME);
    }
    (h ^ bytes.len() as u64).wrapping_mul(PRIME)
}

fn f32_bytes(values: impl Iterator<Item = f32>, len: usize) -> Vec<u8> {
    let mut out = Vec::with_capacity(len * 4);
    values.for_each(|v| out.extend_from_slice(&v.to_le_bytes()));
    out
}

fn write_file(dir: &Path, name: &str, bytes: &[u8], overwrite: bool) -> Result<FileEntry, String> {
    let path = dir.join(name);
    write_atomic(&path, bytes, overwrite).map_err(|e| format!("writing {}: {e}", path.display()))?;
    Ok(FileEntry { file: name.to_string(), bytes: bytes.len() as u64, checksum: checksum(bytes) })
}

/// Writes `db` into folder `dir` in packs of `pack_size` components; the header goes last.
/// Returns the files written, in the order they were written.
pub fn save(db: &Database, dir: &Path, pack_size: usize, overwrite: bool) -> Result<Vec<PathBuf>, String> {
    let (b, w) = (&db.basis, &db.weights);
    let (n, m, e) = (b.pixels(), b.sources.len(), b.components());
    if w.frames != m || w.components != e {
        return Err(format!(
            "the weights ({} frames x {} components) do not belong to the basis ({m} frames, {e} components)",
            w.frames, w.components
        ));
    }
    if pack_size == 0 {
        return Err("pack_size must be at least 1".into());
    }
    if !overwrite && dir.join(HEADER).exists() {
        return Err(format!("{} already holds a database; set overwrite to replace it", dir.display()));
    }
    std::fs::create_dir_all(dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    let mean = write_file(dir, "mean.bin", &f32_bytes(b.mean.iter().copied(), n), true)?;
    let mut packs = Vec::new();
    let mut first = 0;
    while first < e {
        let count = pack_size.min(e - first);
        let vecs = &b.eigenvectors[first * n..(first + count) * n];
        let cols = (first..first + count).flat_map(|c| (0..m).map(move |f| w.data[f * e + c]));
        let mut bytes = f32_bytes(vecs.iter().copied(), count * (n + m));
        bytes.extend(f32_bytes(cols, count * m));
        let name = format!("pack_{:03}.bin", packs.len() + 1);
        packs.push(PackEntry { first, count, data: write_file(dir, &name, &bytes, true)? });
        first += count;
    }
    let header = Header {
        format: FORMAT.into(),
        version: VERSION,
        width: b.width,
        height: b.height,
        frames: m,
        components: e,
        pack_size,
        checksum: CHECKSUM.into(),
        eigenvalues: b.eigenvalues.clone(),
        sources: b.sources.iter().map(|s| (s.clip, s.index)).collect(),
        mean,
        packs,
    };
    let text = ron::ser::to_string_pretty(&header, ron::ser::PrettyConfig::default()).map_err(|e| e.to_string())?;
    let path = dir.join(HEADER);
    write_atomic(&path, text.as_bytes(), true).map_err(|e| format!("writing {}: {e}", path.display()))?;
    let mut written = vec![dir.join(&header.mean.file)];
    written.extend(header.packs.iter().map(|p| dir.join(&p.data.file)));
    written.push(path);
    Ok(written)
}

/// Reads and validates the header of the database in `dir`.
pub fn read_header(dir: &Path) -> Result<Header, String> {
    let path = dir.join(HEADER);
    pyrograph_core::limits::may_read(&path)?;
    let text = std::fs::read_to_string(&path)
        .map_err(|e| format!("cannot read {}: {e} (is this an Eigenfires database folder?)", path.display()))?;
    let h: Header = ron::from_str(&text).map_err(|e| format!("{} is not an Eigenfires database header: {e}", path.display()))?;
    if h.format != FORMAT {
        return Err(format!("{} has format '{}', expected '{FORMAT}'", path.display(), h.format));
    }
    if h.version != VERSION {
        return Err(format!("{} is database version {}, this build reads version {VERSION}", path.display(), h.version));
    }
    if h.checksum != CHECKSUM {
        return Err(format!("{}: unknown checksum '{}'", path.display(), h.checksum));
    }
    // The header names its binary files: only plain names inside the folder, so a hostile or
    // corrupt header cannot send the reader elsewhere (`../../secret`, `/etc/passwd`).
    for entry in std::iter::once(&h.mean).chain(h.packs.iter().map(|p| &p.data)) {
        let mut parts = Path::new(&entry.file).components();
        if !matches!((parts.next(), parts.next()), (Some(std::path::Component::Normal(_)), None)) {
            return Err(format!(
                "{}: names the data file \"{}\", which is not a file name inside the database folder",
                path.display(),
                entry.file
            ));
        }
    }
    let n = h.width as u64 * h.height as u64;
    let mut next = 0;
    for p in &h.packs {
        if p.first != next || p.count == 0 || p.data.bytes != p.count as u64 * (n + h.frames as u64) * 4 {
            return Err(format!("{}: pack {} is inconsistent with the header's sizes", path.display(), p.data.file));
        }
        next += p.count;
    }
    if next != h.components || h.eigenvalues.len() != h.components || h.sources.len() != h.frames || h.mean.bytes != n * 4 {
        return Err(format!("{}: header sizes disagree (components, eigenvalues, frames or mean)", path.display()));
    }
    Ok(h)
}

fn read_checked(dir: &Path, entry: &FileEntry) -> Result<Vec<u8>, String> {
    let path = dir.join(&entry.file);
    pyrograph_core::limits::may_read(&path)?;
    let bytes = std::fs::read(&path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    if bytes.len() as u64 != entry.bytes {
        return Err(format!(
            "{} is {} bytes, the header says {}: the file is truncated or from another database",
            path.display(),
            bytes.len(),
            entry.bytes
        ));
    }
    if checksum(&bytes) != entry.checksum {
        return Err(format!("{} fails its checksum: the file is corrupt or from another database", path.display()));
    }
    Ok(bytes)
}

fn f32s(bytes: &[u8]) -> impl Iterator<Item = f32> + '_ {
    bytes.chunks_exact(4).map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
}

/// Loads the first `components` eigenfires (0 = every pack present: loading stops at the first
/// missing pack file) of the database in `dir`.
pub fn load(dir: &Path, components: usize) -> Result<Database, String> {
    let h = read_header(dir)?;
    if components > h.components {
        return Err(format!(
            "asks for {components} components but the database holds {}; use at most {} (0 = all)",
            h.components, h.components
        ));
    }
    let present = h.packs.iter().take_while(|p| dir.join(&p.data.file).exists()).map(|p| p.count).sum::<usize>();
    let e = if components == 0 { present } else { components };
    if e > present {
        let missing = h.packs.iter().find(|p| !dir.join(&p.data.file).exists()).map(|p| p.data.file.clone()).unwrap_or_default();
        return Err(format!("asks for {e} components but {missing} is missing: only the first {present} are on disk"));
    }
    let (n, m) = (h.width as usize * h.height as usize, h.frames);
    let mean: Vec<f32> = f32s(&read_checked(dir, &h.mean)?).collect();
    // On huge pages where the system allows (see `pages`): the products read the eigenfires in
    // columns a frame apart, and at 410×670 pixels and E 1,100 a reconstruction of 64 frames
    // took 356–365 ms on one thread from a basis on 2 MiB pages against 402–424 ms from 4 KiB
    // pages, as numpy's own arrays get (BENCHMARKS.md, § Products at BLAS speed).
    let mut eigenvectors = crate::pages::with_capacity_huge(n * e);
    let mut columns = Vec::with_capacity(m * e);
    for p in h.packs.iter().take_while(|p| p.first < e) {
        let bytes = read_checked(dir, &p.data)?;
        let take = p.count.min(e - p.first);
        eigenvectors.extend(f32s(&bytes[..take * n * 4]));
        let w0 = p.count * n * 4;
        columns.extend(f32s(&bytes[w0..w0 + take * m * 4]));
    }
    let mut data = vec![0.0_f32; m * e];
    for c in 0..e {
        for f in 0..m {
            data[f * e + c] = columns[c * m + f];
        }
    }
    let basis = Basis {
        width: h.width,
        height: h.height,
        mean,
        eigenvectors,
        eigenvalues: h.eigenvalues[..e].to_vec(),
        sources: h.sources.iter().map(|&(clip, index)| FrameRef { clip, index }).collect(),
    };
    let weights = Weights::new(m, e, data).ok_or("weights size mismatch")?;
    Ok(Database { basis, weights })
}

pyrograph_core::node! {
    /// Writes an Eigenfires database folder: RON header plus little-endian f32 packs (thesis §4.1 off-line mode, §4.8).
    ///
    /// Packs of pack_size eigenfires (with their weight columns) can later be dropped to shrink the database.
    /// Every file is written atomically, the header last; an existing database is kept unless overwrite is on.
    #[node("eigen.save_database", "Eigenfires", Sink)]
    pub struct SaveDatabase {
        /// The basis to save.
        basis: Arc<Basis>,
        /// Its training weights.
        weights: Arc<Weights>,
        /// Database folder.
        path: OutputPath = "eigenfires.db".into(),
        /// Eigenfires per pack file (packSize).
        #[range(1, 1_000_000)]
        pack_size: usize = 500,
        /// Replace an existing database.
        overwrite: bool = false,
    }
    /// The database folder.
    -> path: OutputPath
}

impl Cook for SaveDatabase {
    fn cook(self, ctx: &CookCtx) -> Result<OutputPath, NodeError> {
        let db = Database { basis: Arc::unwrap_or_clone(self.basis), weights: Arc::unwrap_or_clone(self.weights) };
        let written = save(&db, &self.path, self.pack_size, self.overwrite || ctx.settings().overwrite)
            .map_err(|m| NodeError::port(port!(SaveDatabase, path), m))?;
        written.iter().for_each(|f| ctx.record_written(f));
        Ok(self.path)
    }
}

pyrograph_core::node! {
    /// Loads an Eigenfires database folder written by eigen.save_database (thesis §4.1, §4.8).
    ///
    /// components loads only the first E eigenfires (and weight columns), reading only the packs it needs;
    /// 0 loads every pack present. Sizes and checksums are verified.
    #[node("eigen.load_database", "Eigenfires", Source)]
    pub struct LoadDatabase {
        /// Database folder.
        path: InputPath,
        /// Eigenfires to load; 0 = all present.
        #[range(0, 1_000_000)]
        components: usize = 0,
    }
    pub struct LoadDatabaseOut {
        /// The basis.
        basis: Arc<Basis>,
        /// The training weights.
        weights: Arc<Weights>,
    }
}

impl Cook for LoadDatabase {
    fn cook(self, _: &CookCtx) -> Result<LoadDatabaseOut, NodeError> {
        let db = load(&self.path, self.components).map_err(|m| NodeError::port(port!(LoadDatabase, path), m))?;
        Ok(LoadDatabaseOut { basis: Arc::new(db.basis), weights: Arc::new(db.weights) })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pca::tests::{random_frames, sources};
    use crate::pca::train;

    fn trained() -> Database {
        train(6, 5, random_frames(6, 5, 12, 21), sources(12), 0).unwrap()
    }

    #[test]
    fn save_then_load_gives_identical_weights_and_basis() {
        let db = trained();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("fire.db");
        save(&db, &path, 4, false).unwrap();
        assert_eq!(load(&path, 0).unwrap(), db);
        assert!(save(&db, &path, 4, false).unwrap_err().contains("overwrite"));
        save(&db, &path, 4, true).unwrap();
    }

    #[test]
    fn partial_load_gives_the_first_components() {
        let db = trained();
        let dir = tempfile::tempdir().unwrap();
        save(&db, dir.path(), 4, false).unwrap();
        let part = load(dir.path(), 6).unwrap();
        assert_eq!(part.basis.components(), 6);
        assert_eq!(part.basis.eigenvectors[..], db.basis.eigenvectors[..6 * 30]);
        for f in 0..12 {
            assert_eq!(part.weights.row(f).unwrap(), &db.weights.row(f).unwrap()[..6]);
        }
        assert!(load(dir.path(), 12).unwrap_err().contains("holds 11"));
        // Dropping the last pack leaves a valid smaller database (§4.8).
        std::fs::remove_file(dir.path().join("pack_003.bin")).unwrap();
        assert_eq!(load(dir.path(), 0).unwrap().basis.components(), 8);
        assert!(load(dir.path(), 10).unwrap_err().contains("pack_003.bin is missing"));
    }

    #[test]
    fn truncated_corrupt_and_foreign_files_are_clear_errors() {
        let db = trained();
        let dir = tempfile::tempdir().unwrap();
        save(&db, dir.path(), 5, false).unwrap();
        let pack = dir.path().join("pack_001.bin");
        let bytes = std::fs::read(&pack).unwrap();
        std::fs::write(&pack, &bytes[..bytes.len() - 3]).unwrap();
        assert!(load(dir.path(), 0).unwrap_err().contains("truncated"));
        let mut bad = bytes.clone();
        bad[10] ^= 1;
        std::fs::write(&pack, &bad).unwrap();
        assert!(load(dir.path(), 0).unwrap_err().contains("checksum"));
        std::fs::write(dir.path().join(HEADER), "(version: 1, nodes: {})").unwrap();
        assert!(load(dir.path(), 0).unwrap_err().contains("not an Eigenfires database header"));
        let empty = tempfile::tempdir().unwrap();
        assert!(load(empty.path(), 0).unwrap_err().contains("database folder"));
    }

    #[test]
    fn a_header_naming_files_outside_its_folder_is_refused_before_reading_them() {
        let dir = tempfile::tempdir().unwrap();
        save(&trained(), dir.path(), 5, false).unwrap();
        let header = std::fs::read_to_string(dir.path().join(HEADER)).unwrap();
        for hostile in ["../../../etc/passwd", "/etc/passwd", "sub/mean.bin", ".."] {
            std::fs::write(dir.path().join(HEADER), header.replace("\"mean.bin\"", &format!("{hostile:?}"))).unwrap();
            let e = load(dir.path(), 0).unwrap_err();
            assert!(e.contains("not a file name inside the database folder") && e.contains(hostile), "{hostile}: {e}");
        }
    }
}
