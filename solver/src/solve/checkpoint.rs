//! The solver's state between shots, for checkpoint files: written streaming,
//! read back with every size checked before anything is allocated.
//!
//! Between shots the state is: the mesh (rebuilt exactly by replaying its split
//! log on a fresh mesh of the same scene), each vertex's radiance, the list of
//! recorded (emitter) shots, each patch's unshot radiance, and the counters.
//! Vertex ΔL is always zero between shots (it is gathered into the patches), and
//! random samples are drawn from stateless streams (seed, shot, vertex), so
//! nothing else is needed for a resumed solve to end bit-identical to an
//! uninterrupted one.
//!
//! What is not stored because it is recomputed exactly: directional mode's
//! per-coefficient part of the radiance from recorded shots (`direct`, as large
//! as the radiance itself; it made a checkpoint four times the solution file).
//! Each recorded shot knows how many vertices it was shot to
//! ([`super::shoot::RecordedShot::receivers`]); a resume shoots it again to those
//! vertices and replays it to the later ones, in the order the solve did, which
//! gives the same bits (see `directional/state.rs`). That costs one pass of the
//! recorded shots over the mesh, a few shots' time. The diffuse mode's `direct`
//! (three f64 per vertex) is stored: it is small beside the solution's vertex.
//! Directional mode's diffuse proxies (per vertex c₀₀ Y₀₀, per patch the
//! hemisphere-equivalent unshot) are recomputed from the coefficients, by the
//! expressions every step ends with, so they are not stored either.
//!
//! Format: a sequence of sections, each a 4-byte tag, a u64 element count and the
//! elements, little-endian; every f64 as its IEEE bits, so values round-trip bit
//! for bit. The bulk arrays of f64 are *packed* (byte planes and deflate, chunk
//! by chunk: [`packed`]), lossless and still streaming; their count is of f64
//! values. In order: `HEAD` (one record: fingerprint, shots, rays, seconds,
//! mode), `SPLT` (u32 per split), `RECS` (40 bytes per recorded shot: index u64,
//! patch u32, receivers u32, unshot 3 × f64), `RADI` (packed, 3 per vertex),
//! `UNSH` (packed, 3 per patch), `DIRC` (packed, 3 per vertex; these three are
//! empty in directional mode), `RECG` (16 bytes per recorded group of
//! emitters' first shots: index u64, receivers u32, member count u32) and
//! `RECM` (28 bytes per member, the groups' in order: patch u32, unshot
//! 3 × f64); in
//! directional mode then `SHOR` (u32 order per surface), `BRDF` (one u32),
//! `SHRA` (packed, one per radiance coefficient, its bits XOR the kept bits
//! of the coefficient's recorded-shot part), `SHUN` (packed, one per patch
//! coefficient; a patch's bits XOR the kept bits of a prediction where `SHUM`
//! flags it), `SHUM` (u32 per patch: 1 where masked), `SHRL` (u32 coefficient count
//! per recorded shot), `SHRU` (their f64s) and `SHSS` (packed, one per patch
//! coefficient: the SH each patch has shot in unrecorded shots, which a
//! split's new glossy vertex gathers, `directional/near_gather.rs`). The masks turn bits that agree
//! into zero bytes for deflate; a resume recomputes what masked them, exactly,
//! and unmasks (`directional/state.rs`). Directional mode keeps its radiance
//! and unshot coefficients at 40 mantissa bits ([`precision`]), so their 12
//! low bits are zero, and the masks leave them so.
//! Last come the set-up's results (`CUTI`, `CUTV`, `HIDN`, [`SetupResult`]):
//! the contact cuts and the hidden flags, which the set-up finds by searching
//! the scene and casting probe rays, so that a resume rebuilds the mesh from
//! them and probes no vertex again. The first checkpoint is written as the
//! set-up ends, at shot 0.
//! The file envelope around it (magic, settings, checksum) is the command line's
//! (`cli/solve/checkpoint.rs`).

use super::shoot::RecordedGroup;
use super::{SolveError, Solver};
use crate::scene::Scene;
use crate::settings::SolverSettings;
use glam::DVec3;
use std::io::{self, Read, Write};

mod packed;
pub(super) use packed::CHUNK_VALUES;
pub(super) mod precision;

/// Bump when the meaning of the fields changes (3: the f64 arrays packed;
/// 4: directional masks use only the kept bits, [`precision`]; 5: `SHSS`;
/// 6: `RECG` and `RECM`, the recorded groups; 7: the set-up's `CUTI`, `CUTV`
/// and `HIDN`).
pub const CHECKPOINT_VERSION: u32 = 7;

/// Everything [`Solver::resume`] needs, as read back from a checkpoint. See the
/// module documentation. (Writing streams from the solver itself:
/// [`Solver::write_checkpoint`].)
#[derive(Clone, Debug, PartialEq)]
pub struct Checkpoint {
    pub version: u32,
    /// FNV-1a of the meshed scene (surfaces, patch counts, materials): a
    /// checkpoint of another scene is refused.
    pub fingerprint: u64,
    pub shots: u64,
    pub rays: u64,
    pub seconds: f64,
    /// The power the lights put into the patches (`lights.rs`); 0 without
    /// lights.
    pub lights_power: f64,
    /// The elements split so far, in order.
    pub split_log: Vec<u32>,
    /// Per vertex: radiance (RGB).
    pub radiance: Vec<DVec3>,
    /// Per patch: unshot radiance (RGB).
    pub patch_unshot: Vec<DVec3>,
    /// Per vertex: the part of the radiance from recorded shots; empty when the
    /// mode does not keep it (directional).
    pub direct: Vec<DVec3>,
    /// The recorded (emitter) shots, in order.
    pub recorded: Vec<super::shoot::RecordedShot>,
    /// The recorded groups of emitters' first shots, in order.
    pub recorded_groups: Vec<RecordedGroup>,
    /// Directional mode's SH coefficients; absent for a diffuse solve. Its
    /// radiance and unshot coefficients are masked (see `write_checkpoint`):
    /// [`Solver::resume`] unmasks them.
    pub directional: Option<super::DirectionalCheckpoint>,
    /// Directional mode: per patch, 1 where its unshot SH is masked.
    pub unshot_masked: Vec<u32>,
    /// The set-up's searches, so that a resume does not repeat them: the
    /// receivers cut along contact lines (polygon, parts), and per vertex
    /// whether it is hidden (`hidden.rs`).
    pub setup: SetupResult,
}

impl SetupResult {
    /// Per polygon of `scene`, its part of `cuts` or `None`; a cut naming no
    /// polygon, or a part that is not a finite polygon, is refused.
    pub(super) fn parts_for(
        polygons_hash: u64,
        cuts: Vec<(u32, Vec<crate::mesh::contact::Part>)>,
        scene: &Scene,
    ) -> Result<Vec<Option<Vec<crate::mesh::contact::Part>>>, SolveError> {
        let mut parts = vec![None; scene.polygons.len()];
        if polygons_hash != self::polygons_hash(scene) {
            return Err(SolveError::CheckpointMismatch(
                "its contact cuts were made on other polygons (another scene)".into(),
            ));
        }
        for (polygon, cut) in cuts {
            let sound = cut.iter().all(|p| {
                p.vertices.len() >= 3 && p.vertices.iter().chain(&p.apexes).all(|v| v.is_finite())
            });
            match parts.get_mut(polygon as usize) {
                Some(slot @ None) if sound => *slot = Some(cut),
                _ => {
                    return Err(SolveError::CheckpointMismatch(format!(
                        "its contact cuts name polygon {polygon} twice, beyond the scene's {} \
                         or with a degenerate part",
                        scene.polygons.len()
                    )))
                }
            }
        }
        Ok(parts)
    }
}

/// FNV-1a over every polygon's vertex count and coordinates' bits.
pub fn polygons_hash(scene: &Scene) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let mut eat = |x: u64| {
        for b in x.to_le_bytes() {
            h ^= b as u64;
            h = h.wrapping_mul(0x0000_0100_0000_01b3);
        }
    };
    for p in &scene.polygons {
        eat(p.vertices.len() as u64);
        for v in &p.vertices {
            v.to_array().iter().for_each(|c| eat(c.to_bits()));
        }
    }
    h
}

/// What the set-up found by searching the scene: stored in every
/// checkpoint, from the first (written as the set-up ends), so that
/// `--resume` rebuilds the mesh from it instead of searching again.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SetupResult {
    /// FNV-1a of the scene's polygons' vertices ([`polygons_hash`]): the
    /// stored parts stand for those polygons only.
    pub polygons_hash: u64,
    /// The cut polygons (index into the scene's polygons) and their parts.
    pub cuts: Vec<(u32, Vec<crate::mesh::contact::Part>)>,
    /// Per mesh vertex, hidden or not.
    pub hidden: Vec<bool>,
}

/// A checkpoint's solver state cannot be read: `field` names the section.
#[derive(Debug, thiserror::Error)]
pub enum StateError {
    #[error("section {field}: {detail}")]
    Bad { field: &'static str, detail: String },
    #[error("section {field}: {source}")]
    Io {
        field: &'static str,
        #[source]
        source: io::Error,
    },
}

/// Writes sections of little-endian elements.
struct SectionWriter<'w, W: Write> {
    w: &'w mut W,
    packer: packed::Packer,
}

impl<'w, W: Write> SectionWriter<'w, W> {
    fn new(w: &'w mut W) -> Self {
        SectionWriter {
            w,
            packer: packed::Packer::default(),
        }
    }
    fn start(&mut self, tag: &[u8; 4], count: usize) -> io::Result<()> {
        self.w.write_all(tag)?;
        self.w.write_all(&(count as u64).to_le_bytes())
    }
    fn u32(&mut self, v: u32) -> io::Result<()> {
        self.w.write_all(&v.to_le_bytes())
    }
    fn u64(&mut self, v: u64) -> io::Result<()> {
        self.w.write_all(&v.to_le_bytes())
    }
    fn f64(&mut self, v: f64) -> io::Result<()> {
        self.u64(v.to_bits())
    }
    fn u32s(&mut self, tag: &[u8; 4], values: &[u32]) -> io::Result<()> {
        self.start(tag, values.len())?;
        values.iter().try_for_each(|&v| self.u32(v))
    }
    /// A packed section (see [`packed`]) of `count` values.
    fn packed(
        &mut self,
        tag: &[u8; 4],
        count: usize,
        values: impl Iterator<Item = f64>,
    ) -> io::Result<()> {
        self.start(tag, count)?;
        self.packer.write(self.w, count, values)
    }
    #[cfg(test)]
    fn packed_f64s(&mut self, tag: &[u8; 4], values: &[f64]) -> io::Result<()> {
        self.packed(tag, values.len(), values.iter().copied())
    }
    /// Packed as 3 n values, RGB interleaved.
    fn packed_dvec3s(&mut self, tag: &[u8; 4], values: &[DVec3]) -> io::Result<()> {
        self.packed(
            tag,
            3 * values.len(),
            values.iter().flat_map(|v| v.to_array()),
        )
    }
}

/// Reads sections, never allocating more than the bytes still unread can fill
/// (packed sections: can inflate to, see [`packed::MAX_RATIO`]).
struct SectionReader<'r, R: Read> {
    reader: &'r mut R,
    /// Bytes of the state not read yet.
    remaining: u64,
    unpacker: packed::Unpacker,
}

impl<R: Read> SectionReader<'_, R> {
    fn bytes<const N: usize>(&mut self, field: &'static str) -> Result<[u8; N], StateError> {
        if self.remaining < N as u64 {
            return Err(StateError::Bad {
                field,
                detail: "the state ends early (truncated)".into(),
            });
        }
        let mut b = [0u8; N];
        self.reader
            .read_exact(&mut b)
            .map_err(|source| StateError::Io { field, source })?;
        self.remaining -= N as u64;
        Ok(b)
    }
    fn u32(&mut self, field: &'static str) -> Result<u32, StateError> {
        Ok(u32::from_le_bytes(self.bytes(field)?))
    }
    fn u64(&mut self, field: &'static str) -> Result<u64, StateError> {
        Ok(u64::from_le_bytes(self.bytes(field)?))
    }
    fn f64(&mut self, field: &'static str) -> Result<f64, StateError> {
        Ok(f64::from_bits(self.u64(field)?))
    }
    /// Fills the unpacker's buffer with the next `len` bytes.
    fn chunk_bytes(&mut self, field: &'static str, len: usize) -> Result<(), StateError> {
        if self.remaining < len as u64 {
            return Err(StateError::Bad {
                field,
                detail: format!(
                    "a chunk of {len} bytes, only {} bytes remain (truncated or corrupted)",
                    self.remaining
                ),
            });
        }
        self.reader
            .read_exact(self.unpacker.compressed_buffer(len))
            .map_err(|source| StateError::Io { field, source })?;
        self.remaining -= len as u64;
        Ok(())
    }

    /// Reads the tag and count of the next section, which must be `field`, and
    /// checks that `count` elements of `width` bytes fit in what is left.
    fn start(&mut self, field: &'static str, width: u64) -> Result<usize, StateError> {
        let tag = self.bytes::<4>(field)?;
        if tag != *field.as_bytes() {
            return Err(StateError::Bad {
                field,
                detail: format!(
                    "expected this section, found tag {:?}",
                    String::from_utf8_lossy(&tag)
                ),
            });
        }
        let count = self.u64(field)?;
        match count.checked_mul(width) {
            Some(bytes) if bytes <= self.remaining => Ok(count as usize),
            _ => Err(StateError::Bad {
                field,
                detail: format!(
                    "announces {count} elements of {width} bytes, only {} bytes remain \
                     (truncated or corrupted)",
                    self.remaining
                ),
            }),
        }
    }
    /// A whole section of elements read by `element`; the vector's capacity is
    /// the checked count.
    fn section<T>(
        &mut self,
        field: &'static str,
        width: u64,
        mut element: impl FnMut(&mut Self) -> Result<T, StateError>,
    ) -> Result<Vec<T>, StateError> {
        let count = self.start(field, width)?;
        let mut out = Vec::with_capacity(count);
        for _ in 0..count {
            out.push(element(self)?);
        }
        Ok(out)
    }
    fn u32s(&mut self, field: &'static str) -> Result<Vec<u32>, StateError> {
        self.section(field, 4, |r| r.u32(field))
    }
    fn f64s(&mut self, field: &'static str) -> Result<Vec<f64>, StateError> {
        self.section(field, 8, |r| r.f64(field))
    }

    /// A packed section (see [`packed`]). Its count is checked against what
    /// the bytes left could inflate to at deflate's largest ratio, and memory
    /// grows only as chunks really inflate (one chunk's buffers, then the
    /// values), so a lying count is refused before anything is allocated.
    fn packed(&mut self, field: &'static str) -> Result<Vec<f64>, StateError> {
        let tag = self.bytes::<4>(field)?;
        if tag != *field.as_bytes() {
            return Err(StateError::Bad {
                field,
                detail: format!(
                    "expected this section, found tag {:?}",
                    String::from_utf8_lossy(&tag)
                ),
            });
        }
        let count = self.u64(field)?;
        let possible = self.remaining.saturating_mul(packed::MAX_RATIO) / 8;
        if count > possible {
            return Err(StateError::Bad {
                field,
                detail: format!(
                    "announces {count} values, only {} bytes remain (at most {possible} \
                     values; truncated or corrupted)",
                    self.remaining
                ),
            });
        }
        let mut out = Vec::new();
        let mut left = count as usize;
        while left > 0 {
            let n = left.min(packed::CHUNK_VALUES);
            let len = self.u32(field)? as usize;
            if len > packed::max_chunk_bytes(n) {
                return Err(StateError::Bad {
                    field,
                    detail: format!("a chunk of {n} values announces {len} bytes"),
                });
            }
            self.chunk_bytes(field, len)?;
            out.reserve(n);
            self.unpacker
                .inflate(n, &mut out)
                .map_err(|detail| StateError::Bad { field, detail })?;
            left -= n;
        }
        Ok(out)
    }
    /// A packed section of 3 n values, as n RGB triples.
    fn packed_dvec3s(&mut self, field: &'static str) -> Result<Vec<DVec3>, StateError> {
        let values = self.packed(field)?;
        if values.len() % 3 != 0 {
            return Err(StateError::Bad {
                field,
                detail: format!("{} values, not RGB triples", values.len()),
            });
        }
        Ok(values.chunks_exact(3).map(DVec3::from_slice).collect())
    }
}

const MODE_DIFFUSE: u32 = 0;
const MODE_DIRECTIONAL: u32 = 1;

impl Checkpoint {
    /// Reads the state of [`Solver::write_checkpoint`] from `reader`, of which
    /// exactly `length` bytes belong to it. Sizes are checked against the bytes
    /// left before any allocation, so a truncated or damaged state is an error
    /// naming its section, never a huge allocation.
    pub fn read_from(reader: &mut impl Read, length: u64) -> Result<Checkpoint, StateError> {
        let mut r = SectionReader {
            reader,
            remaining: length,
            unpacker: packed::Unpacker::default(),
        };
        r.start("HEAD", 48).and_then(|n| match n {
            1 => Ok(()),
            _ => Err(StateError::Bad {
                field: "HEAD",
                detail: format!("{n} records, expected 1"),
            }),
        })?;
        let version = r.u32("HEAD")?;
        let mode = r.u32("HEAD")?;
        let fingerprint = r.u64("HEAD")?;
        let shots = r.u64("HEAD")?;
        let rays = r.u64("HEAD")?;
        let seconds = r.f64("HEAD")?;
        let lights_power = r.f64("HEAD")?;
        if version != CHECKPOINT_VERSION {
            return Err(StateError::Bad {
                field: "HEAD",
                detail: format!(
                    "state version {version}, this solver reads version {CHECKPOINT_VERSION}"
                ),
            });
        }
        let split_log = r.u32s("SPLT")?;
        let recorded = r.section("RECS", 40, |r| {
            Ok(super::shoot::RecordedShot {
                index: r.u64("RECS")?,
                patch: r.u32("RECS")?,
                receivers: r.u32("RECS")?,
                unshot: [r.u64("RECS")?, r.u64("RECS")?, r.u64("RECS")?],
            })
        })?;
        let radiance = r.packed_dvec3s("RADI")?;
        let patch_unshot = r.packed_dvec3s("UNSH")?;
        let direct = r.packed_dvec3s("DIRC")?;
        let recorded_groups = read_groups(&mut r)?;
        let (directional, unshot_masked) = match mode {
            MODE_DIFFUSE => (None, Vec::new()),
            MODE_DIRECTIONAL => {
                let (d, masked) = read_directional(&mut r)?;
                (Some(d), masked)
            }
            other => {
                return Err(StateError::Bad {
                    field: "HEAD",
                    detail: format!("unknown mode {other}"),
                })
            }
        };
        let setup = read_setup(&mut r)?;
        if r.remaining != 0 {
            return Err(StateError::Bad {
                field: "HIDN",
                detail: format!("{} bytes follow the last section", r.remaining),
            });
        }
        Ok(Checkpoint {
            version,
            fingerprint,
            shots,
            rays,
            seconds,
            lights_power,
            split_log,
            radiance,
            patch_unshot,
            direct,
            recorded,
            recorded_groups,
            directional,
            unshot_masked,
            setup,
        })
    }
}

/// The set-up's sections: `CUTI` (the polygons' hash, low word first; per
/// cut polygon: its index and part count;
/// per part: covered 0/1, vertex count, apex count), `CUTV` (packed: every
/// part's vertices then apexes, xyz) and `HIDN` (the vertex count, then the
/// hidden flags 32 a word, least significant bit first).
fn read_setup<R: Read>(r: &mut SectionReader<'_, R>) -> Result<SetupResult, StateError> {
    let index = r.u32s("CUTI")?;
    let values = r.packed("CUTV")?;
    let bad = |detail: String| StateError::Bad {
        field: "CUTI",
        detail,
    };
    let mut words = index.iter().copied();
    let (lo, hi) = (words.next(), words.next());
    let polygons_hash = match (lo, hi) {
        (Some(lo), Some(hi)) => lo as u64 | (hi as u64) << 32,
        _ => return Err(bad("no polygons' hash".into())),
    };
    let mut points = values.chunks_exact(3).map(DVec3::from_slice);
    let mut take = |n: u32| -> Result<Vec<DVec3>, StateError> {
        (0..n)
            .map(|_| {
                points
                    .next()
                    .ok_or_else(|| bad("more points than CUTV holds".into()))
            })
            .collect()
    };
    let mut cuts = Vec::new();
    while let Some(polygon) = words.next() {
        let mut next = || {
            words
                .next()
                .ok_or_else(|| bad("a part is cut short".into()))
        };
        let count = next()?;
        let mut parts = Vec::new();
        for _ in 0..count {
            let (covered, vertices, apexes) = (next()?, next()?, next()?);
            parts.push((covered, vertices, apexes));
        }
        let parts = parts
            .into_iter()
            .map(|(covered, vertices, apexes)| {
                Ok(crate::mesh::contact::Part {
                    vertices: take(vertices)?,
                    covered: covered != 0,
                    apexes: take(apexes)?,
                })
            })
            .collect::<Result<Vec<_>, StateError>>()?;
        cuts.push((polygon, parts));
    }
    if points.next().is_some() {
        return Err(bad("CUTV holds more points than the parts".into()));
    }
    let flags = r.u32s("HIDN")?;
    let (count, bits) = flags
        .split_first()
        .map_or((0, &[][..]), |(c, b)| (*c as usize, b));
    if bits.len() != count.div_ceil(32) {
        return Err(StateError::Bad {
            field: "HIDN",
            detail: format!("{count} flags in {} words", bits.len()),
        });
    }
    let hidden = (0..count)
        .map(|v| bits[v / 32] >> (v % 32) & 1 == 1)
        .collect();
    Ok(SetupResult {
        polygons_hash,
        cuts,
        hidden,
    })
}

/// The `RECG` and `RECM` sections: the recorded groups and their members.
fn read_groups<R: Read>(r: &mut SectionReader<'_, R>) -> Result<Vec<RecordedGroup>, StateError> {
    let heads = r.section("RECG", 16, |r| {
        Ok((r.u64("RECG")?, r.u32("RECG")?, r.u32("RECG")?))
    })?;
    let members = r.section("RECM", 28, |r| {
        Ok((
            r.u32("RECM")?,
            [r.u64("RECM")?, r.u64("RECM")?, r.u64("RECM")?],
        ))
    })?;
    let total: u64 = heads.iter().map(|h| h.2 as u64).sum();
    if total != members.len() as u64 {
        return Err(StateError::Bad {
            field: "RECM",
            detail: format!("{} members, the groups of RECG name {total}", members.len()),
        });
    }
    let mut rest = members.as_slice();
    Ok(heads
        .into_iter()
        .map(|(index, receivers, count)| {
            let (own, after) = rest.split_at(count as usize);
            rest = after;
            RecordedGroup {
                index,
                receivers,
                members: own.to_vec(),
            }
        })
        .collect())
}

/// Writes the `RECG` and `RECM` sections of `groups`.
fn write_groups<W: Write>(
    s: &mut SectionWriter<'_, W>,
    groups: &[RecordedGroup],
) -> io::Result<()> {
    s.start(b"RECG", groups.len())?;
    for g in groups {
        s.u64(g.index)?;
        s.u32(g.receivers)?;
        s.u32(g.members.len() as u32)?;
    }
    s.start(b"RECM", groups.iter().map(|g| g.members.len()).sum())?;
    for (patch, unshot) in groups.iter().flat_map(|g| &g.members) {
        s.u32(*patch)?;
        unshot.iter().try_for_each(|&b| s.u64(b))?;
    }
    Ok(())
}

/// The directional sections, and the per-patch flags of masked unshot SH.
fn read_directional<R: Read>(
    r: &mut SectionReader<'_, R>,
) -> Result<(super::DirectionalCheckpoint, Vec<u32>), StateError> {
    let surface_order = r.u32s("SHOR")?;
    let brdf = r.u32s("BRDF")?;
    // The lobe normalization: 0, the thesis's, is the only one (1 was a
    // reciprocal variant, since removed).
    if brdf.as_slice() != [0] {
        return Err(StateError::Bad {
            field: "BRDF",
            detail: format!(
                "unknown lobe normalization {brdf:?} (0, the thesis's, is the only one)"
            ),
        });
    }
    let radiance = r.packed("SHRA")?.into_iter().map(f64::to_bits).collect();
    let patch_unshot = r.packed("SHUN")?.into_iter().map(f64::to_bits).collect();
    let unshot_masked = r.u32s("SHUM")?;
    let lengths = r.u32s("SHRL")?;
    let flat = r.f64s("SHRU")?;
    let shot_sum = r.packed("SHSS")?.into_iter().map(f64::to_bits).collect();
    let total: u64 = lengths.iter().map(|&n| n as u64).sum();
    if total != flat.len() as u64 {
        return Err(StateError::Bad {
            field: "SHRU",
            detail: format!(
                "{} coefficients, the lengths in SHRL add up to {total}",
                flat.len()
            ),
        });
    }
    let mut at = 0usize;
    let recorded_unshot = lengths
        .iter()
        .map(|&n| {
            let part = flat[at..at + n as usize]
                .iter()
                .map(|x| x.to_bits())
                .collect();
            at += n as usize;
            part
        })
        .collect();
    Ok((
        super::DirectionalCheckpoint {
            surface_order,
            radiance,
            patch_unshot,
            direct: Vec::new(),
            recorded_unshot,
            shot_sum,
        },
        unshot_masked,
    ))
}

/// Writes [`read_setup`]'s sections.
fn write_setup<W: Write>(
    s: &mut SectionWriter<'_, W>,
    polygons_hash: u64,
    cuts: &[(u32, Vec<crate::mesh::contact::Part>)],
    hidden: &[bool],
) -> io::Result<()> {
    let mut index = vec![polygons_hash as u32, (polygons_hash >> 32) as u32];
    let mut values = Vec::new();
    for (polygon, parts) in cuts {
        index.extend([*polygon, parts.len() as u32]);
        for part in parts {
            index.extend([
                part.covered as u32,
                part.vertices.len() as u32,
                part.apexes.len() as u32,
            ]);
        }
        for part in parts {
            values.extend(
                part.vertices
                    .iter()
                    .chain(&part.apexes)
                    .flat_map(|p| p.to_array()),
            );
        }
    }
    s.u32s(b"CUTI", &index)?;
    s.packed(b"CUTV", values.len(), values.into_iter())?;
    let mut flags = vec![hidden.len() as u32];
    flags.extend(hidden.chunks(32).map(|chunk| {
        chunk
            .iter()
            .enumerate()
            .fold(0u32, |word, (k, &h)| word | (h as u32) << k)
    }));
    s.u32s(b"HIDN", &flags)
}

/// Refuses a checkpoint written in the other mode. Checked before the
/// fingerprint: diffuse mode folds glossy materials' Ks into the
/// reflectances the fingerprint hashes, and the mode is the more useful
/// thing to name.
fn check_mode(checkpoint: &Checkpoint, settings: &SolverSettings) -> Result<(), SolveError> {
    let name = |directional: bool| {
        if directional {
            "directional"
        } else {
            "diffuse"
        }
    };
    let written = checkpoint.directional.is_some();
    if written == (settings.mode == solution::format::SolveMode::Directional) {
        return Ok(());
    }
    Err(SolveError::CheckpointMismatch(format!(
        "it was written by a {} solve, this one is {}",
        name(written),
        name(!written)
    )))
}

impl Solver {
    /// Writes the state between shots to `w`, section by section straight from
    /// the solver's own arrays (no copy of the state is made; buffer `w`).
    pub fn write_checkpoint(&self, w: &mut impl Write) -> io::Result<()> {
        let mut s = SectionWriter::new(w);
        s.start(b"HEAD", 1)?;
        s.u32(CHECKPOINT_VERSION)?;
        s.u32(if self.directional.is_some() {
            MODE_DIRECTIONAL
        } else {
            MODE_DIFFUSE
        })?;
        s.u64(self.fingerprint())?;
        s.u64(self.stats.shots)?;
        s.u64(self.stats.rays)?;
        s.f64(self.stats.seconds)?;
        // Once reserved (0); now the lights' power, which a solve without
        // lights leaves 0.
        s.f64(self.lights.power)?;
        s.u32s(b"SPLT", &self.mesh.split_log)?;
        s.start(b"RECS", self.record.shots.len())?;
        for r in &self.record.shots {
            s.u64(r.index)?;
            s.u32(r.patch)?;
            s.u32(r.receivers)?;
            r.unshot.iter().try_for_each(|&b| s.u64(b))?;
        }
        // Directional mode stores none of the diffuse arrays: the radiance and
        // unshot proxies are recomputed from the coefficients on resume (as every
        // step ends by recomputing them), and its recorded-shot part is per
        // coefficient, recomputed too.
        let diffuse = self.directional.is_none();
        let keeps_direct = diffuse && self.field.direct.len() == self.field.radiance.len();
        s.packed_dvec3s(b"RADI", if diffuse { &self.field.radiance } else { &[] })?;
        s.packed_dvec3s(b"UNSH", if diffuse { &self.patches.unshot } else { &[] })?;
        s.packed_dvec3s(
            b"DIRC",
            if keeps_direct {
                &self.field.direct
            } else {
                &[]
            },
        )?;
        write_groups(&mut s, &self.record.groups)?;
        if let Some(d) = self.directional.as_deref() {
            let sections = d.checkpoint_sections();
            s.u32s(b"SHOR", sections.surface_order)?;
            // The lobe normalization's code, kept in the format: 0, the thesis's.
            s.u32s(b"BRDF", &[0])?;
            // Masked: each coefficient's bits XOR those of its recorded-shot
            // part (recomputed exactly on resume before unmasking). Where the
            // light's direct reflection dominates, as in most high-order
            // coefficients, the two share sign, exponent and leading mantissa
            // bits, which the mask turns into zero bytes for deflate.
            s.packed(
                b"SHRA",
                sections.radiance.len(),
                sections
                    .radiance
                    .iter()
                    .zip(sections.direct)
                    .map(|(r, m)| f64::from_bits(r.to_bits() ^ precision::kept_bits(*m))),
            )?;
            // Masked where a prediction from the radiance is close (patches
            // that have not shot), with one flag per patch after it.
            let mut masked = Vec::with_capacity(self.mesh.patches.len());
            let (mut prediction, mut buffer) = (Vec::new(), Vec::new());
            let values = (0..self.mesh.patches.len()).flat_map(|p| {
                masked.push(self.masked_unshot(p, &mut prediction, &mut buffer) as u32);
                buffer.clone()
            });
            s.packed(b"SHUN", sections.patch_unshot.len(), values)?;
            s.u32s(b"SHUM", &masked)?;
            let lengths: Vec<u32> = sections
                .recorded_unshot
                .iter()
                .map(|u| u.len() as u32)
                .collect();
            s.u32s(b"SHRL", &lengths)?;
            let total = sections.recorded_unshot.iter().map(Vec::len).sum();
            s.start(b"SHRU", total)?;
            for u in sections.recorded_unshot {
                u.iter().try_for_each(|&x| s.f64(x))?;
            }
            s.packed(
                b"SHSS",
                sections.shot_sum.len(),
                sections.shot_sum.iter().copied(),
            )?;
        }
        write_setup(
            &mut s,
            self.setup_cuts.polygons_hash,
            &self.setup_cuts.cuts,
            &self.field.hidden,
        )
    }

    /// Rebuilds a solver from `checkpoint` on the same scene. With the same
    /// settings, continuing it gives bit-identical results to a solve that was
    /// never interrupted. The thresholds and shot budget may differ (to continue
    /// a solve further); settings that change the mesh (patches) may not.
    pub fn resume(
        scene: &Scene,
        settings: &SolverSettings,
        checkpoint: Checkpoint,
    ) -> Result<Solver, SolveError> {
        Self::resume_observed(scene, settings, checkpoint, &mut crate::progress::Quiet)
    }

    /// [`Solver::resume`], reporting the set-up's passes to `observer`.
    pub fn resume_observed(
        scene: &Scene,
        settings: &SolverSettings,
        mut checkpoint: Checkpoint,
        observer: &mut dyn crate::progress::Observer,
    ) -> Result<Solver, SolveError> {
        let mismatch = |what: String| Err(SolveError::CheckpointMismatch(what));
        if checkpoint.version != CHECKPOINT_VERSION {
            return mismatch(format!(
                "it has state version {}, this solver reads version {CHECKPOINT_VERSION}",
                checkpoint.version
            ));
        }
        // The set-up's searches are not repeated: the mesh is rebuilt from
        // the stored cuts and the stored hidden flags are taken as they are.
        let setup = std::mem::take(&mut checkpoint.setup);
        let hidden = setup.hidden.clone();
        let mut solver = Solver::set_up(scene, settings, Some(setup), observer)?;
        check_mode(&checkpoint, settings)?;
        if checkpoint.fingerprint != solver.fingerprint() {
            return mismatch(format!(
                "its scene fingerprint is {:016x}, this scene's is {:016x} (another scene, or \
                 another patch count)",
                checkpoint.fingerprint,
                solver.fingerprint()
            ));
        }
        // Validate the log before replaying it: every entry must name an element
        // that exists by then (each split adds four).
        let mut elements = solver.mesh.elements.len() as u64;
        for &e in &checkpoint.split_log {
            if e as u64 >= elements {
                return mismatch(format!("its split log names element {e}, of {elements}"));
            }
            elements += 4;
        }
        solver
            .mesh
            .replay(&checkpoint.split_log)
            .map_err(|e| SolveError::CheckpointMismatch(e.to_string()))?;
        if hidden.len() > solver.mesh.vertices.len() {
            return mismatch(format!(
                "it has {} hidden flags, the replayed mesh {} vertices",
                hidden.len(),
                solver.mesh.vertices.len()
            ));
        }
        solver.field.hidden = hidden;
        // A directional checkpoint stores no diffuse proxies (they are recomputed
        // below); a diffuse one stores both.
        let proxies_derived = checkpoint.directional.is_some()
            && checkpoint.radiance.is_empty()
            && checkpoint.patch_unshot.is_empty();
        if proxies_derived {
            solver
                .field
                .radiance
                .resize(solver.mesh.vertices.len(), DVec3::ZERO);
        } else if checkpoint.radiance.len() != solver.mesh.vertices.len()
            || !(checkpoint.direct.is_empty()
                || checkpoint.direct.len() == solver.mesh.vertices.len())
            || checkpoint.patch_unshot.len() != solver.mesh.patches.len()
        {
            return mismatch(format!(
                "it has {} vertices and {} patches, the replayed mesh {} and {}",
                checkpoint.radiance.len(),
                checkpoint.patch_unshot.len(),
                solver.mesh.vertices.len(),
                solver.mesh.patches.len()
            ));
        }
        if !proxies_derived {
            solver.field.radiance = checkpoint.radiance;
            solver.patches.unshot = checkpoint.patch_unshot;
        }
        solver.field.direct = if checkpoint.direct.is_empty() {
            vec![DVec3::ZERO; solver.mesh.vertices.len()]
        } else {
            checkpoint.direct
        };
        let (patches, vertices) = (
            solver.mesh.patches.len() as u32,
            solver.mesh.vertices.len() as u32,
        );
        // Receivers never decrease along the recorded shots (the mesh only
        // grows), and none exceeds the mesh.
        let mut receivers = 0;
        if let Some(bad) = checkpoint.recorded.iter().find(|r| {
            let bad = r.patch >= patches
                || r.index >= checkpoint.shots
                || r.receivers < receivers
                || r.receivers > vertices;
            receivers = r.receivers;
            bad
        }) {
            return mismatch(format!("its recorded shot {bad:?} does not fit the solve"));
        }
        solver.record.shots = checkpoint.recorded;
        solver.restore_groups(checkpoint.recorded_groups, checkpoint.shots)?;
        solver.record.pools = solver
            .record
            .shots
            .iter()
            .map(|r| {
                let shot = super::shoot::Shot::for_patch(
                    &solver.mesh,
                    r.patch,
                    r.index,
                    r.unshot(),
                    &solver.settings,
                    &solver.occluder,
                    &solver.materials.kd,
                );
                super::shoot::SamplePool::with_sets(&shot, super::shoot::REPLAY_POOL_SETS)
            })
            .collect();
        if !solver
            .field
            .radiance
            .iter()
            .chain(&solver.patches.unshot)
            .chain(&solver.field.direct)
            .all(|v| v.is_finite())
        {
            return mismatch("it holds non-finite radiance".into());
        }
        let count = solver.mesh.vertices.len();
        solver.field.received = vec![DVec3::ZERO; count];
        solver.field.visible = vec![0; count];
        solver.stats.leaf_count = solver.mesh.leaf_count();
        let all: Vec<u32> = (0..solver.mesh.surfaces.len() as u32).collect();
        solver.update_weights(&all);
        solver.stats.shots = checkpoint.shots;
        solver.stats.rays = checkpoint.rays;
        solver.stats.seconds = checkpoint.seconds;
        // The lights shoot first: once a shot was taken, theirs was.
        if checkpoint.shots > 0 && !solver.lights.lights.is_empty() {
            if !(checkpoint.lights_power.is_finite() && checkpoint.lights_power >= 0.0) {
                return mismatch(format!("its lights' power is {}", checkpoint.lights_power));
            }
            solver.lights.shot = true;
            solver.lights.power = checkpoint.lights_power;
            solver.include_lights_power();
        }
        let directional = checkpoint.directional.is_some();
        solver
            .restore_directional(checkpoint.directional)
            .map_err(SolveError::CheckpointMismatch)?;
        if directional {
            solver.recompute_directional_direct();
            solver
                .unmask_directional_radiance()
                .and_then(|()| solver.unmask_unshot(&checkpoint.unshot_masked))
                .map_err(SolveError::CheckpointMismatch)?;
            solver.restore_diffuse_proxies();
        }
        solver.stats.unshot_power = solver.total_unshot_power();
        Ok(solver)
    }

    /// Takes a checkpoint's recorded groups (written by a solve of `shots`
    /// shots) after checking that they fit the replayed mesh, and rebuilds
    /// their members and trees as the shots built them.
    fn restore_groups(&mut self, groups: Vec<RecordedGroup>, shots: u64) -> Result<(), SolveError> {
        let (patches, vertices) = (
            self.mesh.patches.len() as u32,
            self.mesh.vertices.len() as u32,
        );
        let mut last = None;
        for g in &groups {
            let member_fits = |&(p, u): &(u32, [u64; 3])| {
                p < patches && u.iter().all(|b| f64::from_bits(*b).is_finite())
            };
            if g.index >= shots
                || last.is_some_and(|l| g.index <= l)
                || g.receivers > vertices
                || g.members.is_empty()
                || !g.members.iter().all(member_fits)
            {
                return Err(SolveError::CheckpointMismatch(format!(
                    "its recorded group of shot {} ({} members, {} receivers) does not fit the \
                     solve",
                    g.index,
                    g.members.len(),
                    g.receivers
                )));
            }
            last = Some(g.index);
        }
        self.record.group_sources = groups
            .iter()
            .map(|g| std::sync::Arc::new(g.sources(&self.mesh)))
            .collect();
        self.record.groups = groups;
        Ok(())
    }

    /// FNV-1a over what the mesh and the transport are built from.
    fn fingerprint(&self) -> u64 {
        let mut h: u64 = 0xcbf2_9ce4_8422_2325;
        let mut eat = |x: u64| {
            for b in x.to_le_bytes() {
                h ^= b as u64;
                h = h.wrapping_mul(0x0000_0100_0000_01b3);
            }
        };
        eat(self.mesh.surfaces.len() as u64);
        for (i, s) in self.mesh.surfaces.iter().enumerate() {
            eat(s.polygon as u64);
            eat(s.patches_per_side as u64);
            // The absolute smallest element decides later splits (a per-object
            // TOML size is not in the settings); nothing in the flat rule, so
            // its fingerprints are those of checkpoints written before sizes.
            if let Some(size) = s.min_element_size {
                eat(size.to_bits());
            }
            eat(s.vertices.len() as u64);
            for v in &s.vertices {
                v.to_array().iter().for_each(|c| eat(c.to_bits()));
            }
            for c in self.materials.kd[i]
                .to_array()
                .iter()
                .chain(&self.materials.emission[i].to_array())
            {
                eat(c.to_bits());
            }
        }
        eat(self.mesh.patches.len() as u64);
        // A textured surface holds E/π and shoots through its texture, so a
        // changed texture, Kd or UV map must refuse the resume. Untextured
        // scenes add nothing here (their fingerprints are unchanged).
        let mut digests: Vec<(*const crate::scene::SceneTexture, u64)> = Vec::new();
        // Emission textures follow the diffuse ones (indices past the surface
        // count), so a changed `map_Ke`, Ke or UV map refuses it too.
        let textures = self.materials.texturing.per_surface.iter();
        for (i, t) in textures
            .chain(&self.materials.texturing.emissive)
            .enumerate()
        {
            let Some(t) = t else { continue };
            eat(i as u64);
            let source = std::sync::Arc::as_ptr(&t.texture);
            let digest = match digests.iter().find(|(s, _)| *s == source) {
                Some(&(_, d)) => d,
                None => {
                    let d = texture_digest(&t.texture);
                    digests.push((source, d));
                    d
                }
            };
            eat(digest);
            let m = &t.map;
            [t.kd, m.origin, m.du, m.dv]
                .iter()
                .flat_map(|v| v.to_array())
                .chain(m.base.to_array())
                .for_each(|c| eat(c.to_bits()));
        }
        h
    }
}

/// FNV-1a over a texture's size and 8-bit texels, computed once per texture
/// per fingerprint (surfaces that share a texture share its digest).
fn texture_digest(texture: &crate::scene::SceneTexture) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let sizes = [texture.width.to_le_bytes(), texture.height.to_le_bytes()];
    for b in sizes.iter().flatten().chain(&texture.rgba) {
        h ^= *b as u64;
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    h
}

#[cfg(test)]
impl Checkpoint {
    /// `solver`'s state written to memory and read back, as a file would be.
    pub(super) fn round_trip(solver: &Solver) -> Checkpoint {
        let mut bytes = Vec::new();
        solver.write_checkpoint(&mut bytes).unwrap();
        Checkpoint::read_from(&mut bytes.as_slice(), bytes.len() as u64).unwrap()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> Checkpoint {
        Checkpoint {
            version: CHECKPOINT_VERSION,
            fingerprint: 0x0123_4567_89ab_cdef,
            shots: 9,
            rays: 12345,
            seconds: 1.0 / 3.0,
            lights_power: 2.5,
            split_log: vec![0, 3, 7],
            radiance: vec![DVec3::new(0.1, 1.0 / 3.0, -0.0), DVec3::splat(2.5e-300)],
            patch_unshot: vec![DVec3::new(1e-7, 0.0, 5.0)],
            direct: vec![DVec3::ONE, DVec3::ZERO],
            recorded: vec![super::super::shoot::RecordedShot {
                index: 4,
                patch: 0,
                receivers: 2,
                unshot: [1, 2, 3],
            }],
            recorded_groups: vec![
                RecordedGroup {
                    index: 5,
                    receivers: 2,
                    members: vec![(0, [4, 5, 6]), (0, [7, 8, 9])],
                },
                RecordedGroup {
                    index: 7,
                    receivers: 2,
                    members: vec![(0, [10, 11, 12])],
                },
            ],
            directional: None,
            unshot_masked: Vec::new(),
            setup: SetupResult {
                polygons_hash: 0x0123_4567_89ab_cdef,
                cuts: vec![(
                    1,
                    vec![crate::mesh::contact::Part {
                        vertices: vec![DVec3::X, DVec3::Y, DVec3::new(0.5, -0.25, 1e-9)],
                        covered: true,
                        apexes: vec![DVec3::Y],
                    }],
                )],
                hidden: (0..33).map(|v| v % 3 == 0).collect(),
            },
        }
    }

    /// The sample's sections, as [`Solver::write_checkpoint`] lays them out.
    fn encode(c: &Checkpoint) -> Vec<u8> {
        let mut out = Vec::new();
        let mut s = SectionWriter::new(&mut out);
        s.start(b"HEAD", 1).unwrap();
        s.u32(c.version).unwrap();
        s.u32(MODE_DIFFUSE).unwrap();
        s.u64(c.fingerprint).unwrap();
        s.u64(c.shots).unwrap();
        s.u64(c.rays).unwrap();
        s.f64(c.seconds).unwrap();
        s.f64(c.lights_power).unwrap();
        s.u32s(b"SPLT", &c.split_log).unwrap();
        s.start(b"RECS", c.recorded.len()).unwrap();
        for r in &c.recorded {
            s.u64(r.index).unwrap();
            s.u32(r.patch).unwrap();
            s.u32(r.receivers).unwrap();
            r.unshot.iter().for_each(|&b| s.u64(b).unwrap());
        }
        s.packed_dvec3s(b"RADI", &c.radiance).unwrap();
        s.packed_dvec3s(b"UNSH", &c.patch_unshot).unwrap();
        s.packed_dvec3s(b"DIRC", &c.direct).unwrap();
        write_groups(&mut s, &c.recorded_groups).unwrap();
        write_setup(
            &mut s,
            c.setup.polygons_hash,
            &c.setup.cuts,
            &c.setup.hidden,
        )
        .unwrap();
        out
    }

    #[test]
    fn sections_round_trip_bit_for_bit() {
        let c = sample();
        let bytes = encode(&c);
        let back = Checkpoint::read_from(&mut bytes.as_slice(), bytes.len() as u64).unwrap();
        // PartialEq on f64 would accept -0.0 for 0.0: compare the bits.
        assert_eq!(back.radiance[0].z.to_bits(), (-0.0f64).to_bits());
        assert_eq!(back.seconds.to_bits(), c.seconds.to_bits());
        assert_eq!(back, c);
    }

    #[test]
    fn every_truncation_is_an_error_naming_a_section() {
        let bytes = encode(&sample());
        for cut in 0..bytes.len() {
            let err = Checkpoint::read_from(&mut &bytes[..cut], cut as u64).unwrap_err();
            let message = err.to_string();
            assert!(message.starts_with("section "), "cut at {cut}: {message}");
        }
    }

    /// A packed section of `values` alone, as the writer lays it out.
    fn packed_section(values: &[f64]) -> Vec<u8> {
        let mut out = Vec::new();
        SectionWriter::new(&mut out)
            .packed_f64s(b"SHRA", values)
            .unwrap();
        out
    }

    fn read_packed(bytes: &[u8]) -> Result<Vec<f64>, StateError> {
        let mut reader = bytes;
        let mut r = SectionReader {
            reader: &mut reader,
            remaining: bytes.len() as u64,
            unpacker: packed::Unpacker::default(),
        };
        r.packed("SHRA")
    }

    #[test]
    fn packed_sections_round_trip_bit_for_bit_across_chunks() {
        // More than one chunk; signed zeros, subnormals, NaN payloads and
        // infinities, which any lossy or float-parsing path would change.
        let mut values: Vec<f64> = (0..CHUNK_VALUES + 7)
            .map(|i| ((i % 977) as f64).sqrt() * 1e-3 - 0.01)
            .collect();
        values[3] = -0.0;
        values[4] = f64::from_bits(1);
        values[5] = f64::from_bits(0x7ff8_0000_dead_beef);
        values[CHUNK_VALUES] = f64::NEG_INFINITY;
        let bytes = packed_section(&values);
        let back = read_packed(&bytes).unwrap();
        assert_eq!(back.len(), values.len());
        assert!(values
            .iter()
            .zip(&back)
            .all(|(a, b)| a.to_bits() == b.to_bits()));
        // Compact: these values repeat (period 977), so deflate must find
        // them; stored bytes would be 8 per value.
        assert!(bytes.len() < 4 * values.len(), "{} bytes", bytes.len());
        // An empty section is its tag and count alone.
        assert_eq!(packed_section(&[]).len(), 12);
        assert!(read_packed(&packed_section(&[])).unwrap().is_empty());
    }

    #[test]
    fn damaged_packed_sections_are_errors_not_panics() {
        let values: Vec<f64> = (0..1000).map(|i| (i as f64).ln_1p()).collect();
        let good = packed_section(&values);
        // Every truncation.
        for cut in 0..good.len() {
            let err = read_packed(&good[..cut]).unwrap_err();
            assert!(err.to_string().starts_with("section SHRA"), "{cut}: {err}");
        }
        // A count of 10¹² values from a few kilobytes: refused by the deflate
        // ratio bound before any chunk is read.
        let mut bytes = good.clone();
        bytes[4..12].copy_from_slice(&1_000_000_000_000u64.to_le_bytes());
        let err = read_packed(&bytes).unwrap_err().to_string();
        assert!(err.contains("announces") && err.contains("only"), "{err}");
        // One value more than the chunk holds, and one fewer.
        for count in [1001u64, 999] {
            let mut bytes = good.clone();
            bytes[4..12].copy_from_slice(&count.to_le_bytes());
            let err = read_packed(&bytes).unwrap_err().to_string();
            assert!(err.contains("chunk"), "{count}: {err}");
        }
        // A chunk length beyond what a chunk may have.
        let mut bytes = good.clone();
        bytes[12..16].copy_from_slice(&u32::MAX.to_le_bytes());
        let err = read_packed(&bytes).unwrap_err().to_string();
        assert!(err.contains("announces 4294967295 bytes"), "{err}");
        // Flipped bits inside the deflate stream: an error, or values that
        // differ (the envelope's checksum refuses those).
        // (Not the last byte: its high bits may be padding after the stream.)
        for at in [16, 40, good.len() / 2] {
            let mut bytes = good.clone();
            bytes[at] ^= 0x5a;
            if let Ok(back) = read_packed(&bytes) {
                assert!(back
                    .iter()
                    .zip(&values)
                    .any(|(a, b)| a.to_bits() != b.to_bits()));
            }
        }
    }

    #[test]
    fn a_huge_count_is_refused_before_allocating() {
        let mut bytes = encode(&sample());
        // The RADI count: after HEAD (4 + 8 + 48), SPLT (12 + 12), RECS (12 + 40).
        let at = 4 + 8 + 48 + 12 + 12 + 12 + 40 + 4;
        assert_eq!(&bytes[at - 4..at], b"RADI");
        bytes[at..at + 8].copy_from_slice(&(u64::MAX / 2).to_le_bytes());
        let err = Checkpoint::read_from(&mut bytes.as_slice(), bytes.len() as u64).unwrap_err();
        let message = err.to_string();
        assert!(
            message.contains("RADI") && message.contains("only"),
            "{message}"
        );
        // A flipped tag names the section that was expected.
        let mut bytes = encode(&sample());
        bytes[at - 4] = b'X';
        let err = Checkpoint::read_from(&mut bytes.as_slice(), bytes.len() as u64).unwrap_err();
        assert!(err.to_string().contains("section RADI"), "{err}");
    }
}
