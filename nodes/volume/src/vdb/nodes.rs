//! `volume.write_vdb` and `volume.load_vdb`: a clip of volumes as a numbered OpenVDB sequence,
//! and back.

use std::hash::{Hash, Hasher};
use std::path::{Path, PathBuf};
use std::sync::Arc;

use pyrograph_core::document::write_atomic;
use pyrograph_core::fingerprint::Fingerprinter;
use pyrograph_core::{Clip, ClipOf, Cook, CookCtx, FrameSource, InputPath, NodeError, OutputPath, PortType, Value, port};
use pyrograph_nodes_imaging::io::{FramePattern, Gaps, fill_gaps, frames_to_write, list_pattern_numbered, output_pattern};

use super::read::{ReadOptions, read_volume};
use super::stage::{StageField, StageSpec, asset_path, stage_text};
use super::write::{Compression, WriteOptions, write_volume};
use crate::grid::Volume;

pyrograph_core::choice! {
    /// How a VDB file's values are stored.
    pub enum VdbCompression {
        /// Uncompressed (fastest to write and read; the cache's choice).
        None = "none",
        /// zlib, which every OpenVDB reader takes (smaller files for delivery).
        Zip = "zip",
    }
}

pyrograph_core::node! {
    /// Writes a clip of volumes as a numbered OpenVDB sequence, one `.vdb` per frame, for Houdini, Blender,
    /// EmberGen, Unreal or any OpenVDB reader, and as the cache a farm renders from (Museth 2013, "VDB:
    /// High-Resolution Sparse Volumes with Dynamic Topology"; file version 224).
    ///
    /// Each field is one grid under the name DCCs expect (`density`, `temperature`, `fuel`, `flame`, `vel`): a
    /// float grid, or 16-bit half with `half`, `vel` a vec3 grid; the transform is the volume's voxel size and
    /// origin. Every voxel of an active brick is an active voxel, so a file read back holds the same bricks.
    /// Frames are pulled in order (a simulation steps once), each file written atomically; existing files are
    /// refused unless `overwrite` is on, or left alone with `--skip-existing`.
    #[node("volume.write_vdb", "Volume", Sink)]
    pub struct WriteVdb {
        /// The volumes (volume.simulate, volume.load_vdb).
        volume: ClipOf<Arc<Volume>>,
        /// Output files: `####` or `%04d` is the frame number.
        pattern: OutputPath = "vdb/volume_####.vdb".into(),
        /// Fields to write, separated by spaces (`density temperature vel`); every field when empty.
        fields: String = String::new(),
        /// Write values as 16-bit halves (half the size; not for caches that must read back exactly).
        half: bool = false,
        /// How values are stored.
        compression: VdbCompression = VdbCompression::None,
        /// File number of the clip's frame 0.
        #[range(0, 999_999_999)]
        start: u64 = 0,
        /// Replace files that already exist.
        overwrite: bool = false,
        /// Also write a USD stage whose Volume prim references every frame's file (OpenVDBAsset fields with a time-sampled filePath), for Solaris, Omniverse or usdview.
        usd: bool = false,
        /// The USD stage (.usda), written with the clip's first frame.
        usd_path: OutputPath = "vdb/volume.usda".into(),
    }
    pub struct WriteVdbOut {
        /// Files written (or left in place by --skip-existing).
        frames: usize,
        /// The first file.
        first: OutputPath,
    }
}

impl WriteVdb {
    fn frame(&self, i: usize, ctx: &CookCtx) -> Result<Arc<Volume>, NodeError> {
        let value = self.volume.get(i, ctx)?;
        value.downcast::<Volume>().ok_or_else(|| NodeError::port(port!(WriteVdb, volume), format!("frame {i} holds no volume")))
    }

    /// The USD stage of the whole sequence, its fields those written (the first frame's).
    fn write_stage(
        &self,
        dir: &Path,
        pattern: &FramePattern,
        options: &WriteOptions,
        overwrite: bool,
        ctx: &CookCtx,
    ) -> Result<(), NodeError> {
        let usd_err = |m: String| NodeError::port(port!(WriteVdb, usd_path), m);
        let stage_path = &self.usd_path.0;
        if ctx.settings().skip_existing && stage_path.exists() {
            return Ok(());
        }
        let first = self.frame(0, ctx)?;
        let fields: Vec<StageField> = first
            .fields
            .iter()
            .filter(|f| options.fields.is_empty() || options.fields.contains(&f.name))
            .map(|f| StageField { name: f.name.clone(), vector: f.data.components() == 3 })
            .collect();
        let files: Vec<String> =
            (0..self.volume.len()).map(|i| asset_path(&dir.join(pattern.file_name(self.start + i as u64)), stage_path)).collect();
        let spec = StageSpec { name: "volume", fields: &fields, files: &files, fps: self.volume.fps() };
        let text = stage_text(&spec).map_err(|e| usd_err(format!("building the USD stage: {e:#}")))?;
        pyrograph_usd::write(stage_path, &text, overwrite).map_err(usd_err)?;
        ctx.record_written(stage_path);
        Ok(())
    }
}

impl Cook for WriteVdb {
    fn cook(self, ctx: &CookCtx) -> Result<WriteVdbOut, NodeError> {
        let pattern_err = |m: String| NodeError::port(port!(WriteVdb, pattern), m);
        let (dir, pattern) = output_pattern(&self.pattern).map_err(|e| pattern_err(e.to_string()))?;
        let frames = frames_to_write(self.volume.len(), ctx.settings().frames.as_ref())
            .map_err(|e| NodeError::port(port!(WriteVdb, volume), e.to_string()))?;
        let overwrite = self.overwrite || ctx.settings().overwrite;
        let options = WriteOptions {
            fields: self.fields.split_whitespace().map(str::to_string).collect(),
            half: self.half,
            compression: if self.compression == VdbCompression::Zip { Compression::Zip } else { Compression::None },
        };
        let targets: Vec<(usize, PathBuf)> =
            frames.iter().map(|i| (*i, dir.join(pattern.file_name(self.start + *i as u64)))).collect();
        if !overwrite
            && !ctx.settings().skip_existing
            && let Some((_, p)) = targets.iter().find(|(_, p)| p.exists())
        {
            return Err(NodeError::port(
                port!(WriteVdb, overwrite),
                format!(
                    "{} already exists; nothing was written. Set overwrite to true or render with --overwrite to replace it",
                    p.display()
                ),
            ));
        }
        if !dir.as_os_str().is_empty() {
            std::fs::create_dir_all(&dir).map_err(|e| pattern_err(format!("cannot create {}: {e}", dir.display())))?;
        }
        for (done, (i, path)) in targets.iter().enumerate() {
            ctx.check_cancel()?;
            if ctx.settings().skip_existing && path.exists() {
                ctx.record_written(path);
                continue;
            }
            let volume = self.frame(*i, ctx)?;
            let bytes = write_volume(&volume, &options).map_err(|e| NodeError::port(port!(WriteVdb, fields), e.to_string()))?;
            write_atomic(path, &bytes, overwrite).map_err(|e| pattern_err(format!("writing {}: {e}", path.display())))?;
            ctx.record_written(path);
            ctx.frame_progress(done + 1, targets.len());
        }
        if self.usd && frames.first() == Some(&0) {
            self.write_stage(&dir, &pattern, &options, overwrite, ctx)?;
        }
        let first = targets.first().map(|(_, p)| p.clone()).unwrap_or_default();
        Ok(WriteVdbOut { frames: targets.len(), first: OutputPath(first) })
    }
}

pyrograph_core::node! {
    /// Reads an OpenVDB file or numbered sequence as a clip of volumes, so a cached simulation is rendered
    /// without simulating again and VDBs from Houdini, EmberGen or Blender can be rendered (Museth 2013).
    ///
    /// Float, double, half and vec3 grids are read, compressed or not (zlib, Blosc-LZ4, active-value masks),
    /// active tiles expanded into bricks; grids of other types are skipped with a warning. The grids must share
    /// one voxel size and origin. Frames are read on demand; a file over the voxel budget (`--max-voxels`), a
    /// truncated or corrupt file is an error naming it.
    #[node("volume.load_vdb", "Volume", Source)]
    pub struct LoadVdb {
        /// A `.vdb` file or a numbered sequence (`cache/smoke_####.vdb`).
        path: InputPath,
        /// Frames per second of the clip.
        #[range(0.001, 1000.0)]
        fps: f64 = 24.0,
    }
    /// Per frame, the volume.
    -> volume: ClipOf<Arc<Volume>>
}

/// The files of a VDB sequence, in frame order.
pub fn vdb_files(path: &Path) -> Result<Vec<PathBuf>, String> {
    pyrograph_core::limits::may_read(path)?;
    let name = path.file_name().and_then(|n| n.to_str()).unwrap_or_default();
    match FramePattern::parse(name)? {
        Some(pattern) => {
            let numbered = list_pattern_numbered(path, &pattern).map_err(|e| e.to_string())?;
            fill_gaps(numbered, Gaps::Error, path).map_err(|e| e.to_string())
        }
        None if path.is_file() => Ok(vec![path.to_path_buf()]),
        None => Err(format!("{}: no such file", path.display())),
    }
}

/// Reads one VDB file as a volume; errors name the file.
pub fn load_vdb_file(path: &Path) -> Result<(Volume, Vec<String>), String> {
    let data = std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut skipped = Vec::new();
    let options = ReadOptions { max_voxels: pyrograph_core::limits::max_voxels() };
    let v = read_volume(&data, &options, &mut skipped).map_err(|e| format!("{}: {e}", path.display()))?;
    Ok((v, skipped))
}

struct VdbFrames {
    files: Vec<PathBuf>,
}

impl FrameSource for VdbFrames {
    fn len(&self) -> usize {
        self.files.len()
    }
    fn frame(&self, index: usize, ctx: &CookCtx) -> Result<Value, NodeError> {
        let (v, skipped) = load_vdb_file(&self.files[index]).map_err(|m| NodeError::port(port!(LoadVdb, path), m))?;
        if !skipped.is_empty() {
            ctx.warn(format!("{}: skipped grids pyrograph does not read: {}", self.files[index].display(), skipped.join(", ")));
        }
        Ok(Value::custom(Arc::new(v)))
    }
}

impl Cook for LoadVdb {
    fn cook(self, _: &CookCtx) -> Result<ClipOf<Arc<Volume>>, NodeError> {
        let files = vdb_files(&self.path).map_err(|m| NodeError::port(port!(LoadVdb, path), m))?;
        let mut h = Fingerprinter::new();
        "volume.load_vdb".hash(&mut h);
        for f in &files {
            f.hash(&mut h);
            let meta =
                std::fs::metadata(f).map_err(|e| NodeError::port(port!(LoadVdb, path), format!("{}: {e}", f.display())))?;
            (meta.len(), meta.modified().ok()).hash(&mut h);
        }
        let clip = Clip::new(PortType::of::<Volume>(), self.fps, h.finish(), Arc::new(VdbFrames { files }));
        Ok(ClipOf::new(clip))
    }
}
