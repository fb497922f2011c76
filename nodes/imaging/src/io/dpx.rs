//! DPX (SMPTE 268M) files, the film-scan and grading format: the size is read from the header
//! here, the pixels are decoded by the `ffmpeg` executable.
//!
//! Why so: no maintained Rust crate decodes DPX, while ffmpeg's decoder handles every packing
//! studios write (8-bit, 10-bit filled to 32-bit words in either method, 12 and 16 bits, either
//! byte order, RGB and RGBA). Only the two size fields of the header are read by hand, so a file
//! is checked against the pixel budget before ffmpeg allocates anything.

use std::io::Read;
use std::path::Path;
use std::process::{Command, Stdio};

use pyrograph_core::{Channels, Image};

use crate::media::IoError;

/// Bytes of the header up to and including the first image element's bit size.
const HEADER: usize = 804;

/// Width and height from a DPX header: pixels per line at byte 772 and lines per element at 776,
/// in the byte order its magic number (`SDPX` big-endian, `XPDS` little-endian) states.
pub fn dpx_dimensions(path: &Path) -> Result<(u32, u32), IoError> {
    dpx_header(path).map(|(w, h, _)| (w, h))
}

/// Width, height and the first image element's bits per sample (byte 803).
fn dpx_header(path: &Path) -> Result<(u32, u32, u8), IoError> {
    let named = |e: &dyn std::fmt::Display| IoError::Message(format!("{}: {e}", path.display()));
    let mut head = [0u8; HEADER];
    let mut file = std::fs::File::open(path).map_err(|e| named(&e))?;
    file.read_exact(&mut head).map_err(|_| named(&format!("not a DPX file: shorter than a DPX header ({HEADER} bytes)")))?;
    let word = |at: usize| -> [u8; 4] { [head[at], head[at + 1], head[at + 2], head[at + 3]] };
    let read: fn([u8; 4]) -> u32 = match &head[..4] {
        b"SDPX" => u32::from_be_bytes,
        b"XPDS" => u32::from_le_bytes,
        _ => return Err(named(&"not a DPX file: it does not start with SDPX or XPDS")),
    };
    let (w, h) = (read(word(772)), read(word(776)));
    if w == 0 || h == 0 || w == u32::MAX || h == u32::MAX {
        return Err(named(&format!("the DPX header states no usable size ({w} × {h})")));
    }
    Ok((w, h, head[803]))
}

/// Decodes a DPX file (whose size, `w` × `h`, was checked against the budget) with `ffmpeg`: 8-bit
/// files at 8 bits, deeper ones at 16 so 10- and 12-bit scans keep their precision (ffmpeg's
/// widening of 8-bit samples to 16 is not exact); RGBA, alpha 1 where the file has none.
pub fn decode_dpx(path: &Path, (w, h): (u32, u32)) -> Result<Image, IoError> {
    let named = |e: &dyn std::fmt::Display| IoError::Message(format!("{}: {e}", path.display()));
    let deep = dpx_header(path)?.2 > 8;
    let out = Command::new("ffmpeg")
        .args(["-v", "error", "-nostdin", "-f", "dpx_pipe", "-i"])
        // `file:` so a name with a colon or a leading dash is never read as a protocol or option,
        // joined to the path's own bytes so a name that is not UTF-8 arrives whole.
        .arg({
            let mut url = std::ffi::OsString::from("file:");
            url.push(path.as_os_str());
            url
        })
        .args(["-frames:v", "1", "-f", "rawvideo", "-pix_fmt", if deep { "rgba64le" } else { "rgba" }, "-"])
        .stdin(Stdio::null())
        .output()
        .map_err(|e| {
            if e.kind() == std::io::ErrorKind::NotFound {
                named(&"DPX files are decoded with ffmpeg, which is not on PATH; install ffmpeg (apt-get install ffmpeg) or convert the frames to EXR, TIFF or PNG")
            } else {
                named(&format!("could not run ffmpeg: {e}"))
            }
        })?;
    let pixels = w as usize * h as usize;
    let bytes = if deep { 2 } else { 1 };
    if !out.status.success() || out.stdout.len() != pixels * 4 * bytes {
        let why = String::from_utf8_lossy(&out.stderr);
        let why = why.trim().lines().last().unwrap_or("it decoded to the wrong size").to_string();
        return Err(named(&format!("ffmpeg could not decode this DPX file: {why}")));
    }
    let data = if deep {
        out.stdout.chunks_exact(2).map(|s| f32::from(u16::from_le_bytes([s[0], s[1]])) / 65535.0).collect()
    } else {
        out.stdout.iter().map(|&v| f32::from(v) / 255.0).collect()
    };
    Image::from_vec(w, h, Channels::Rgba, data).ok_or_else(|| named(&"frame size mismatch"))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn header(magic: &[u8; 4], w: u32, h: u32, big: bool) -> Vec<u8> {
        let mut b = vec![0u8; 2048];
        b[..4].copy_from_slice(magic);
        let put = |b: &mut Vec<u8>, at: usize, v: u32| {
            b[at..at + 4].copy_from_slice(&if big { v.to_be_bytes() } else { v.to_le_bytes() });
        };
        put(&mut b, 772, w);
        put(&mut b, 776, h);
        b
    }

    #[test]
    fn the_size_is_read_in_the_byte_order_the_magic_states() {
        let dir = tempfile::tempdir().unwrap();
        let (big, little) = (dir.path().join("b.dpx"), dir.path().join("l.dpx"));
        std::fs::write(&big, header(b"SDPX", 2048, 1556, true)).unwrap();
        std::fs::write(&little, header(b"XPDS", 1920, 1080, false)).unwrap();
        assert_eq!(dpx_dimensions(&big).unwrap(), (2048, 1556));
        assert_eq!(dpx_dimensions(&little).unwrap(), (1920, 1080));
        // The same bytes read in the other order would be enormous: the magic decides.
        std::fs::write(&little, header(b"XPDS", 1920, 1080, true)).unwrap();
        assert_ne!(dpx_dimensions(&little).unwrap(), (1920, 1080));
    }

    #[test]
    fn a_file_that_is_not_dpx_is_named_and_refused() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("x.dpx");
        std::fs::write(&path, b"SDPX short").unwrap();
        let e = dpx_dimensions(&path).unwrap_err().to_string();
        assert!(e.contains("x.dpx") && e.contains("shorter than a DPX header"), "{e}");
        std::fs::write(&path, header(b"PNG!", 4, 4, true)).unwrap();
        assert!(dpx_dimensions(&path).unwrap_err().to_string().contains("does not start with SDPX"));
        std::fs::write(&path, header(b"SDPX", 0, 4, true)).unwrap();
        assert!(dpx_dimensions(&path).unwrap_err().to_string().contains("no usable size (0 × 4)"));
    }
}
