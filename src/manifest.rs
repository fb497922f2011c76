//! Render manifests: what one `render` (one farm task) wrote — every file with its size and
//! SHA-256, the frames it covered, its time and peak memory — and `job collect`, which merges
//! a job's task manifests and finds the frames no finished task covered.

use std::collections::BTreeSet;
use std::io::Read;
use std::path::{Path, PathBuf};

use pyrograph_core::FrameSet;
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

/// Where a job's tasks leave their manifests, inside the job's output folder.
pub const TASK_DIR: &str = ".pyrograph-job";

/// Whether `file` holds a manifest as `render --manifest` writes it (so a re-run may replace
/// it); anything else, or a file too big to be one, is not.
pub fn is_manifest(file: &Path) -> bool {
    const LARGEST: u64 = 256 << 20;
    std::fs::metadata(file).is_ok_and(|m| m.len() <= LARGEST)
        && std::fs::read(file).is_ok_and(|bytes| serde_json::from_slice::<Manifest>(&bytes).is_ok())
}

/// One file written.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FileRecord {
    /// The path, relative to the output folder when inside it.
    pub path: String,
    /// Size in bytes.
    pub bytes: u64,
    /// SHA-256 of the contents, hex.
    pub sha256: String,
}

/// What one render wrote.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Manifest {
    /// The graph file rendered.
    pub graph: String,
    /// The frames asked for (`--frames`), all when absent.
    pub frames: Option<String>,
    /// The wedge variant rendered (`--wedge-index`), when the job is a wedge.
    #[serde(default)]
    pub wedge: Option<usize>,
    /// Whether every node cooked.
    pub ok: bool,
    /// Wall time of the cook, seconds.
    pub seconds: f64,
    /// Peak resident memory of the process, MiB (Linux).
    pub peak_rss_mib: Option<u64>,
    /// Files written (or, with `--skip-existing`, found whole), in the order they were finished.
    pub files: Vec<FileRecord>,
}

/// SHA-256 and size of a file, streamed.
pub fn hash_file(path: &Path) -> std::io::Result<(u64, String)> {
    let mut f = std::fs::File::open(path)?;
    let mut h = Sha256::new();
    let mut buf = vec![0u8; 1 << 16];
    let mut total = 0u64;
    loop {
        let n = f.read(&mut buf)?;
        if n == 0 {
            break;
        }
        total += n as u64;
        h.update(&buf[..n]);
    }
    let hex: String = h.finalize().iter().map(|b| format!("{b:02x}")).collect();
    Ok((total, hex))
}

/// Records `files` (hashing each) relative to `out`.
pub fn records(files: &[PathBuf], out: &Path) -> std::io::Result<Vec<FileRecord>> {
    let mut seen = BTreeSet::new();
    let mut v = Vec::new();
    for f in files {
        if !seen.insert(f.clone()) {
            continue;
        }
        let (bytes, sha256) = hash_file(f)?;
        let path = f.strip_prefix(out).unwrap_or(f).to_string_lossy().into_owned();
        v.push(FileRecord { path, bytes, sha256 });
    }
    Ok(v)
}

/// The merged record of a job, and what is wrong with it.
#[derive(Debug, Serialize)]
pub struct JobReport {
    /// The frames the job asked for.
    pub frames: String,
    /// Task manifests found (finished or not).
    pub tasks: usize,
    /// Frames no finished task covered, in frame-set form, per wedge variant for a wedge job
    /// (`frames 8-15`, `wedge 2 frames 8-15; wedge 3 frames 0-7`); empty when complete.
    pub missing: String,
    /// Files listed by a manifest that are gone or changed since.
    pub damaged: Vec<String>,
    /// Every file of every finished task.
    pub files: Vec<FileRecord>,
    /// Sum of the tasks' cook times, seconds.
    pub task_seconds: f64,
    /// Largest peak memory of a task, MiB.
    pub peak_rss_mib: Option<u64>,
}

impl JobReport {
    /// Whether every frame was rendered and every file is as its task left it.
    pub fn is_complete(&self) -> bool {
        self.missing.is_empty() && self.damaged.is_empty()
    }
}

/// What the bundle's `pyrograph_job.json` (written by `pyrograph job`) says the job renders.
#[derive(Deserialize)]
struct JobFile {
    out: PathBuf,
    frames: String,
    #[serde(default)]
    variants: usize,
}

/// Merges the task manifests of the job in `job_dir` and checks them against its frames.
pub fn collect(job_dir: &Path) -> Result<JobReport, String> {
    let file = job_dir.join("pyrograph_job.json");
    let text = std::fs::read_to_string(&file).map_err(|e| format!("cannot read {}: {e}", file.display()))?;
    let job: JobFile =
        serde_json::from_str(&text).map_err(|e| format!("{}: not written by `pyrograph job`: {e}", file.display()))?;
    let frames: FrameSet = job.frames.parse()?;
    let out = job.out;
    // Wedge variant k of a wedge job, or the one "variant" of a plain job.
    let variants: Vec<Option<usize>> = if job.variants == 0 { vec![None] } else { (0..job.variants).map(Some).collect() };
    let dir = out.join(TASK_DIR);
    let mut paths: Vec<PathBuf> = match std::fs::read_dir(&dir) {
        Ok(rd) => rd.flatten().map(|e| e.path()).filter(|p| p.extension().is_some_and(|e| e == "json")).collect(),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Vec::new(),
        Err(e) => return Err(format!("cannot read {}: {e}", dir.display())),
    };
    paths.sort();
    let mut covered = BTreeSet::new();
    let mut report = JobReport {
        frames: frames.to_string(),
        tasks: paths.len(),
        missing: String::new(),
        damaged: Vec::new(),
        files: Vec::new(),
        task_seconds: 0.0,
        peak_rss_mib: None,
    };
    for p in &paths {
        let text = std::fs::read_to_string(p).map_err(|e| format!("cannot read {}: {e}", p.display()))?;
        let m: Manifest = serde_json::from_str(&text).map_err(|e| format!("{}: not a task manifest: {e}", p.display()))?;
        report.task_seconds += m.seconds;
        report.peak_rss_mib = report.peak_rss_mib.max(m.peak_rss_mib);
        if !m.ok {
            continue;
        }
        let done = match m.frames.as_deref().map(str::parse::<FrameSet>) {
            Some(Ok(set)) => set.frames(),
            Some(Err(e)) => return Err(format!("{}: {e}", p.display())),
            None => frames.frames(),
        };
        // A task without a wedge index rendered every variant (a local `render --wedge`).
        let which: Vec<Option<usize>> = if m.wedge.is_some() { vec![m.wedge] } else { variants.clone() };
        for w in which {
            covered.extend(done.iter().map(|f| (w, *f)));
        }
        for f in m.files {
            let on_disk = out.join(&f.path);
            match hash_file(&on_disk) {
                Ok((bytes, sha)) if bytes == f.bytes && sha == f.sha256 => report.files.push(f),
                Ok(_) => report.damaged.push(format!("{} changed after its task wrote it", on_disk.display())),
                Err(e) => report.damaged.push(format!("{}: {e}", on_disk.display())),
            }
        }
    }
    let mut gaps = Vec::new();
    for w in &variants {
        let missing: Vec<usize> = frames.frames().into_iter().filter(|f| !covered.contains(&(*w, *f))).collect();
        if let Some(set) = FrameSet::from_list(&missing) {
            gaps.push(match w {
                Some(k) => format!("wedge {k} frames {set}"),
                None => format!("frames {set}"),
            });
        }
    }
    report.missing = gaps.join("; ");
    report.files.sort_by(|a, b| a.path.cmp(&b.path));
    report.files.dedup_by(|a, b| a.path == b.path);
    Ok(report)
}
