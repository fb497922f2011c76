//! Reading video through the `ffmpeg` executables, on demand.
//!
//! A video clip holds no frames: each request is served by an `ffmpeg` decoder process reading
//! from a position (a cursor). A writer walking the clip in order keeps reading from the same
//! cursor; a request far from every cursor starts a new one with an input seek (`-ss`), so a
//! scrubber or a transition reaches frame 10,000 without decoding frames 0–9,999. At most a few
//! cursors live at once (one per worker thread, plus one), each holding only ffmpeg's own decoder
//! state and a pipe, so memory does not grow with the clip. Decoded frames land in the global
//! frame cache like any other clip's.
//!
//! Why processes and not libav bindings: the `ffmpeg` executable is what `.ci/run` installs and
//! what artists have; bindings would tie the build to one libav version's system headers.

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdout, Command, Stdio};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;

use pyrograph_core::{Channels, Clip, CookCtx, FrameSource, Image, NodeError, PortType, Value};

use crate::io::{DEFAULT_FPS, IoError, ReportError, fingerprint_files};

const MISSING_FFMPEG: &str = "install ffmpeg (apt-get install ffmpeg) or convert the video to PNG frames";

/// A cursor this many frames behind a request reads on to it rather than seeking (a seek decodes
/// from the previous keyframe anyway, and starting a process costs a few milliseconds).
const SKIP_LIMIT: usize = 48;

/// What `ffprobe` says about a video's first video stream.
#[derive(Clone, Debug, PartialEq)]
pub struct VideoInfo {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Frame rate, when the container states one.
    pub fps: Option<f64>,
    /// Frame count: what decodes where it could be measured, else what the container states.
    pub frames: Option<usize>,
    /// The count the container states, when it differs from what decodes (the header's count is
    /// an estimate in many real files, e.g. an edit list that hides frames of a trimmed clip).
    pub stated_frames: Option<usize>,
    /// Time of the first frame in seconds (the stream's start time, 0 when not stated).
    pub start: f64,
    /// Whether the stream has a constant frame rate (its average rate equals its base rate), so
    /// frame `i` is at time `i / fps` and can be reached by seeking.
    pub constant_rate: bool,
}

/// An error about the video file (videos are read by `imaging.load_sequence`, which puts these on
/// its `path` port).
fn path_error(message: String) -> IoError {
    IoError::Path(message)
}

fn run_error(program: &str, path: &Path, e: &std::io::Error) -> IoError {
    if e.kind() == std::io::ErrorKind::NotFound {
        path_error(format!("{}: '{program}' is not on PATH; {MISSING_FFMPEG}", path.display()))
    } else {
        path_error(format!("{}: could not run '{program}': {e}", path.display()))
    }
}

fn ffprobe_fields(ffprobe: &str, path: &Path, extra: &[&str], entries: &str) -> Result<String, IoError> {
    let out = Command::new(ffprobe)
        .args(["-v", "error", "-select_streams", "v:0"])
        .args(extra)
        .args(["-show_entries", entries, "-of", "default=noprint_wrappers=1"])
        .arg(path)
        .stdin(Stdio::null())
        .output()
        .map_err(|e| run_error(ffprobe, path, &e))?;
    if !out.status.success() {
        let why = String::from_utf8_lossy(&out.stderr);
        return Err(path_error(format!("{}: ffprobe failed: {}", path.display(), why.trim())));
    }
    Ok(String::from_utf8_lossy(&out.stdout).into_owned())
}

/// Probes size, frame rate and frame count with the `ffprobe` executable named `ffprobe`. When
/// the container does not state a frame count (Matroska, WebM), the packets are counted: a read
/// of the file without decoding. When it does and the rate is constant, the count is checked
/// against what decodes at the end of the stream ([`decoded_count`]); results are cached per file
/// (path, size and modification time), so a re-cook does not probe again.
pub fn probe_video(ffprobe: &str, path: &Path) -> Result<VideoInfo, IoError> {
    pyrograph_core::limits::may_read(path).map_err(path_error)?;
    let key = probe_key(path);
    if let Some(info) = key.as_ref().and_then(|k| probe_cache().lock().ok()?.get(k).cloned()) {
        return Ok(info);
    }
    let entries = "stream=width,height,avg_frame_rate,r_frame_rate,nb_frames,start_time";
    let text = ffprobe_fields(ffprobe, path, &[], entries)?;
    let mut info = parse_probe(&text).ok_or_else(|| path_error(format!("{}: no video stream found", path.display())))?;
    // Frames are decoded at the size the header states: refuse one over the budget first.
    if let Some(m) = crate::io::files::over_budget(path, info.width, info.height) {
        return Err(path_error(m));
    }
    match info.frames {
        None => {
            let text = ffprobe_fields(ffprobe, path, &["-count_packets"], "stream=nb_read_packets")?;
            let field = text.lines().find_map(|l| l.trim().strip_prefix("nb_read_packets=")?.parse().ok());
            info.frames = field;
        }
        Some(stated) if info.constant_rate => {
            if let Some(real) = decoded_count(ffprobe, path, &info, stated).filter(|&n| n != stated && n > 0) {
                info.frames = Some(real);
                info.stated_frames = Some(stated);
            }
        }
        Some(_) => {}
    }
    if let (Some(k), Ok(mut cache)) = (key, probe_cache().lock()) {
        cache.insert(k, info.clone());
    }
    Ok(info)
}

/// What identifies a probed file: its path, size and modification time.
type ProbeKey = (PathBuf, u64, Option<std::time::SystemTime>);

fn probe_key(path: &Path) -> Option<ProbeKey> {
    let meta = std::fs::metadata(path).ok()?;
    Some((std::fs::canonicalize(path).ok()?, meta.len(), meta.modified().ok()))
}

fn probe_cache() -> &'static Mutex<std::collections::HashMap<ProbeKey, VideoInfo>> {
    static CACHE: std::sync::OnceLock<Mutex<std::collections::HashMap<ProbeKey, VideoInfo>>> = std::sync::OnceLock::new();
    CACHE.get_or_init(Default::default)
}

/// How many frames a constant-rate video really decodes to, measured cheaply: `ffprobe` seeks to
/// shortly before the last frame the header states (to the keyframe before it) and decodes from
/// there to the end; the last frame's time gives its index. A read of one group of pictures, not of
/// the file. `None` when that cannot be measured: nothing decodes there or ffprobe reports an error,
/// as a file cut short does; the stated count then stands, and decoding stops at the frame where the
/// file breaks with an error that names it.
pub fn decoded_count(ffprobe: &str, path: &Path, info: &VideoInfo, stated: usize) -> Option<usize> {
    let fps = info.fps?;
    let from = (info.start + (stated as f64 - 1.0) / fps - 1.0).max(info.start);
    let out = Command::new(ffprobe)
        .args(["-v", "error", "-select_streams", "v:0", "-read_intervals"])
        .arg(format!("{from:.6}%"))
        .args(["-show_entries", "frame=best_effort_timestamp_time", "-of", "csv=p=0"])
        .arg(path)
        .stdin(Stdio::null())
        .output()
        .ok()?;
    if !out.status.success() || !out.stderr.trim_ascii().is_empty() {
        return None;
    }
    last_frame_index(&String::from_utf8_lossy(&out.stdout), info.start, fps).map(|last| last + 1)
}

/// The index of the latest frame time among `ffprobe`'s `csv=p=0` lines (seconds, one a line),
/// counting frame 0 at `start`.
fn last_frame_index(text: &str, start: f64, fps: f64) -> Option<usize> {
    let last = text.lines().filter_map(|l| l.trim().trim_end_matches(',').parse::<f64>().ok()).reduce(f64::max)?;
    let index = ((last - start) * fps).round();
    (index.is_finite() && index >= 0.0).then_some(index as usize)
}

/// Parses `key=value` lines printed by `ffprobe -show_entries stream=...`.
pub fn parse_probe(text: &str) -> Option<VideoInfo> {
    let field = |key: &str| text.lines().find_map(|l| l.trim().strip_prefix(key)?.strip_prefix('='));
    let width = field("width")?.parse().ok().filter(|&w| w > 0)?;
    let height = field("height")?.parse().ok().filter(|&h| h > 0)?;
    let avg = field("avg_frame_rate").and_then(parse_rate);
    let base = field("r_frame_rate").and_then(parse_rate);
    let constant_rate = matches!((avg, base), (Some(a), Some(b)) if (a - b).abs() <= 1e-6 * b);
    let frames = field("nb_frames").and_then(|n| n.parse().ok()).filter(|&n| n > 0);
    let start = field("start_time").and_then(|t| t.parse::<f64>().ok()).filter(|t| t.is_finite()).unwrap_or(0.0);
    Some(VideoInfo { width, height, fps: avg.or(base), frames, stated_frames: None, start, constant_rate })
}

/// `30000/1001` or `25` → frames per second; `None` for `0/0` and other non-rates.
fn parse_rate(text: &str) -> Option<f64> {
    let rate = match text.split_once('/') {
        Some((n, d)) => n.trim().parse::<f64>().ok()? / d.trim().parse::<f64>().ok()?,
        None => text.trim().parse().ok()?,
    };
    (rate.is_finite() && rate > 0.0).then_some(rate)
}

/// One `ffmpeg` process decoding the first video stream to packed 8-bit RGB from frame `next`.
struct Cursor {
    child: Child,
    stdout: ChildStdout,
    stderr: Option<JoinHandle<String>>,
    next: usize,
}

impl Cursor {
    /// Starts decoding at frame `start`, seeking to its time when `seek` is given (seconds).
    fn spawn(ffmpeg: &str, path: &Path, start: usize, seek: Option<f64>) -> Result<Cursor, IoError> {
        let mut cmd = Command::new(ffmpeg);
        cmd.args(["-v", "error", "-nostdin", "-noautorotate"]);
        if let Some(t) = seek {
            // An input seek is exact in ffmpeg: it decodes from the keyframe before `t` and drops
            // the frames before it. Half a frame early lands on frame `start` whatever the rounding.
            cmd.arg("-ss").arg(format!("{t:.6}"));
        }
        cmd.arg("-i")
            .arg(path)
            // Every decoded frame once, in order: no duplicated or dropped frames for a rate.
            .args(["-map", "0:v:0", "-an", "-sn", "-dn", "-vsync", "passthrough"])
            .args(["-f", "rawvideo", "-pix_fmt", "rgb24", "-"])
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped());
        let mut child = cmd.spawn().map_err(|e| run_error(ffmpeg, path, &e))?;
        // Drain stderr on its own thread so a chatty ffmpeg cannot block on a full pipe.
        let stderr = child.stderr.take().map(|mut s| {
            std::thread::spawn(move || {
                let mut text = String::new();
                let _ = s.read_to_string(&mut text);
                text
            })
        });
        let Some(stdout) = child.stdout.take() else {
            let _ = child.kill();
            let _ = child.wait();
            return Err(NodeError::msg("ffmpeg's output pipe is missing").into());
        };
        Ok(Cursor { child, stdout, stderr, next: start })
    }

    /// Reads the next frame into `buf`; `Ok(false)` when the stream ended.
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<bool> {
        let ok = read_full(&mut self.stdout, buf)?;
        if ok {
            self.next += 1;
        }
        Ok(ok)
    }

    /// Ends the process and returns what it printed on stderr.
    fn finish(mut self) -> String {
        let _ = self.child.kill();
        let _ = self.child.wait();
        self.stderr.take().and_then(|t| t.join().ok()).unwrap_or_default()
    }
}

impl Drop for Cursor {
    fn drop(&mut self) {
        // A cursor dropped mid-stream (cancelled cook, evicted cursor) must not leave a process.
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Fills `buf`; `Ok(false)` at end of stream (a trailing partial frame is dropped).
pub(crate) fn read_full(r: &mut impl Read, buf: &mut [u8]) -> std::io::Result<bool> {
    let mut filled = 0;
    while filled < buf.len() {
        match r.read(&mut buf[filled..]) {
            Ok(0) => return Ok(false),
            Ok(n) => filled += n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok(true)
}

/// The frames of a video, decoded on request by a small pool of cursors.
struct VideoFrames {
    ffmpeg: String,
    path: PathBuf,
    info: VideoInfo,
    len: usize,
    fps: f64,
    cursors: Mutex<Vec<Cursor>>,
    max_cursors: usize,
    /// The loader's way of naming its ports, for errors while decoding after the cook.
    report: ReportError,
}

impl VideoFrames {
    /// The cursor to serve `index` from: the nearest one at or before it within [`SKIP_LIMIT`]
    /// frames, else a new one started at `index` (by seeking where the rate allows, else from
    /// the start).
    fn cursor_for(&self, index: usize) -> Result<Cursor, IoError> {
        {
            let mut pool = self.cursors.lock().unwrap_or_else(|p| p.into_inner());
            let best = pool
                .iter()
                .enumerate()
                .filter(|(_, c)| c.next <= index && index - c.next <= SKIP_LIMIT)
                .max_by_key(|(_, c)| c.next)
                .map(|(i, _)| i);
            if let Some(i) = best {
                return Ok(pool.swap_remove(i));
            }
        }
        if index == 0 || !self.info.constant_rate {
            return Cursor::spawn(&self.ffmpeg, &self.path, 0, None);
        }
        let t = (index as f64 - 0.5) / self.fps;
        Cursor::spawn(&self.ffmpeg, &self.path, index, Some(t.max(0.0)))
    }

    fn give_back(&self, cursor: Cursor) {
        let mut pool = self.cursors.lock().unwrap_or_else(|p| p.into_inner());
        if pool.len() >= self.max_cursors {
            // The cursor furthest along is the least likely to be continued by an in-order walk.
            if let Some((i, _)) = pool.iter().enumerate().max_by_key(|(_, c)| c.next) {
                pool.swap_remove(i);
            }
        }
        pool.push(cursor);
    }
}

impl FrameSource for VideoFrames {
    fn len(&self) -> usize {
        self.len
    }

    fn frame(&self, index: usize, ctx: &CookCtx) -> Result<Value, NodeError> {
        let mut cursor = self.cursor_for(index).map_err(self.report)?;
        let (w, h) = (self.info.width, self.info.height);
        let mut buf = vec![0u8; w as usize * h as usize * 3];
        while cursor.next <= index {
            // Cancelling drops the cursor, which ends its process; nothing half-made is cached.
            ctx.check_cancel()?;
            let at = cursor.next;
            let got = cursor.read(&mut buf).map_err(|e| NodeError::msg(format!("reading ffmpeg's output: {e}")))?;
            if !got {
                let why = cursor.finish();
                let why = why.trim();
                let why =
                    if why.is_empty() { String::new() } else { format!(" (ffmpeg: {})", why.lines().last().unwrap_or(why)) };
                return Err(NodeError::msg(format!(
                    "{}: the video ends before frame {at} although it states {} frames: it is truncated or corrupt{why}",
                    self.path.display(),
                    self.len
                )));
            }
        }
        self.give_back(cursor);
        Ok(Value::Image(Arc::new(rgb24_to_image(w, h, &buf)?)))
    }
}

/// Packed 8-bit RGB to an opaque f32 RGBA image.
pub fn rgb24_to_image(width: u32, height: u32, rgb: &[u8]) -> Result<Image, NodeError> {
    // A table of v / 255 and a plain loop over pre-sized output: the iterator chain this
    // replaced was most of a 1080p streaming cook's CPU time (callgrind: 56 %).
    let unit: [f32; 256] = std::array::from_fn(|v| v as f32 / 255.0);
    let mut data = vec![1.0_f32; rgb.len() / 3 * 4];
    for (o, p) in data.chunks_exact_mut(4).zip(rgb.chunks_exact(3)) {
        o[0] = unit[usize::from(p[0])];
        o[1] = unit[usize::from(p[1])];
        o[2] = unit[usize::from(p[2])];
    }
    Image::from_vec(width, height, Channels::Rgba, data).ok_or_else(|| {
        NodeError::msg(format!(
            "a {width}x{height} frame needs {} bytes, got {}",
            width as usize * height as usize * 3,
            rgb.len()
        ))
    })
}

/// A video as a clip whose frames decode on demand; `fps` of 0 takes the video's own rate. A
/// container that states more (or fewer) frames than decode gives the frames that decode, with a
/// warning naming both counts. Errors of frames decoded later (ffmpeg cannot start) reach the
/// user through `report`, the loader's.
pub fn video_clip(path: &Path, fps: f64, ctx: &CookCtx, report: ReportError) -> Result<Clip, IoError> {
    video_clip_with("ffmpeg", "ffprobe", path, fps, ctx, report)
}

/// [`video_clip`] with the executables named.
pub fn video_clip_with(
    ffmpeg: &str,
    ffprobe: &str,
    path: &Path,
    fps: f64,
    ctx: &CookCtx,
    report: ReportError,
) -> Result<Clip, IoError> {
    let info = probe_video(ffprobe, path)?;
    let len = info.frames.ok_or_else(|| path_error(format!("{}: the video has no frames", path.display())))?;
    if let Some(stated) = info.stated_frames {
        ctx.warn(format!(
            "{}: the video's header states {stated} frames but {len} decode (the count in a header is an \
             estimate, e.g. where a trimmed clip hides frames); using the {len} that decode",
            path.display()
        ));
    }
    let source_fps = info.fps.unwrap_or(DEFAULT_FPS);
    let fps = if fps > 0.0 { fps } else { source_fps };
    let fingerprint = fingerprint_files(&[path.to_path_buf()])?;
    let source = VideoFrames {
        ffmpeg: ffmpeg.to_string(),
        path: path.to_path_buf(),
        info,
        len,
        fps: source_fps,
        cursors: Mutex::new(Vec::new()),
        max_cursors: rayon::current_num_threads() + 1,
        report,
    };
    Ok(Clip::new(PortType::Image, fps, fingerprint, Arc::new(source)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::LoadSequence;

    #[test]
    fn probe_output_parses_size_rate_and_count() {
        let info = parse_probe("width=480\nheight=270\nr_frame_rate=30/1\navg_frame_rate=30000/1001\nnb_frames=796\n").unwrap();
        assert_eq!((info.width, info.height, info.frames), (480, 270, Some(796)));
        assert!((info.fps.unwrap() - 29.97).abs() < 0.01);
        assert!(!info.constant_rate, "an average rate below the base rate is variable");
        let info = parse_probe("width=4\nheight=2\navg_frame_rate=0/0\nr_frame_rate=25/1\nnb_frames=N/A").unwrap();
        assert_eq!((info.fps, info.frames), (Some(25.0), None));
        let info = parse_probe("width=4\nheight=2\navg_frame_rate=24/1\nr_frame_rate=24/1\nnb_frames=10").unwrap();
        assert!(info.constant_rate);
        assert_eq!(parse_probe("height=2"), None);
    }

    #[test]
    fn missing_ffmpeg_names_the_fix() {
        let err = probe_video("pyrograph-no-such-ffprobe", Path::new("/tmp/clip.mp4")).unwrap_err().to_string();
        assert!(err.contains("install ffmpeg (apt-get install ffmpeg)") && err.contains("PNG frames"), "{err}");
    }

    #[test]
    fn rgb24_frames_become_opaque_rgba() {
        let img = rgb24_to_image(2, 1, &[255, 0, 51, 0, 255, 0]).unwrap();
        let want = [1.0, 0.0, 0.2, 1.0, 0.0, 1.0, 0.0, 1.0];
        assert!(img.data().iter().zip(want).all(|(a, b)| (a - b).abs() < 1e-6));
        assert!(rgb24_to_image(2, 2, &[0; 6]).is_err());
    }

    /// A `frames`-frame 128×96 test video at 24 fps (ffmpeg's `testsrc2`, a counter in every
    /// frame, a keyframe every 12 frames), written with `extra` output options.
    fn make_video(dir: &Path, name: &str, frames: usize, extra: &[&str]) -> PathBuf {
        let path = dir.join(name);
        let status = Command::new("ffmpeg")
            .args(["-v", "error", "-nostdin", "-f", "lavfi", "-i"])
            .arg(format!("testsrc2=size=128x96:rate=24:duration={}", frames as f64 / 24.0))
            .args(["-c:v", "libx264", "-g", "12", "-pix_fmt", "yuv420p"])
            .args(extra)
            .arg(&path)
            .status()
            .expect("ffmpeg runs");
        assert!(status.success());
        path
    }

    #[test]
    #[ignore = "needs ffmpeg: .ci/run installs it and runs the ignored tests"]
    fn seeking_gives_the_frames_an_in_order_walk_gives() {
        let dir = tempfile::tempdir().unwrap();
        let path = make_video(dir.path(), "t.mp4", 90, &[]);
        let ctx = CookCtx::new();
        let walk = video_clip(&path, 0.0, &ctx, LoadSequence::node_error).unwrap();
        assert_eq!((walk.len(), walk.fps()), (90, 24.0));
        let frames: Vec<Arc<Image>> = (0..90).map(|i| walk.image(i, &ctx).unwrap()).collect();
        assert!(frames.windows(2).all(|w| w[0].data() != w[1].data()), "every frame differs (the counter runs)");
        // A second clip of the same file, asked out of order: every answer seeks or skips.
        let jump = video_clip(&path, 0.0, &ctx, LoadSequence::node_error).unwrap();
        for i in [75, 3, 50, 89, 20, 21, 60, 0, 12, 11, 88, 47] {
            assert!(jump.image(i, &ctx).unwrap().data() == frames[i].data(), "frame {i} differs after a seek");
        }
    }

    #[test]
    #[ignore = "needs ffmpeg: .ci/run installs it and runs the ignored tests"]
    fn a_truncated_video_names_the_frame_and_keeps_what_was_written() {
        let dir = tempfile::tempdir().unwrap();
        let path = make_video(dir.path(), "t.mp4", 240, &["-movflags", "+faststart"]);
        // Cut the file in half: the header still states 240 frames.
        let bytes = std::fs::read(&path).unwrap();
        std::fs::write(&path, &bytes[..bytes.len() / 2]).unwrap();
        let ctx = CookCtx::new();
        let clip = video_clip(&path, 0.0, &ctx, LoadSequence::node_error).unwrap();
        assert_eq!(clip.len(), 240);
        let out = dir.path().join("out").join("f_####.png");
        let options = crate::io::WriteOptions {
            pattern: out.clone(),
            format: crate::io::OutputFormat::Png { sixteen_bit: false },
            start: 0,
            overwrite: false,
            frames: None,
            skip_existing: false,
            alpha: crate::color::AlphaMode::Straight,
        };
        let err = crate::io::write_sequence(&clip, &options, &ctx).unwrap_err().to_string();
        assert!(err.contains("truncated or corrupt") && err.contains("before frame"), "{err}");
        assert!(dir.path().join("out/f_0000.png").exists(), "frames decoded before the cut are written and stay");
    }

    #[test]
    fn the_last_frame_time_gives_the_count() {
        assert_eq!(last_frame_index("1.166667\n1.625000\n1.583333\n", 0.0, 24.0), Some(39));
        assert_eq!(last_frame_index("N/A\n2.5,\n", 0.5, 10.0), Some(20));
        assert_eq!(last_frame_index("", 0.0, 24.0), None);
        assert_eq!(last_frame_index("N/A\n", 0.0, 24.0), None);
    }

    /// Every frame of `path` as ffmpeg itself decodes it (packed RGB, 128×96).
    fn ffmpeg_frames(path: &Path) -> Vec<Vec<u8>> {
        let out = Command::new("ffmpeg")
            .args(["-v", "error", "-nostdin", "-i"])
            .arg(path)
            .args(["-map", "0:v:0", "-vsync", "passthrough", "-f", "rawvideo", "-pix_fmt", "rgb24", "-"])
            .output()
            .expect("ffmpeg runs");
        assert!(out.status.success());
        out.stdout.chunks_exact(128 * 96 * 3).map(<[u8]>::to_vec).collect()
    }

    #[test]
    #[ignore = "needs ffmpeg: .ci/run installs it and runs the ignored tests"]
    fn a_header_that_overstates_the_count_loses_only_the_missing_frames() {
        let dir = tempfile::tempdir().unwrap();
        let full = make_video(dir.path(), "t.mp4", 48, &[]);
        // A trim by stream copy, as editing tools make: the file keeps all 48 samples (and states
        // 48 frames) while its edit list hides the first 8, so 40 decode.
        let path = dir.path().join("trimmed.mp4");
        let status = Command::new("ffmpeg")
            .args(["-v", "error", "-nostdin", "-ss", "0.3", "-i"])
            .arg(&full)
            .args(["-c", "copy"])
            .arg(&path)
            .status()
            .unwrap();
        assert!(status.success());
        let stated = parse_probe(&ffprobe_fields("ffprobe", &path, &[], "stream=width,height,nb_frames").unwrap());
        assert_eq!(stated.and_then(|i| i.frames), Some(48), "the header states 48 frames");
        let want = ffmpeg_frames(&path);
        assert_eq!(want.len(), 40, "ffmpeg decodes 40");

        let ctx = CookCtx::new();
        let clip = video_clip(&path, 0.0, &ctx, LoadSequence::node_error).unwrap();
        assert_eq!(clip.len(), 40);
        let warnings = ctx.warnings();
        assert_eq!(warnings.len(), 1, "{warnings:?}");
        assert!(warnings[0].message.contains("states 48 frames but 40 decode"), "{}", warnings[0].message);
        let rgb = |img: &Image| -> Vec<u8> {
            img.data().chunks_exact(4).flat_map(|p| [p[0], p[1], p[2]]).map(|v| (v * 255.0).round() as u8).collect()
        };
        for (i, frame) in want.iter().enumerate() {
            assert!(rgb(&clip.image(i, &ctx).unwrap()) == *frame, "frame {i} differs from ffmpeg's decode");
        }
        // Asked out of order, each answer seeks: the same frames.
        let jump = video_clip(&path, 0.0, &CookCtx::new(), LoadSequence::node_error).unwrap();
        for i in [39, 5, 30, 0, 17, 38] {
            assert!(rgb(&jump.image(i, &ctx).unwrap()) == want[i], "frame {i} differs after a seek");
        }
        // The untouched file keeps its stated count and gives no warning.
        let ctx = CookCtx::new();
        assert_eq!(video_clip(&full, 0.0, &ctx, LoadSequence::node_error).unwrap().len(), 48);
        assert!(ctx.warnings().is_empty());
    }

    #[test]
    #[ignore = "needs ffmpeg: .ci/run installs it and runs the ignored tests"]
    fn a_cancelled_read_leaves_the_clip_usable() {
        let dir = tempfile::tempdir().unwrap();
        let path = make_video(dir.path(), "t.mp4", 48, &[]);
        let token = pyrograph_core::CancelToken::new();
        let ctx = CookCtx::new().with_cancel(token.clone());
        let clip = video_clip(&path, 0.0, &ctx, LoadSequence::node_error).unwrap();
        let a = clip.image(10, &ctx).unwrap();
        token.cancel();
        assert!(clip.image(30, &ctx).is_err(), "a cancelled cook stops");
        token.reset();
        assert!(clip.image(10, &ctx).unwrap().data() == a.data());
        let fresh = video_clip(&path, 0.0, &ctx, LoadSequence::node_error).unwrap();
        assert!(clip.image(30, &ctx).unwrap().data() == fresh.image(30, &ctx).unwrap().data());
    }
}
