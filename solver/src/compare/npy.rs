//! A small reader for NumPy's `.npy` format (NumPy Enhancement Proposal 1,
//! "A simple file format for NumPy arrays"), restricted to what `solver compare`
//! needs: little-endian `float32`, C order, any rank.
//!
//! The input is untrusted: the header is bounded, parsed without recursion, and the
//! declared shape is checked against the bytes actually present before anything is
//! allocated, so a hostile header cannot exhaust memory or cause a panic.

use std::io::Read;

/// The longest header accepted. NumPy pads headers to a multiple of 64 bytes and a
/// rank-3 float array needs well under 128; 64 KiB leaves room for any honest file.
const MAX_HEADER_BYTES: usize = 64 * 1024;

/// The most dimensions accepted (NumPy's own limit is 64).
const MAX_RANK: usize = 64;

const MAGIC: &[u8; 6] = b"\x93NUMPY";

/// A decoded array: its shape (C order, outermost first) and its values.
#[derive(Debug, Clone, PartialEq)]
pub struct NpyArray {
    pub shape: Vec<usize>,
    pub data: Vec<f32>,
}

/// Why a `.npy` stream was refused.
#[derive(Debug, thiserror::Error)]
pub enum NpyError {
    #[error("I/O error: {0}")]
    Io(#[from] std::io::Error),
    #[error("not a .npy file (the magic string \\x93NUMPY is missing)")]
    BadMagic,
    #[error("unsupported .npy format version {major}.{minor} (1.0, 2.0 and 3.0 are read)")]
    Version { major: u8, minor: u8 },
    #[error("header length {0} bytes exceeds the {MAX_HEADER_BYTES}-byte limit")]
    HeaderTooLong(u64),
    #[error("file ends inside the header")]
    TruncatedHeader,
    #[error("header is not text: {0}")]
    HeaderEncoding(String),
    #[error("malformed header dictionary at byte {at}: {what}")]
    Syntax { at: usize, what: String },
    #[error("header lacks the key '{0}'")]
    MissingKey(&'static str),
    #[error("dtype '{0}' is not supported: only little-endian float32 ('<f4') is read")]
    Dtype(String),
    #[error("Fortran-order arrays are not supported: write the array in C order")]
    FortranOrder,
    #[error("shape {shape:?} has more elements than can be addressed")]
    ShapeOverflow { shape: Vec<usize> },
    #[error("shape {shape:?} needs {expected} data bytes but the file holds {actual}")]
    SizeMismatch {
        shape: Vec<usize>,
        expected: u64,
        actual: u64,
    },
}

/// Reads a whole `.npy` stream whose total length is `stream_len` bytes (from file
/// metadata). The length is what lets the shape be checked before allocation.
pub fn read_npy(mut reader: impl Read, stream_len: u64) -> Result<NpyArray, NpyError> {
    let (header, header_end) = read_header(&mut reader, stream_len)?;
    let meta = parse_header(&header)?;
    let count = element_count(&meta.shape)?;
    let expected = count
        .checked_mul(4)
        .ok_or_else(|| NpyError::ShapeOverflow {
            shape: meta.shape.clone(),
        })? as u64;
    let actual = stream_len.saturating_sub(header_end);
    if expected != actual {
        return Err(NpyError::SizeMismatch {
            shape: meta.shape,
            expected,
            actual,
        });
    }
    let mut bytes = vec![0u8; count * 4];
    reader.read_exact(&mut bytes).map_err(|e| match e.kind() {
        // The file shrank between the metadata query and the read.
        std::io::ErrorKind::UnexpectedEof => NpyError::SizeMismatch {
            shape: meta.shape.clone(),
            expected,
            actual: 0,
        },
        _ => NpyError::Io(e),
    })?;
    let data = bytes
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect();
    Ok(NpyArray {
        shape: meta.shape,
        data,
    })
}

/// Writes `data` with `shape` as a version 1.0 `.npy` stream (little-endian
/// float32, C order), byte for byte as `numpy.save` does.
pub fn write_npy(
    mut writer: impl std::io::Write,
    shape: &[usize],
    data: &[f32],
) -> std::io::Result<()> {
    let dims: Vec<String> = shape.iter().map(|d| d.to_string()).collect();
    let shape_text = match dims.len() {
        1 => format!("({},)", dims[0]),
        _ => format!("({})", dims.join(", ")),
    };
    let mut dict = format!("{{'descr': '<f4', 'fortran_order': False, 'shape': {shape_text}, }}");
    // Magic (6) + version (2) + length (2) + dict + newline is padded to 64 bytes.
    let unpadded = 10 + dict.len() + 1;
    dict.push_str(&" ".repeat((64 - unpadded % 64) % 64));
    dict.push('\n');
    writer.write_all(MAGIC)?;
    writer.write_all(&[1, 0])?;
    writer.write_all(&(dict.len() as u16).to_le_bytes())?;
    writer.write_all(dict.as_bytes())?;
    for value in data {
        writer.write_all(&value.to_le_bytes())?;
    }
    Ok(())
}

/// Reads the magic, version and header text; returns the text and the offset of
/// the first data byte.
fn read_header(reader: &mut impl Read, stream_len: u64) -> Result<(String, u64), NpyError> {
    let mut preamble = [0u8; 8];
    read_or_truncated(reader, &mut preamble)?;
    if &preamble[..6] != MAGIC {
        return Err(NpyError::BadMagic);
    }
    let (major, minor) = (preamble[6], preamble[7]);
    let (len_bytes, utf8) = match (major, minor) {
        (1, 0) => (2, false),
        (2, 0) => (4, false),
        (3, 0) => (4, true),
        _ => return Err(NpyError::Version { major, minor }),
    };
    let mut len_buf = [0u8; 4];
    read_or_truncated(reader, &mut len_buf[..len_bytes])?;
    let header_len = u32::from_le_bytes(len_buf) as u64;
    let header_start = 8 + len_bytes as u64;
    if header_len > MAX_HEADER_BYTES as u64 {
        return Err(NpyError::HeaderTooLong(header_len));
    }
    if header_start + header_len > stream_len {
        return Err(NpyError::TruncatedHeader);
    }
    let mut text = vec![0u8; header_len as usize];
    read_or_truncated(reader, &mut text)?;
    let text = if utf8 {
        String::from_utf8(text).map_err(|e| NpyError::HeaderEncoding(e.to_string()))?
    } else if text.is_ascii() {
        String::from_utf8(text).map_err(|e| NpyError::HeaderEncoding(e.to_string()))?
    } else {
        return Err(NpyError::HeaderEncoding(
            "version 1.0/2.0 headers must be ASCII".into(),
        ));
    };
    Ok((text, header_start + header_len))
}

fn read_or_truncated(reader: &mut impl Read, buf: &mut [u8]) -> Result<(), NpyError> {
    reader.read_exact(buf).map_err(|e| match e.kind() {
        std::io::ErrorKind::UnexpectedEof => NpyError::TruncatedHeader,
        _ => NpyError::Io(e),
    })
}

fn element_count(shape: &[usize]) -> Result<usize, NpyError> {
    shape
        .iter()
        .try_fold(1usize, |n, &d| n.checked_mul(d))
        .ok_or_else(|| NpyError::ShapeOverflow {
            shape: shape.to_vec(),
        })
}

/// What the header dictionary declares.
#[derive(Debug, PartialEq)]
struct HeaderMeta {
    shape: Vec<usize>,
}

/// One value of the header dictionary: the only kinds NumPy writes there.
#[derive(Debug)]
enum Value {
    Text(String),
    Bool(bool),
    Tuple(Vec<usize>),
}

/// Parses `{'descr': '<f4', 'fortran_order': False, 'shape': (h, w, 3), }`.
fn parse_header(text: &str) -> Result<HeaderMeta, NpyError> {
    let mut p = Parser {
        s: text.as_bytes(),
        at: 0,
    };
    let mut descr = None;
    let mut fortran = None;
    let mut shape = None;
    p.expect(b'{')?;
    loop {
        p.skip_space();
        if p.eat(b'}') {
            break;
        }
        let key = p.string()?;
        p.skip_space();
        p.expect(b':')?;
        let value = p.value()?;
        match (key.as_str(), value) {
            ("descr", Value::Text(d)) => descr = Some(d),
            ("fortran_order", Value::Bool(f)) => fortran = Some(f),
            ("shape", Value::Tuple(s)) => shape = Some(s),
            (k @ ("descr" | "fortran_order" | "shape"), v) => {
                return Err(p.error(format!("key '{k}' has the wrong kind of value {v:?}")))
            }
            // Unknown keys are tolerated, as NumPy's own reader does not.
            _ => {}
        }
        p.skip_space();
        if !p.eat(b',') {
            p.skip_space();
            p.expect(b'}')?;
            break;
        }
    }
    let descr = descr.ok_or(NpyError::MissingKey("descr"))?;
    if !matches!(descr.as_str(), "<f4" | "float32") {
        return Err(NpyError::Dtype(descr));
    }
    if fortran.ok_or(NpyError::MissingKey("fortran_order"))? {
        return Err(NpyError::FortranOrder);
    }
    let shape = shape.ok_or(NpyError::MissingKey("shape"))?;
    Ok(HeaderMeta { shape })
}

struct Parser<'a> {
    s: &'a [u8],
    at: usize,
}

impl Parser<'_> {
    fn error(&self, what: impl Into<String>) -> NpyError {
        NpyError::Syntax {
            at: self.at,
            what: what.into(),
        }
    }

    fn peek(&self) -> Option<u8> {
        self.s.get(self.at).copied()
    }

    fn skip_space(&mut self) {
        while matches!(self.peek(), Some(b' ' | b'\t' | b'\n' | b'\r')) {
            self.at += 1;
        }
    }

    fn eat(&mut self, c: u8) -> bool {
        if self.peek() == Some(c) {
            self.at += 1;
            true
        } else {
            false
        }
    }

    fn expect(&mut self, c: u8) -> Result<(), NpyError> {
        self.skip_space();
        if self.eat(c) {
            Ok(())
        } else {
            Err(self.error(format!("expected '{}'", c as char)))
        }
    }

    /// A Python string literal in single or double quotes, without escapes.
    fn string(&mut self) -> Result<String, NpyError> {
        let quote = match self.peek() {
            Some(q @ (b'\'' | b'"')) => q,
            _ => return Err(self.error("expected a quoted string")),
        };
        self.at += 1;
        let start = self.at;
        while let Some(c) = self.peek() {
            if c == quote {
                let text = String::from_utf8_lossy(&self.s[start..self.at]).into_owned();
                self.at += 1;
                return Ok(text);
            }
            if c == b'\\' {
                return Err(self.error("escapes in strings are not supported"));
            }
            self.at += 1;
        }
        Err(self.error("unterminated string"))
    }

    fn value(&mut self) -> Result<Value, NpyError> {
        self.skip_space();
        match self.peek() {
            Some(b'\'' | b'"') => self.string().map(Value::Text),
            Some(b'(') => self.tuple().map(Value::Tuple),
            Some(b'T') => self.word("True").map(|_| Value::Bool(true)),
            Some(b'F') => self.word("False").map(|_| Value::Bool(false)),
            _ => Err(self.error("expected a string, a tuple, True or False")),
        }
    }

    fn word(&mut self, word: &str) -> Result<(), NpyError> {
        if self.s[self.at..].starts_with(word.as_bytes()) {
            self.at += word.len();
            Ok(())
        } else {
            Err(self.error(format!("expected {word}")))
        }
    }

    /// `()`, `(n,)` or `(a, b, ...)` of non-negative integers.
    fn tuple(&mut self) -> Result<Vec<usize>, NpyError> {
        self.expect(b'(')?;
        let mut dims = Vec::new();
        loop {
            self.skip_space();
            if self.eat(b')') {
                return Ok(dims);
            }
            if dims.len() == MAX_RANK {
                return Err(self.error(format!("more than {MAX_RANK} dimensions")));
            }
            dims.push(self.integer()?);
            self.skip_space();
            if !self.eat(b',') {
                self.expect(b')')?;
                return Ok(dims);
            }
        }
    }

    fn integer(&mut self) -> Result<usize, NpyError> {
        let start = self.at;
        let mut n: usize = 0;
        while let Some(c @ b'0'..=b'9') = self.peek() {
            n = n
                .checked_mul(10)
                .and_then(|n| n.checked_add((c - b'0') as usize))
                .ok_or_else(|| self.error("dimension does not fit in an integer"))?;
            self.at += 1;
        }
        if self.at == start {
            return Err(self.error("expected a non-negative integer"));
        }
        Ok(n)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn encode(shape: &[usize], data: &[f32]) -> Vec<u8> {
        let mut bytes = Vec::new();
        write_npy(&mut bytes, shape, data).unwrap();
        bytes
    }

    fn decode(bytes: &[u8]) -> Result<NpyArray, NpyError> {
        read_npy(bytes, bytes.len() as u64)
    }

    /// Builds a version 1.0 file with an arbitrary header text and payload.
    fn raw(header: &str, payload: &[u8]) -> Vec<u8> {
        let mut bytes = MAGIC.to_vec();
        bytes.extend_from_slice(&[1, 0]);
        bytes.extend_from_slice(&(header.len() as u16).to_le_bytes());
        bytes.extend_from_slice(header.as_bytes());
        bytes.extend_from_slice(payload);
        bytes
    }

    #[test]
    fn round_trips_and_pads_header_like_numpy() {
        let data: Vec<f32> = (0..2 * 3 * 3).map(|i| i as f32 * 0.5 - 1.0).collect();
        let bytes = encode(&[2, 3, 3], &data);
        // numpy.save pads magic + version + length + header to a multiple of 64.
        let header_len = u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
        assert_eq!((10 + header_len) % 64, 0);
        assert_eq!(bytes[10 + header_len - 1], b'\n');
        let array = decode(&bytes).unwrap();
        assert_eq!(array.shape, vec![2, 3, 3]);
        assert_eq!(array.data, data);
    }

    #[test]
    fn reads_numpy_written_header_verbatim() {
        // The header numpy 1.26 writes for np.zeros((2, 2, 3), np.float32).
        let header =
            "{'descr': '<f4', 'fortran_order': False, 'shape': (2, 2, 3), }                                                          \n";
        let payload = vec![0u8; 2 * 2 * 3 * 4];
        let array = decode(&raw(header, &payload)).unwrap();
        assert_eq!(array.shape, vec![2, 2, 3]);
        assert_eq!(array.data.len(), 12);
    }

    #[test]
    fn truncated_files_are_refused() {
        let bytes = encode(&[4, 4, 3], &[1.0; 48]);
        for cut in [0, 3, 7, 9, 30, bytes.len() - 1] {
            let result = decode(&bytes[..cut]);
            assert!(
                matches!(
                    result,
                    Err(NpyError::TruncatedHeader
                        | NpyError::SizeMismatch { .. }
                        | NpyError::BadMagic)
                ),
                "cut at {cut}: {result:?}"
            );
        }
    }

    #[test]
    fn huge_shape_is_refused_before_allocation() {
        // 2^20 × 2^20 × 3 floats would be 12 TiB: the size check must refuse it
        // against the 0 payload bytes actually present.
        let header = "{'descr': '<f4', 'fortran_order': False, 'shape': (1048576, 1048576, 3), }\n";
        let result = decode(&raw(header, &[]));
        assert!(
            matches!(result, Err(NpyError::SizeMismatch { expected, .. }) if expected == 12 << 40)
        );
        // A product that overflows usize is refused as such.
        let header =
            "{'descr': '<f4', 'fortran_order': False, 'shape': (18446744073709551615, 2, 3), }\n";
        assert!(matches!(
            decode(&raw(header, &[])),
            Err(NpyError::ShapeOverflow { .. })
        ));
        // A single dimension that does not fit in usize is a syntax error.
        let header =
            "{'descr': '<f4', 'fortran_order': False, 'shape': (99999999999999999999999, 3), }\n";
        assert!(matches!(
            decode(&raw(header, &[])),
            Err(NpyError::Syntax { .. })
        ));
    }

    #[test]
    fn declared_header_length_beyond_the_file_is_refused() {
        let mut bytes = MAGIC.to_vec();
        bytes.extend_from_slice(&[2, 0]);
        bytes.extend_from_slice(&u32::MAX.to_le_bytes());
        assert!(matches!(decode(&bytes), Err(NpyError::HeaderTooLong(_))));
        let mut bytes = MAGIC.to_vec();
        bytes.extend_from_slice(&[1, 0, 0xff, 0x0f]);
        assert!(matches!(decode(&bytes), Err(NpyError::TruncatedHeader)));
    }

    #[test]
    fn wrong_dtype_fortran_order_and_bad_syntax_are_refused() {
        let payload = [0u8; 8 * 3];
        for (descr, ok) in [
            ("<f8", false),
            (">f4", false),
            ("<i4", false),
            ("<f4", true),
        ] {
            let header =
                format!("{{'descr': '{descr}', 'fortran_order': False, 'shape': (2, 3), }}\n");
            let result = decode(&raw(&header, &payload[..2 * 3 * 4]));
            assert_eq!(result.is_ok(), ok, "{descr}: {result:?}");
            if !ok {
                assert!(matches!(result, Err(NpyError::Dtype(d)) if d == descr));
            }
        }
        let header = "{'descr': '<f4', 'fortran_order': True, 'shape': (2, 3), }\n";
        assert!(matches!(
            decode(&raw(header, &payload[..24])),
            Err(NpyError::FortranOrder)
        ));
        for header in [
            "{'descr': '<f4', 'fortran_order': False}\n",
            "{'descr': '<f4', 'fortran_order': False, 'shape': (2, -3), }\n",
            "{'descr': '<f4', 'fortran_order': False, 'shape': [2, 3], }\n",
            "{'descr': '<f4, 'fortran_order': False, 'shape': (2, 3), }\n",
            "{'descr': 3, 'fortran_order': False, 'shape': (2, 3), }\n",
            "not a dict",
            "",
        ] {
            let result = decode(&raw(header, &payload[..24]));
            assert!(
                matches!(
                    result,
                    Err(NpyError::Syntax { .. } | NpyError::MissingKey(_))
                ),
                "{header:?}: {result:?}"
            );
        }
        assert!(matches!(
            decode(b"PK\x03\x04 not npy at all"),
            Err(NpyError::BadMagic)
        ));
        let mut bytes = encode(&[1], &[1.0]);
        bytes[6] = 9;
        assert!(matches!(
            decode(&bytes),
            Err(NpyError::Version { major: 9, .. })
        ));
    }

    #[test]
    fn deep_nesting_and_long_tuples_do_not_recurse_or_grow() {
        let header = format!(
            "{{'descr': '<f4', 'fortran_order': False, 'shape': ({}), }}\n",
            "1, ".repeat(100)
        );
        assert!(matches!(
            decode(&raw(&header, &[0; 4])),
            Err(NpyError::Syntax { .. })
        ));
        let header = format!("{}\n", "(".repeat(10_000));
        assert!(decode(&raw(&header, &[])).is_err());
    }
}
