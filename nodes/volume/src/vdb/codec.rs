//! The codecs of OpenVDB value arrays: zlib (through flate2) and Blosc 1 frames with LZ4 blocks
//! and byte shuffling (the blocks through lz4_flex; the frame layout and the unshuffle are the
//! few lines c-blosc's format needs, written here because no maintained Rust crate decodes Blosc 1
//! frames without linking the C library).

use std::io::{Read, Write};

use super::VdbError;

/// Inflates a zlib stream into exactly `expected` bytes.
pub fn unzip(data: &[u8], expected: usize) -> Result<Vec<u8>, VdbError> {
    let mut out = Vec::with_capacity(expected);
    let mut z = flate2::read::ZlibDecoder::new(data).take(expected as u64 + 1);
    z.read_to_end(&mut out).map_err(|e| VdbError::Invalid(format!("a zlib block does not inflate: {e}")))?;
    if out.len() != expected {
        return Err(VdbError::Invalid(format!(
            "a zlib block inflates to {} bytes, not the {expected} its node needs",
            out.len()
        )));
    }
    Ok(out)
}

/// Deflates `data` as a zlib stream.
pub fn zip(data: &[u8]) -> Vec<u8> {
    let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::default());
    // Writing into a Vec cannot fail.
    let _ = z.write_all(data);
    z.finish().unwrap_or_default()
}

/// Decodes a Blosc 1 frame into exactly `expected` bytes (c-blosc 1.x's chunk format: a 16-byte
/// header, block starts, per block one or `typesize` LZ4 streams, then the byte unshuffle).
pub fn unblosc(frame: &[u8], expected: usize) -> Result<Vec<u8>, VdbError> {
    let bad = |m: &str| VdbError::Invalid(format!("a Blosc block {m}"));
    if frame.len() < 16 {
        return Err(bad("is shorter than its 16-byte header"));
    }
    let (version, flags, typesize) = (frame[0], frame[2], frame[3] as usize);
    let word = |at: usize| u32::from_le_bytes([frame[at], frame[at + 1], frame[at + 2], frame[at + 3]]) as usize;
    let (nbytes, blocksize, cbytes) = (word(4), word(8), word(12));
    if version != 2 || flags & 0x0c != 0 || typesize == 0 {
        return Err(bad(&format!("has an unsupported header (version {version}, flags {flags:#x}, type size {typesize})")));
    }
    if nbytes != expected || cbytes != frame.len() {
        return Err(bad(&format!("holds {nbytes} bytes in {cbytes}, but its node needs {expected} in {}", frame.len())));
    }
    if nbytes == 0 {
        return Ok(Vec::new());
    }
    if flags & 0x02 != 0 {
        // Stored as it is (not shuffled, whatever the shuffle bit says).
        if cbytes != nbytes + 16 {
            return Err(bad("is marked as stored but its size does not match"));
        }
        return Ok(frame[16..].to_vec());
    }
    if blocksize == 0 || blocksize > nbytes {
        return Err(bad(&format!("has a block size of {blocksize} for {nbytes} bytes")));
    }
    let blocks = nbytes.div_ceil(blocksize);
    if 16 + 4 * blocks > cbytes {
        return Err(bad("has more block starts than bytes"));
    }
    let mut out = vec![0u8; nbytes];
    let leftover = nbytes % blocksize;
    for b in 0..blocks {
        let last_short = b + 1 == blocks && leftover > 0;
        let size = if last_short { leftover } else { blocksize };
        let splits = if flags & 0x10 == 0 && typesize <= 16 && blocksize / typesize >= 128 && !last_short { typesize } else { 1 };
        let part = size / splits;
        let mut pos = word(16 + 4 * b);
        let mut tmp = Vec::with_capacity(size);
        for _ in 0..splits {
            if pos + 4 > cbytes {
                return Err(bad("points past its end"));
            }
            let csize = word(pos);
            pos += 4;
            if csize > cbytes - pos {
                return Err(bad("holds a stream longer than itself"));
            }
            let src = &frame[pos..pos + csize];
            if csize == part {
                tmp.extend_from_slice(src);
            } else {
                let start = tmp.len();
                tmp.resize(start + part, 0);
                let n = lz4_flex::block::decompress_into(src, &mut tmp[start..])
                    .map_err(|e| bad(&format!("does not decode: {e}")))?;
                if n != part {
                    return Err(bad(&format!("decodes to {n} bytes, not {part}")));
                }
            }
            pos += csize;
        }
        if tmp.len() != size {
            return Err(bad("decodes to the wrong size"));
        }
        let dst = &mut out[b * blocksize..b * blocksize + size];
        if flags & 0x01 != 0 && typesize > 1 {
            unshuffle(&tmp, typesize, dst);
        } else {
            dst.copy_from_slice(&tmp);
        }
    }
    Ok(out)
}

/// Undoes Blosc's byte shuffle of one block: byte j of value i was stored at j·(n / ts) + i.
fn unshuffle(src: &[u8], ts: usize, dst: &mut [u8]) {
    let q = src.len() / ts;
    for i in 0..q {
        for j in 0..ts {
            dst[i * ts + j] = src[j * q + i];
        }
    }
    dst[q * ts..].copy_from_slice(&src[q * ts..]);
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A Blosc frame as c-blosc lays one out, built here with lz4_flex: one block, shuffled, split
    /// into `typesize` streams.
    pub(crate) fn blosc_frame(data: &[u8], ts: usize) -> Vec<u8> {
        let q = data.len() / ts;
        let mut shuffled = vec![0; data.len()];
        for i in 0..q {
            for j in 0..ts {
                shuffled[j * q + i] = data[i * ts + j];
            }
        }
        let mut f = vec![2, 1, 0x21, ts as u8];
        f.extend((data.len() as u32).to_le_bytes());
        f.extend((data.len() as u32).to_le_bytes());
        f.extend([0; 4]);
        f.extend(20u32.to_le_bytes());
        for s in shuffled.chunks(q) {
            let c = lz4_flex::block::compress(s);
            f.extend((c.len() as u32).to_le_bytes());
            f.extend(c);
        }
        let n = f.len() as u32;
        f[12..16].copy_from_slice(&n.to_le_bytes());
        f
    }

    #[test]
    fn blosc_frames_split_shuffled_or_stored_decode_and_bad_ones_are_refused() {
        let data: Vec<u8> = (0..2048u32).flat_map(|i| ((i % 37) as f32 * 0.25).to_le_bytes()).take(2048).collect();
        let frame = blosc_frame(&data, 4);
        assert_eq!(unblosc(&frame, 2048).unwrap(), data);
        let mut stored = vec![2, 1, 0x33, 4];
        stored.extend(8u32.to_le_bytes());
        stored.extend(8u32.to_le_bytes());
        stored.extend(24u32.to_le_bytes());
        stored.extend([0, 0, 0x80, 0x3f, 0, 0, 0, 0x3f]);
        assert_eq!(unblosc(&stored, 8).unwrap(), [0, 0, 0x80, 0x3f, 0, 0, 0, 0x3f]);
        assert!(unblosc(&frame, 1024).is_err(), "the wrong size");
        assert!(unblosc(&frame[..frame.len() - 3], 2048).is_err(), "truncated");
        let mut garbled = frame.clone();
        garbled[30] ^= 0xff;
        let _ = unblosc(&garbled, 2048);
        assert!(unblosc(&[2, 1], 0).is_err());
    }

    #[test]
    fn zlib_round_trips_and_insists_on_the_size() {
        let data = vec![7u8; 1000];
        let z = zip(&data);
        assert_eq!(unzip(&z, 1000).unwrap(), data);
        assert!(unzip(&z, 999).is_err() && unzip(&z, 1001).is_err() && unzip(&z[..5], 1000).is_err());
    }
}
