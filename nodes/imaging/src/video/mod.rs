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

use crate::media::{DEFAULT_FPS, IoError, ReportError, fingerprint_files};

mod probe;

pub use probe::{VariableRate, VideoInfo, decoded_count, on_one_grid, parse_probe, probe_video, variable_rate};
use probe::{input_url, path_error, run_error};

/// A cursor this many frames behind a request reads on to it rather than seeking (a seek decodes
/// from the previous keyframe anyway, and starting a process costs a few milliseconds).
const SKIP_LIMIT: usize = 48;

/// One `ffmpeg` process decoding the first video stream to packed RGB (8 or 16 bits a sample)
/// from frame `next`.
struct Cursor {
    child: Child,
    stdout: ChildStdout,
    stderr: Option<JoinHandle<String>>,
    next: usize,
    /// The last frame read, kept for a resampled clip whose final frame holds the one before.
    last: Option<Vec<u8>>,
}

impl Cursor {
    /// Starts decoding at frame `start`, seeking to its time when `seek` is given (seconds). The
    /// picture is turned as its rotation says (ffmpeg's default), a variable-rate stream is
    /// resampled by timestamps, and sources over 8 bits decode at 16.
    fn spawn(ffmpeg: &str, path: &Path, info: &VideoInfo, start: usize, seek: Option<f64>) -> Result<Cursor, IoError> {
        let mut cmd = Command::new(ffmpeg);
        cmd.args(["-v", "error", "-nostdin"]);
        match (seek, &info.variable) {
            (Some(t), None) => {
                // An input seek is exact in ffmpeg: it decodes from the keyframe before `t` and
                // drops the frames before it. Half a frame early lands on frame `start` whatever
                // the rounding.
                cmd.arg("-ss").arg(format!("{t:.6}"));
            }
            (Some(t), Some(_)) => {
                // A resampled clip: decode from the keyframe before `t` (a time in the stream's
                // own clock, not after the file's start) keeping every frame and its own time, so
                // the resampler below sees what a walk from the start sees there.
                cmd.args(["-noaccurate_seek", "-seek_timestamp", "1", "-ss"]).arg(format!("{t:.6}"));
            }
            (None, _) => {}
        }
        if info.variable.is_some() {
            cmd.arg("-copyts");
        }
        cmd.arg("-i").arg(input_url(path)).args(["-map", "0:v:0", "-an", "-sn", "-dn"]);
        if let Some(v) = &info.variable {
            // Each output frame is the source frame on screen at its time, on a grid from the
            // clip's first frame (in the stream's own clock, the same for a walk and a seek); after
            // a seek, the frames before `start` are dropped here.
            let rate = rate_text(v.rate);
            let grid = format!("fps={rate}:start_time={:.6}", v.first);
            cmd.arg("-vf").arg(if start > 0 { format!("{grid},select='gte(n\\,{start})'") } else { grid });
        }
        // Every frame out of the decoder (or the resampler) once, in order.
        cmd.args(["-vsync", "passthrough", "-f", "rawvideo", "-pix_fmt", if info.bits > 8 { "rgb48le" } else { "rgb24" }, "-"])
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
            return Err(IoError::Message("ffmpeg's output pipe is missing".to_string()));
        };
        Ok(Cursor { child, stdout, stderr, next: start, last: info.variable.as_ref().map(|_| Vec::new()) })
    }

    /// Reads the next frame into `buf`; `Ok(false)` when the stream ended.
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<bool> {
        let ok = read_full(&mut self.stdout, buf)?;
        if ok {
            self.next += 1;
            if let Some(last) = &mut self.last {
                last.clear();
                last.extend_from_slice(buf);
            }
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

/// A rate as ffmpeg's `fps` filter reads it: the NTSC rates as their exact fractions.
fn rate_text(rate: f64) -> String {
    for (approx, exact) in [(23.976, "24000/1001"), (29.97, "30000/1001"), (59.94, "60000/1001")] {
        if (rate - approx).abs() < 1e-3 {
            return exact.to_string();
        }
    }
    format!("{rate:.6}")
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
        let seek = match &self.info.variable {
            _ if index == 0 => None,
            Some(v) => Some((v.first + (index as f64 - 0.5) / v.rate).max(0.0)),
            None if self.info.constant_rate => Some(((index as f64 - 0.5) / self.fps).max(0.0)),
            None => None,
        };
        match seek {
            Some(t) => Cursor::spawn(&self.ffmpeg, &self.path, &self.info, index, Some(t)),
            None => Cursor::spawn(&self.ffmpeg, &self.path, &self.info, 0, None),
        }
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
        let sample_bytes = if self.info.bits > 8 { 2 } else { 1 };
        let mut buf = vec![0u8; w as usize * h as usize * 3 * sample_bytes];
        while cursor.next <= index {
            // Cancelling drops the cursor, which ends its process; nothing half-made is cached.
            ctx.check_cancel()?;
            let at = cursor.next;
            let got = cursor.read(&mut buf).map_err(|e| NodeError::msg(format!("reading ffmpeg's output: {e}")))?;
            if got {
                continue;
            }
            // The resampler's count can differ from the one computed from timestamps by a frame at
            // the end (rounding of the last frame's duration): the last frames hold the one before.
            let near_end = self.info.variable.is_some() && at + 2 >= self.len && at > 0;
            if let Some(last) = cursor.last.take().filter(|l| l.len() == buf.len() && near_end) {
                buf = last;
                break;
            }
            if near_end && at == index {
                // A cursor that started here (a seek) has no frame before to hold: the one before
                // is the answer, decoded by a cursor of its own (at most two frames back).
                drop(cursor);
                return self.frame(at - 1, ctx);
            }
            let why = cursor.finish();
            let why = why.trim();
            let why = if why.is_empty() { String::new() } else { format!(" (ffmpeg: {})", why.lines().last().unwrap_or(why)) };
            return Err(NodeError::msg(format!(
                "{}: the video ends before frame {at} although it states {} frames: it is truncated or corrupt{why}",
                self.path.display(),
                self.len
            )));
        }
        if cursor.next > index {
            self.give_back(cursor);
        }
        let image = if sample_bytes == 2 { rgb48_to_image(w, h, &buf) } else { rgb24_to_image(w, h, &buf) };
        let image = image.map_err(NodeError::msg)?;
        Ok(Value::Image(Arc::new(image)))
    }
}

/// Packed 8-bit RGB to an opaque f32 RGBA image.
pub fn rgb24_to_image(width: u32, height: u32, rgb: &[u8]) -> Result<Image, String> {
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
        format!("a {width}x{height} frame needs {} bytes, got {}", width as usize * height as usize * 3, rgb.len())
    })
}

/// Packed 16-bit little-endian RGB (ffmpeg's `rgb48le`) to an opaque f32 RGBA image: 10-, 12- and
/// 16-bit sources keep their precision.
pub fn rgb48_to_image(width: u32, height: u32, rgb: &[u8]) -> Result<Image, String> {
    let pixels = width as usize * height as usize;
    if rgb.len() != pixels * 6 {
        return Err(format!("a {width}x{height} frame needs {} bytes, got {}", pixels * 6, rgb.len()));
    }
    let mut data = vec![1.0_f32; pixels * 4];
    for (o, p) in data.chunks_exact_mut(4).zip(rgb.chunks_exact(6)) {
        for c in 0..3 {
            o[c] = f32::from(u16::from_le_bytes([p[2 * c], p[2 * c + 1]])) / 65535.0;
        }
    }
    Image::from_vec(width, height, Channels::Rgba, data).ok_or_else(|| "frame size mismatch".to_string())
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
    let mut info = probe_video(ffprobe, path)?;
    if let Some(v) = info.variable.as_mut().filter(|_| fps > 0.0) {
        // A variable-rate clip has no frames of its own: the rate asked for is the one to sample.
        v.rate = fps;
        info.frames = Some(((v.seconds * fps).round() as usize).max(1));
    }
    let len = info.frames.ok_or_else(|| path_error(format!("{}: the video has no frames", path.display())))?;
    if let Some(stated) = info.stated_frames {
        ctx.warn(format!(
            "{}: the video's header states {stated} frames but {len} decode (the count in a header is an \
             estimate, e.g. where a trimmed clip hides frames); using the {len} that decode",
            path.display()
        ));
    }
    let mut fingerprint = fingerprint_files(&[path.to_path_buf()])?;
    if let Some(v) = &info.variable {
        ctx.warn(format!(
            "{}: the video has a variable frame rate ({} frames over {:.2} s, {} fps on average): \
             resampled by their timestamps to {} fps, {len} frames (a frame repeats or is skipped where its \
             time falls); set fps to sample it at another rate",
            path.display(),
            v.source_frames,
            v.seconds,
            rate_label(v.average),
            rate_label(v.rate)
        ));
        let mut h = pyrograph_core::fingerprint::Fingerprinter::new();
        std::hash::Hash::hash(&(fingerprint, v.rate.to_bits()), &mut h);
        fingerprint = std::hash::Hasher::finish(&h);
    }
    let source_fps = info.fps.unwrap_or(DEFAULT_FPS);
    let source_fps = info.variable.as_ref().map_or(source_fps, |v| v.rate);
    let fps = if fps > 0.0 { fps } else { source_fps };
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

/// A rate for people: `24`, `29.97`, `12.5`.
fn rate_label(rate: f64) -> String {
    let text = format!("{rate:.3}");
    text.trim_end_matches('0').trim_end_matches('.').to_string()
}

#[cfg(test)]
mod tests;
