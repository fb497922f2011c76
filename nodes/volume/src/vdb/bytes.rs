//! Little-endian byte reading with bounds checks (every count is checked against the bytes left
//! before anything is allocated) and writing, for the OpenVDB file format.

use super::VdbError;

/// A cursor over a file's bytes.
pub struct Reader<'a> {
    data: &'a [u8],
    pos: usize,
    /// What is being read, for errors ("the 4-node masks of grid 'density'").
    pub what: String,
}

impl<'a> Reader<'a> {
    /// A reader at the start of `data`.
    pub fn new(data: &'a [u8]) -> Self {
        Reader { data, pos: 0, what: "the file header".into() }
    }

    /// The byte offset.
    pub fn pos(&self) -> usize {
        self.pos
    }

    /// Bytes left.
    pub fn left(&self) -> usize {
        self.data.len() - self.pos
    }

    /// Moves to byte `pos` (within the file).
    pub fn seek(&mut self, pos: u64) -> Result<(), VdbError> {
        if pos > self.data.len() as u64 {
            return Err(VdbError::Invalid(format!(
                "{} points to byte {pos}, past the end of the file ({} bytes)",
                self.what,
                self.data.len()
            )));
        }
        self.pos = pos as usize;
        Ok(())
    }

    /// The next `n` bytes.
    pub fn bytes(&mut self, n: usize) -> Result<&'a [u8], VdbError> {
        if n > self.left() {
            return Err(VdbError::Truncated { at: self.pos, what: self.what.clone() });
        }
        let s = &self.data[self.pos..self.pos + n];
        self.pos += n;
        Ok(s)
    }

    fn array<const N: usize>(&mut self) -> Result<[u8; N], VdbError> {
        let mut a = [0; N];
        a.copy_from_slice(self.bytes(N)?);
        Ok(a)
    }

    /// A u8.
    pub fn u8(&mut self) -> Result<u8, VdbError> {
        Ok(self.bytes(1)?[0])
    }
    /// A u32.
    pub fn u32(&mut self) -> Result<u32, VdbError> {
        Ok(u32::from_le_bytes(self.array()?))
    }
    /// An i32.
    pub fn i32(&mut self) -> Result<i32, VdbError> {
        Ok(i32::from_le_bytes(self.array()?))
    }
    /// An i64.
    pub fn i64(&mut self) -> Result<i64, VdbError> {
        Ok(i64::from_le_bytes(self.array()?))
    }
    /// An f32.
    pub fn f32(&mut self) -> Result<f32, VdbError> {
        Ok(f32::from_le_bytes(self.array()?))
    }
    /// An f64.
    pub fn f64(&mut self) -> Result<f64, VdbError> {
        Ok(f64::from_le_bytes(self.array()?))
    }

    /// A string: u32 length, then that many bytes (at most `max`).
    pub fn string(&mut self, max: usize) -> Result<String, VdbError> {
        let n = self.u32()? as usize;
        if n > max || n > self.left() {
            return Err(VdbError::Invalid(format!(
                "{} declares a {n}-byte string, longer than the {} bytes allowed there",
                self.what,
                max.min(self.left())
            )));
        }
        Ok(String::from_utf8_lossy(self.bytes(n)?).into_owned())
    }

    /// A count of records of at least `min_bytes` each, refused when they could not fit in what is
    /// left of the file (so an absurd count never reaches an allocation).
    pub fn count(&mut self, min_bytes: usize, what: &str) -> Result<usize, VdbError> {
        let n = self.u32()? as usize;
        if n.saturating_mul(min_bytes.max(1)) > self.left() {
            return Err(VdbError::Invalid(format!(
                "{} declares {n} {what}, more than the {} bytes left in the file can hold",
                self.what,
                self.left()
            )));
        }
        Ok(n)
    }
}

/// Little-endian writing into a byte vector.
#[derive(Default)]
pub struct Writer {
    /// The bytes so far.
    pub buf: Vec<u8>,
}

impl Writer {
    /// Appends bytes.
    pub fn bytes(&mut self, b: &[u8]) {
        self.buf.extend_from_slice(b);
    }
    /// Appends a u8.
    pub fn u8(&mut self, v: u8) {
        self.buf.push(v);
    }
    /// Appends a u32.
    pub fn u32(&mut self, v: u32) {
        self.bytes(&v.to_le_bytes());
    }
    /// Appends an i32.
    pub fn i32(&mut self, v: i32) {
        self.bytes(&v.to_le_bytes());
    }
    /// Appends an i64.
    pub fn i64(&mut self, v: i64) {
        self.bytes(&v.to_le_bytes());
    }
    /// Appends an f32.
    pub fn f32(&mut self, v: f32) {
        self.bytes(&v.to_le_bytes());
    }
    /// Appends an f64.
    pub fn f64(&mut self, v: f64) {
        self.bytes(&v.to_le_bytes());
    }
    /// Appends a string (u32 length, bytes).
    pub fn string(&mut self, s: &str) {
        self.u32(s.len() as u32);
        self.bytes(s.as_bytes());
    }
    /// Overwrites 8 bytes at `at` with `v`.
    pub fn patch_i64(&mut self, at: usize, v: i64) {
        self.buf[at..at + 8].copy_from_slice(&v.to_le_bytes());
    }
}
