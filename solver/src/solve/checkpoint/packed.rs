//! Lossless compact f64 arrays for checkpoints: byte planes and deflate, chunk
//! by chunk, so that writing and reading stay streaming with bounded buffers.
//!
//! Why: a checkpoint's bulk is f64 radiance (directional mode: one f64 per SH
//! coefficient, against the solution file's f32). Neighbouring values share
//! their sign, exponent and high mantissa bytes while the low mantissa bytes
//! are close to noise. Splitting a chunk of values into eight byte planes
//! (byte 0 of every value, then byte 1, …: the "shuffle" filter of HDF5 and
//! Blosc) puts the alike bytes side by side, where deflate (Deutsch 1996,
//! RFC 1951) finds them. Nothing is rounded: every value reads back bit for
//! bit, so a resumed solve stays bit-identical. Measured on the glossy scenes
//! in docs/benchmarks.md ("Checkpoints at scale").
//!
//! Layout of a packed section, after its tag and its value count N: ⌈N / C⌉
//! chunks (C = [`CHUNK_VALUES`]; every chunk holds C values but the last), each
//! a u32 byte length and that many bytes of raw deflate (no zlib header: the
//! envelope's CRC-32 covers the bytes) of the chunk's eight planes.

use flate2::{Compress, Compression, Decompress, FlushCompress, FlushDecompress, Status};
use std::io::{self, Write};

/// Values per chunk: 256 KiB of f64. Deflate looks back 32 KiB at most, so
/// larger chunks would compress no better, and the writer's two chunk
/// buffers stay small beside its 1 MiB stream buffer.
pub const CHUNK_VALUES: usize = 1 << 15;

/// Deflate's largest possible expansion ratio: one 258-byte match coded in as
/// little as two bits gives at most 1032 output bytes per input byte (zlib's
/// technical details, "Maximum compression factor"). A section whose count
/// needs more than this from the bytes left cannot be genuine.
pub const MAX_RATIO: u64 = 1032;

/// The most compressed bytes a chunk of `values` values may have: deflate's
/// stored blocks add 5 bytes per 65,535 (RFC 1951, §3.2.4); the rest is margin.
pub fn max_chunk_bytes(values: usize) -> usize {
    let raw = 8 * values;
    raw + raw / 1024 + 1024
}

/// The deflate level: the fastest. The planes of low mantissa bytes do not
/// compress at any level, and the others hardly compress better at higher
/// levels: on the glossy Cornell box's vertex SH (17 MB, byte planes, zlib
/// for the comparison) level 1 gave 0.840 of the raw size in 1.8 s, level 6
/// 0.834 in 2.9 s, level 9 0.833 in 9.5 s, on the shared 2-core machine.
const LEVEL: u32 = 1;

/// Writes packed sections; its buffers (a chunk's planes and its deflated
/// bytes) are reused.
pub struct Packer {
    planes: Vec<u8>,
    out: Vec<u8>,
    compress: Compress,
}

impl Default for Packer {
    fn default() -> Self {
        Packer {
            planes: Vec::new(),
            out: Vec::new(),
            compress: Compress::new(Compression::new(LEVEL), false),
        }
    }
}

impl Packer {
    /// Writes the chunks of `count` values (the section's tag and count are the
    /// caller's); `values` must yield exactly `count`.
    pub fn write(
        &mut self,
        w: &mut impl Write,
        count: usize,
        mut values: impl Iterator<Item = f64>,
    ) -> io::Result<()> {
        let mut left = count;
        while left > 0 {
            let n = left.min(CHUNK_VALUES);
            if !shuffle(&mut values, n, &mut self.planes) {
                return Err(io::Error::other(format!(
                    "a packed section announced {count} values and has fewer"
                )));
            }
            self.chunk(w, n)?;
            left -= n;
        }
        if values.next().is_some() {
            return Err(io::Error::other(format!(
                "a packed section announced {count} values and has more"
            )));
        }
        Ok(())
    }

    /// Compresses and writes the planes of a chunk of `n` values.
    fn chunk(&mut self, w: &mut impl Write, n: usize) -> io::Result<()> {
        self.compress.reset();
        self.out.clear();
        self.out.reserve(max_chunk_bytes(n));
        let mut consumed = 0usize;
        loop {
            let before = self.compress.total_in();
            let status = self
                .compress
                .compress_vec(
                    &self.planes[consumed..],
                    &mut self.out,
                    FlushCompress::Finish,
                )
                .map_err(io::Error::other)?;
            consumed += (self.compress.total_in() - before) as usize;
            match status {
                Status::StreamEnd => break,
                // Out of room: deflate's bound was exceeded (it cannot be, but
                // growing is correct either way).
                Status::Ok | Status::BufError => self.out.reserve(self.out.len().max(1024)),
            }
        }
        if self.out.len() > max_chunk_bytes(n) {
            return Err(io::Error::other(format!(
                "a chunk of {n} values deflated to {} bytes, more than the reader accepts",
                self.out.len()
            )));
        }
        w.write_all(&(self.out.len() as u32).to_le_bytes())?;
        w.write_all(&self.out)
    }
}

/// Takes `n` values into byte planes: byte `b` of value `i` goes to
/// `planes[b · n + i]` (little-endian bytes). False when `values` ends first.
fn shuffle(values: &mut impl Iterator<Item = f64>, n: usize, planes: &mut Vec<u8>) -> bool {
    planes.clear();
    planes.resize(8 * n, 0);
    for i in 0..n {
        let Some(v) = values.next() else {
            return false;
        };
        for (b, byte) in v.to_bits().to_le_bytes().into_iter().enumerate() {
            planes[b * n + i] = byte;
        }
    }
    true
}

/// The inverse of [`shuffle`], appending the values to `out`.
fn unshuffle(planes: &[u8], out: &mut Vec<f64>) {
    let n = planes.len() / 8;
    out.extend((0..n).map(|i| {
        let mut bytes = [0u8; 8];
        for (b, byte) in bytes.iter_mut().enumerate() {
            *byte = planes[b * n + i];
        }
        f64::from_bits(u64::from_le_bytes(bytes))
    }));
}

/// Reads packed chunks; its buffers (about two chunks) are reused.
pub struct Unpacker {
    compressed: Vec<u8>,
    planes: Vec<u8>,
    decompress: Decompress,
}

impl Default for Unpacker {
    fn default() -> Self {
        Unpacker {
            compressed: Vec::new(),
            planes: Vec::new(),
            decompress: Decompress::new(false),
        }
    }
}

impl Unpacker {
    /// The buffer a chunk of `len` compressed bytes is read into.
    pub fn compressed_buffer(&mut self, len: usize) -> &mut [u8] {
        self.compressed.clear();
        self.compressed.resize(len, 0);
        &mut self.compressed
    }

    /// Inflates the chunk in the compressed buffer, which must give exactly
    /// `values` values and use every byte, and appends them to `out`.
    pub fn inflate(&mut self, values: usize, out: &mut Vec<f64>) -> Result<(), String> {
        self.planes.clear();
        self.planes.resize(8 * values, 0);
        self.decompress.reset(false);
        let status = self
            .decompress
            .decompress(&self.compressed, &mut self.planes, FlushDecompress::Finish)
            .map_err(|e| format!("a chunk does not inflate ({e})"))?;
        let (used, made) = (self.decompress.total_in(), self.decompress.total_out());
        if status != Status::StreamEnd || made != 8 * values as u64 {
            return Err(format!(
                "a chunk of {values} values inflates to {} {made} bytes",
                if status == Status::StreamEnd {
                    "exactly"
                } else {
                    "at least"
                }
            ));
        }
        if used != self.compressed.len() as u64 {
            return Err(format!(
                "a chunk ends after {used} of its {} bytes",
                self.compressed.len()
            ));
        }
        unshuffle(&self.planes, out);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn planes_round_trip() {
        let values = [1.0, -0.0, f64::MIN_POSITIVE / 3.0, f64::NAN, 1.0 / 3.0];
        let mut planes = Vec::new();
        assert!(shuffle(
            &mut values.iter().copied(),
            values.len(),
            &mut planes
        ));
        assert!(!shuffle(
            &mut values.iter().copied(),
            values.len() + 1,
            &mut planes
        ));
        shuffle(&mut values.iter().copied(), values.len(), &mut planes);
        // Byte 7 of 1.0 (0x3ff0…) is 0x3f, the first of the last plane.
        assert_eq!(planes[7 * values.len()], 0x3f);
        let mut back = Vec::new();
        unshuffle(&planes, &mut back);
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&back), bits(&values));
    }
}
