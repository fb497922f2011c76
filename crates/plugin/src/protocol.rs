//! The wire between pyrograph and a Python worker (`host/pyrograph_host.py`): every message is a
//! little-endian `u32` length and that many bytes of UTF-8 JSON holding an `"op"`. Arrays never
//! travel here; they sit in the arena file (`arena.rs`) and a message gives their offset, shape
//! and dtype. Framing is written by hand: it is a few lines, and the Python side has to match it
//! with nothing but its standard library.

use std::io::{self, Read, Write};

use serde::Deserialize;

use crate::decl::NodeDecl;

/// The largest message either side accepts: declarations and tracebacks, never pixels.
pub const MAX_FRAME: usize = 16 << 20;

/// Why a message could not be read.
#[derive(Debug, thiserror::Error)]
pub enum FrameError {
    /// The pipe failed or ended inside a message.
    #[error("the connection broke: {0}")]
    Io(#[from] io::Error),
    /// A length over [`MAX_FRAME`].
    #[error("a message of {0} bytes is over the {MAX_FRAME}-byte limit")]
    TooLong(usize),
    /// Not JSON, or not a message this side knows.
    #[error("an unreadable message: {0}")]
    Json(#[from] serde_json::Error),
}

/// Writes one message.
pub fn write_frame(w: &mut impl Write, msg: &serde_json::Value) -> io::Result<()> {
    let body = serde_json::to_vec(msg)?;
    let len = u32::try_from(body.len()).ok().filter(|&n| n as usize <= MAX_FRAME);
    let len = len.ok_or_else(|| io::Error::other(format!("a message of {} bytes is too long to send", body.len())))?;
    w.write_all(&len.to_le_bytes())?;
    w.write_all(&body)?;
    w.flush()
}

/// Reads one message; `None` when the stream ends cleanly between messages.
pub fn read_frame(r: &mut impl Read) -> Result<Option<Reply>, FrameError> {
    let mut len = [0u8; 4];
    // A clean end is an end before the first byte of a length.
    match r.read(&mut len[..1])? {
        0 => return Ok(None),
        _ => r.read_exact(&mut len[1..])?,
    }
    let len = u32::from_le_bytes(len) as usize;
    if len > MAX_FRAME {
        return Err(FrameError::TooLong(len));
    }
    let mut body = vec![0u8; len];
    r.read_exact(&mut body)?;
    Ok(Some(serde_json::from_slice(&body)?))
}

/// A message from the worker.
#[derive(Debug, Deserialize)]
#[serde(tag = "op", rename_all = "snake_case")]
pub enum Reply {
    /// The worker started and has numpy.
    Ready {
        /// Python's version.
        python: String,
        /// numpy's version.
        numpy: String,
    },
    /// What each plugin file declares.
    Described {
        /// One entry per file asked about, in order.
        files: Vec<DescribedFile>,
    },
    /// A cook's outputs, in declared order.
    Result {
        /// The request's id.
        id: u64,
        /// One per declared output.
        outputs: Vec<OutputSpec>,
    },
    /// A whole-clip cook asks for frame `index` of its clip input `clip`.
    NeedFrame {
        /// The request's id.
        id: u64,
        /// The clip input.
        clip: String,
        /// The frame, from 0 (negative indices are resolved by the worker).
        index: i64,
    },
    /// A whole-clip cook hands over frame `index` of its clip output `port`.
    Emit {
        /// The request's id.
        id: u64,
        /// The clip output.
        port: String,
        /// The frame, from 0, in order.
        index: u64,
        /// Where the frame lies in the arena.
        array: ArraySpec,
    },
    /// A cook failed.
    Error(CookFailure),
    /// The worker cannot go on (no numpy, a malformed request) and exits.
    Fatal {
        /// Why.
        message: String,
    },
}

impl Reply {
    /// The message's `op`, for errors that say what arrived instead of what was due.
    pub fn op(&self) -> &'static str {
        match self {
            Reply::Ready { .. } => "ready",
            Reply::Described { .. } => "described",
            Reply::Result { .. } => "result",
            Reply::NeedFrame { .. } => "need_frame",
            Reply::Emit { .. } => "emit",
            Reply::Error(_) => "error",
            Reply::Fatal { .. } => "fatal",
        }
    }
}

/// One plugin file's declarations, or why it could not be loaded.
#[derive(Debug, Deserialize)]
pub struct DescribedFile {
    /// The file, as asked.
    pub path: String,
    /// The node types it declares.
    #[serde(default)]
    pub nodes: Vec<NodeDecl>,
    /// Why it could not be loaded.
    pub error: Option<PyError>,
}

/// A Python exception, with the frames of the plugin's own code.
#[derive(Debug, Deserialize)]
pub struct PyError {
    /// The exception's class (`ZeroDivisionError`).
    pub exception: Option<String>,
    /// Its message.
    pub message: String,
    /// The innermost frames outside pyrograph's own Python files.
    #[serde(default)]
    pub frames: Vec<PyFrame>,
}

/// One traceback frame.
#[derive(Debug, Deserialize)]
pub struct PyFrame {
    /// The source file.
    pub file: String,
    /// The line, from 1.
    pub line: u64,
    /// The function.
    pub function: String,
    /// The line's code, when Python has it.
    pub code: Option<String>,
}

/// A failed cook.
#[derive(Debug, Deserialize)]
pub struct CookFailure {
    /// The request's id.
    pub id: u64,
    /// `exception` (the function raised), `port` (it returned the wrong thing), `load` (its
    /// file failed to load), `frame_error` (a frame it asked for failed upstream) or `cancelled`.
    pub kind: String,
    /// The output the return check blames.
    pub port: Option<String>,
    /// The exception and where it was raised.
    #[serde(flatten)]
    pub error: PyError,
}

/// One output of a cook: an array in the arena, or a plain value.
#[derive(Debug, Deserialize)]
pub struct OutputSpec {
    /// The output port.
    pub port: String,
    /// Where an array output lies in the arena.
    pub array: Option<ArraySpec>,
    /// A number or flag output.
    pub value: Option<serde_json::Value>,
    /// How many frames a clip output emitted.
    pub frames: Option<u64>,
}

/// An array in the arena.
#[derive(Debug, Clone, Deserialize, serde::Serialize, PartialEq)]
pub struct ArraySpec {
    /// Byte offset in the arena.
    pub offset: u64,
    /// numpy's shape.
    pub shape: Vec<u64>,
    /// numpy's dtype string: `<f4` (float32) or `|u1` (uint8).
    pub dtype: String,
}

impl PyError {
    /// The exception, its message, and the innermost frames as `file:line in function: code`
    /// lines, the way a traceback ends.
    pub fn render(&self) -> String {
        let mut s = match &self.exception {
            Some(e) => format!("{e}: {}", self.message),
            None => self.message.clone(),
        };
        for f in &self.frames {
            s.push_str(&format!("\n    {}:{} in {}", f.file, f.line, f.function));
            if let Some(code) = f.code.as_deref().map(str::trim).filter(|c| !c.is_empty()) {
                s.push_str(&format!(": {code}"));
            }
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn a_message_goes_round() {
        let mut buf = Vec::new();
        write_frame(&mut buf, &serde_json::json!({"op": "fatal", "message": "no numpy"})).unwrap();
        assert_eq!(&buf[..4], &(buf.len() as u32 - 4).to_le_bytes());
        match read_frame(&mut buf.as_slice()).unwrap() {
            Some(Reply::Fatal { message }) => assert_eq!(message, "no numpy"),
            other => panic!("{other:?}"),
        }
        assert!(read_frame(&mut &b""[..]).unwrap().is_none(), "a clean end is no message");
    }

    #[test]
    fn a_failed_cook_reads_with_its_frames() {
        let body = br#"{"op":"error","id":7,"kind":"exception","port":null,"exception":"ZeroDivisionError",
            "message":"division by zero","frames":[{"file":"/p/x.py","line":23,"function":"f","code":"  y = 1 / 0"}]}"#;
        let mut buf = (body.len() as u32).to_le_bytes().to_vec();
        buf.extend_from_slice(body);
        let Some(Reply::Error(f)) = read_frame(&mut buf.as_slice()).unwrap() else { panic!() };
        assert_eq!((f.id, f.kind.as_str()), (7, "exception"));
        assert_eq!(f.error.render(), "ZeroDivisionError: division by zero\n    /p/x.py:23 in f: y = 1 / 0");
    }

    #[test]
    fn long_truncated_and_garbled_messages_are_errors() {
        let huge = (MAX_FRAME as u32 + 1).to_le_bytes();
        assert!(matches!(read_frame(&mut &huge[..]), Err(FrameError::TooLong(_))));
        let cut = [10u8, 0, 0, 0, b'{'];
        assert!(matches!(read_frame(&mut &cut[..]), Err(FrameError::Io(_))));
        let garbled = [2u8, 0, 0, 0, b'{', b'x'];
        assert!(matches!(read_frame(&mut &garbled[..]), Err(FrameError::Json(_))));
        let half_length = [2u8, 0];
        assert!(matches!(read_frame(&mut &half_length[..]), Err(FrameError::Io(_))));
    }

    proptest! {
        #[test]
        fn no_byte_string_panics_the_reader(bytes in proptest::collection::vec(any::<u8>(), 0..64)) {
            let _ = read_frame(&mut bytes.as_slice());
        }
    }
}
