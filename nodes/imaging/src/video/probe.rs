//! What a video holds, asked of `ffprobe`: size as displayed, rate, frame count, bit depth,
//! rotation, and whether its frames come at a constant rate.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::Mutex;

use crate::media::IoError;

const MISSING_FFMPEG: &str = "install ffmpeg (apt-get install ffmpeg) or convert the video to PNG frames";

/// What `ffprobe` says about a video's first video stream.
#[derive(Clone, Debug, PartialEq)]
pub struct VideoInfo {
    /// Width in pixels, as displayed (after the rotation is applied).
    pub width: u32,
    /// Height in pixels, as displayed.
    pub height: u32,
    /// Frame rate, when the container states one (for a variable-rate clip, the rate it is
    /// resampled to, once [`probe_video`] has chosen it).
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
    /// Degrees the picture is turned for display (the stream's display matrix or its old `rotate`
    /// tag, counter-clockwise); ffmpeg applies it when decoding, as players do.
    pub rotation: i32,
    /// Bits per sample of the stream: above 8, frames decode at 16 bits so 10-, 12- and 16-bit
    /// sources keep their precision.
    pub bits: u32,
    /// A variable-rate stream: what it was measured to be and the rate it is resampled to.
    pub variable: Option<VariableRate>,
    /// The stream's base rate (`r_frame_rate`: the finest step its frame times take).
    pub base: Option<f64>,
}

/// A variable-frame-rate stream, resampled by its frames' timestamps to a constant rate: each
/// output frame shows the source frame on screen at its time (ffmpeg's `fps` filter).
#[derive(Clone, Debug, PartialEq)]
pub struct VariableRate {
    /// The rate frames are resampled to.
    pub rate: f64,
    /// The stream's average rate.
    pub average: f64,
    /// Frames in the stream.
    pub source_frames: usize,
    /// Seconds from the first frame's time to the end of the last frame.
    pub seconds: f64,
    /// The first frame's time in seconds (frame 0 of the resampled clip).
    pub first: f64,
}

/// An error about the video file (videos are read by `imaging.load_sequence`, which puts these on
/// its `path` port).
pub(crate) fn path_error(message: String) -> IoError {
    IoError::Path(message)
}

/// The error for an `ffmpeg` or `ffprobe` that could not be started.
pub(crate) fn run_error(program: &str, path: &Path, e: &std::io::Error) -> IoError {
    if e.kind() == std::io::ErrorKind::NotFound {
        path_error(format!("{}: '{program}' is not on PATH; {MISSING_FFMPEG}", path.display()))
    } else {
        path_error(format!("{}: could not run '{program}': {e}", path.display()))
    }
}

/// `path` as ffmpeg's and ffprobe's input: through the `file:` protocol, so a name starting with
/// a dash is not read as an option nor one with a colon as another protocol; built from the path's
/// own bytes, so a name that is not UTF-8 reaches them whole.
pub(crate) fn input_url(path: &Path) -> std::ffi::OsString {
    let mut url = std::ffi::OsString::from("file:");
    url.push(path.as_os_str());
    url
}

/// `ffprobe`'s `entries` of the first video stream as `key=value` lines.
pub(crate) fn ffprobe_fields(ffprobe: &str, path: &Path, extra: &[&str], entries: &str) -> Result<String, IoError> {
    ffprobe_run(ffprobe, path, extra, entries, "default=noprint_wrappers=1")
}

/// `ffprobe`'s `entries` of the first video stream as `csv=p=0` lines (values only, by commas).
fn ffprobe_csv(ffprobe: &str, path: &Path, entries: &str) -> Result<String, IoError> {
    ffprobe_run(ffprobe, path, &[], entries, "csv=p=0")
}

fn ffprobe_run(ffprobe: &str, path: &Path, extra: &[&str], entries: &str, format: &str) -> Result<String, IoError> {
    let out = Command::new(ffprobe)
        .args(["-v", "error", "-select_streams", "v:0"])
        .args(extra)
        .args(["-show_entries", entries, "-of", format])
        .arg(input_url(path))
        .stdin(Stdio::null())
        .output()
        .map_err(|e| run_error(ffprobe, path, &e))?;
    if !out.status.success() {
        let why = String::from_utf8_lossy(&out.stderr);
        return Err(path_error(format!("{}: ffprobe failed: {}", path.display(), why.trim())));
    }
    Ok(String::from_utf8_lossy(&out.stdout).into_owned())
}

/// Probes size, frame rate, frame count, bit depth and rotation with the `ffprobe` executable
/// named `ffprobe`. When the container does not state a frame count (Matroska, WebM), the packets
/// are counted: a read of the file without decoding. When it does and the rate is constant, the
/// count is checked against what decodes at the end of the stream ([`decoded_count`]). A
/// variable-rate stream is measured by its packets' times ([`variable_rate`]). Results are cached
/// per file (path, size and modification time), so a re-cook does not probe again.
pub fn probe_video(ffprobe: &str, path: &Path) -> Result<VideoInfo, IoError> {
    pyrograph_core::limits::may_read(path).map_err(path_error)?;
    let key = probe_key(path);
    if let Some(info) = key.as_ref().and_then(|k| probe_cache().lock().ok()?.get(k).cloned()) {
        return Ok(info);
    }
    let entries = "stream=width,height,avg_frame_rate,r_frame_rate,nb_frames,start_time,pix_fmt,bits_per_raw_sample:\
                   stream_side_data=rotation:stream_tags=rotate";
    let text = ffprobe_fields(ffprobe, path, &[], entries)?;
    let mut info = parse_probe(&text).ok_or_else(|| path_error(format!("{}: no video stream found", path.display())))?;
    // Frames are decoded at the size the header states: refuse one over the budget first.
    if let Some(m) = crate::media::over_budget(path, info.width, info.height) {
        return Err(path_error(m));
    }
    if !info.constant_rate {
        let text = ffprobe_csv(ffprobe, path, "packet=pts_time,duration_time")?;
        // An average rate written with rounding (2997/100 beside 30000/1001), or an interlaced
        // clip whose base rate counts fields (50 beside an average of 25): every frame is on the
        // grid of one of the two rates, none missing, so the clip is constant-rate after all.
        if let Some(rate) = [info.base, info.fps].into_iter().flatten().find(|&r| on_one_grid(&text, r)) {
            info.constant_rate = true;
            info.fps = Some(rate);
        } else if let Some(v) = variable_rate(&text, info.fps, info.base) {
            info.frames = Some(((v.seconds * v.rate).round() as usize).max(1));
            info.fps = Some(v.rate);
            info.variable = Some(v);
        }
    }
    match info.frames {
        _ if info.variable.is_some() => {}
        None => info.frames = count_packets(ffprobe, path)?,
        Some(stated) if info.constant_rate => {
            if let Some(by_time) = decoded_count(ffprobe, path, &info, stated).filter(|&n| n != stated && n > 0) {
                // The last frame's time overstates the count when frames are missing before it (a
                // cut that dropped a frame leaves a gap in the times): no more frames decode than
                // the file has packets.
                let real = count_packets(ffprobe, path)?.map_or(by_time, |p| p.min(by_time));
                if real != stated {
                    info.frames = Some(real);
                    info.stated_frames = Some(stated);
                }
            }
        }
        Some(_) => {}
    }
    if let (Some(k), Ok(mut cache)) = (key, probe_cache().lock()) {
        cache.insert(k, info.clone());
    }
    Ok(info)
}

/// The video stream's packets, counted by reading the file without decoding it.
fn count_packets(ffprobe: &str, path: &Path) -> Result<Option<usize>, IoError> {
    let text = ffprobe_fields(ffprobe, path, &["-count_packets"], "stream=nb_read_packets")?;
    Ok(text.lines().find_map(|l| l.trim().strip_prefix("nb_read_packets=")?.parse().ok()))
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
        .arg(input_url(path))
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
pub(crate) fn last_frame_index(text: &str, start: f64, fps: f64) -> Option<usize> {
    let last = text.lines().filter_map(|l| l.trim().trim_end_matches(',').parse::<f64>().ok()).reduce(f64::max)?;
    let index = ((last - start) * fps).round();
    (index.is_finite() && index >= 0.0).then_some(index as usize)
}

/// Whether the packets' times (`pts_time,…` lines, any order) lie on one grid of `base` frames a
/// second with no step missing: frame `i` within half a frame of `first + i / base`.
pub fn on_one_grid(packets: &str, base: f64) -> bool {
    let mut times: Vec<f64> =
        packets.lines().filter_map(|l| l.split(',').next()?.trim().parse::<f64>().ok()).filter(|t| t.is_finite()).collect();
    if times.len() < 2 || !base.is_finite() || base <= 0.0 {
        return false;
    }
    times.sort_by(f64::total_cmp);
    let first = times[0];
    times.iter().enumerate().all(|(i, t)| ((t - first) * base - i as f64).abs() < 0.5)
}

/// Frame rates cameras and editors use: a variable-rate clip is resampled to one of these.
const STANDARD_RATES: [f64; 12] = [23.976, 24.0, 25.0, 29.97, 30.0, 48.0, 50.0, 59.94, 60.0, 90.0, 100.0, 120.0];

/// Measures a variable-rate stream from `ffprobe`'s `packet=pts_time,duration_time` lines (in any
/// order) and picks the rate to resample it to: its base rate (the finest step of its times) when
/// that is a standard rate no more than twice the average, so no frame is dropped; else the
/// standard rate nearest the average (a phone's 29.8 average becomes 29.97); else the average.
pub fn variable_rate(packets: &str, average: Option<f64>, base: Option<f64>) -> Option<VariableRate> {
    let mut times: Vec<(f64, f64)> = packets
        .lines()
        .filter_map(|l| {
            let mut parts = l.split(',').map(str::trim);
            let t = parts.next()?.parse::<f64>().ok().filter(|t| t.is_finite())?;
            let d = parts.next().and_then(|d| d.parse::<f64>().ok()).filter(|d| d.is_finite() && *d >= 0.0);
            Some((t, d.unwrap_or(0.0)))
        })
        .collect();
    if times.len() < 2 {
        return None;
    }
    times.sort_by(|a, b| a.0.total_cmp(&b.0));
    let (first, (last, last_duration)) = (times[0].0, times[times.len() - 1]);
    // A last packet without a duration lasts as long as the step before it.
    let tail = if last_duration > 0.0 { last_duration } else { last - times[times.len() - 2].0 };
    let seconds = last + tail - first;
    let average = average.unwrap_or((times.len() as f64) / seconds);
    if !(seconds > 0.0 && average > 0.0) {
        return None;
    }
    // 23.976 and 24 are 0.1 % apart: the nearest standard rate, within a twentieth of that.
    let standard = |r: f64| {
        STANDARD_RATES.into_iter().min_by(|a, b| (a - r).abs().total_cmp(&(b - r).abs())).filter(|s| (s - r).abs() <= 5e-5 * s)
    };
    let rate = match base.and_then(standard) {
        Some(b) if b <= 2.0 * average + 1e-9 => b,
        _ => STANDARD_RATES
            .into_iter()
            .min_by(|a, b| (a - average).abs().total_cmp(&(b - average).abs()))
            .filter(|s| (s - average).abs() <= 0.05 * average)
            .unwrap_or(average),
    };
    Some(VariableRate { rate, average, source_frames: times.len(), seconds, first })
}

/// Parses `key=value` lines printed by `ffprobe -show_entries stream=...`.
pub fn parse_probe(text: &str) -> Option<VideoInfo> {
    let field = |key: &str| text.lines().find_map(|l| l.trim().strip_prefix(key)?.strip_prefix('='));
    let width: u32 = field("width")?.parse().ok().filter(|&w| w > 0)?;
    let height: u32 = field("height")?.parse().ok().filter(|&h| h > 0)?;
    let avg = field("avg_frame_rate").and_then(parse_rate);
    let base = field("r_frame_rate").and_then(parse_rate);
    let constant_rate = matches!((avg, base), (Some(a), Some(b)) if (a - b).abs() <= 1e-6 * b);
    let frames = field("nb_frames").and_then(|n| n.parse().ok()).filter(|&n| n > 0);
    let start = field("start_time").and_then(|t| t.parse::<f64>().ok()).filter(|t| t.is_finite()).unwrap_or(0.0);
    let rotation = field("rotation")
        .or_else(|| field("TAG:rotate"))
        .and_then(|r| r.parse::<f64>().ok())
        .filter(|r| r.is_finite())
        .map_or(0, |r| r.round() as i32);
    // A quarter turn shows the picture on its side: what decodes is as high as the file is wide.
    let (width, height) = if rotation.rem_euclid(180) == 90 { (height, width) } else { (width, height) };
    let bits = sample_bits(field("bits_per_raw_sample").and_then(|b| b.parse().ok()), field("pix_fmt").unwrap_or(""));
    Some(VideoInfo {
        width,
        height,
        fps: avg.or(base),
        frames,
        stated_frames: None,
        start,
        constant_rate,
        rotation,
        bits,
        variable: None,
        base,
    })
}

/// Bits per sample: what the stream states, else read from its pixel format's name. ffmpeg names
/// every format whose samples take more than a byte with its byte order (`yuv420p10le`, `p010le`,
/// `rgb48be`); 8-bit formats have none (`yuv420p`, `nv12`, `rgb24`).
fn sample_bits(stated: Option<u32>, pix_fmt: &str) -> u32 {
    match stated.filter(|b| (1..=32).contains(b)) {
        Some(b) => b,
        None if pix_fmt.ends_with("le") || pix_fmt.ends_with("be") => 16,
        None => 8,
    }
}

/// `30000/1001` or `25` → frames per second; `None` for `0/0` and other non-rates.
fn parse_rate(text: &str) -> Option<f64> {
    let rate = match text.split_once('/') {
        Some((n, d)) => n.trim().parse::<f64>().ok()? / d.trim().parse::<f64>().ok()?,
        None => text.trim().parse().ok()?,
    };
    (rate.is_finite() && rate > 0.0).then_some(rate)
}
