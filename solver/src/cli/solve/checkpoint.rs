//! Checkpoint files: the solver's state, saved every K shots so that no work is
//! lost, and refused when it belongs to another scene or other settings.
//!
//! Layout (little-endian):
//!
//! | bytes | content |
//! | --- | --- |
//! | 8 | magic `RADCKPT\0` |
//! | 4 | format version (`VERSION`) |
//! | 4 | length M of the meta block |
//! | 8 | length P of the payload |
//! | 4 | CRC-32 of meta + payload |
//! | M | meta: JSON [`Meta`] (scene fingerprint, resolved settings, seconds so far) |
//! | P | payload: the solver's state in binary sections (`solve/checkpoint.rs`) |
//!
//! Written streaming: the payload goes straight from the solver's arrays through a
//! buffer into the atomic writer's temporary file, and the lengths and checksum
//! are patched into the header at the end. Read streaming too: the header's
//! lengths are checked against the file's size, the meta block against
//! [`MAX_META`], and the payload's sections against the bytes left, before
//! anything is allocated; the checksum is verified as the payload streams by.

use crate::scene::Scene;
use crate::settings::SolverSettings;
use serde::{Deserialize, Serialize};
use std::fs::File;
use std::io::{self, BufReader, Read, Seek, SeekFrom, Write};
use std::path::Path;

const MAGIC: &[u8; 8] = b"RADCKPT\0";
/// Bump when the envelope or the meaning of the payload changes.
pub const VERSION: u32 = 4;
const PREFIX: usize = 8 + 4 + 4 + 8 + 4;
/// The most bytes a meta block may have (it is a few kilobytes of JSON: the
/// fingerprint, the scene's path and the settings).
pub const MAX_META: u64 = 16 << 20;

/// A checkpoint's payload as read back: the state a solver resumes from.
pub trait Payload: Sized {
    /// Reads exactly `length` bytes of payload from `reader`; the error names
    /// the part of the state that is wrong.
    fn read_payload(reader: &mut dyn Read, length: u64) -> Result<Self, String>;
}

impl Payload for crate::solve::Checkpoint {
    fn read_payload(mut reader: &mut dyn Read, length: u64) -> Result<Self, String> {
        crate::solve::Checkpoint::read_from(&mut reader, length).map_err(|e| e.to_string())
    }
}

/// What the checkpoint says about the solve it came from.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Meta {
    /// [`scene_fingerprint`] of the scene, hex.
    pub scene_fingerprint: String,
    /// The scene file named on the command line (for messages only).
    pub scene_path: String,
    /// [`result_settings`] of the solve: the settings that decide the result.
    pub settings: serde_json::Value,
    /// Wall-clock seconds spent by the sessions so far.
    pub seconds: f64,
    /// Shots done when the checkpoint was written.
    pub shots: u64,
}

/// Why a checkpoint cannot be used; every message names the file.
#[derive(Debug, thiserror::Error)]
pub enum CheckpointError {
    #[error("cannot read checkpoint {path}: {source}")]
    Io {
        path: String,
        source: std::io::Error,
    },
    #[error("{path} is not a solver checkpoint (bad magic bytes)")]
    NotACheckpoint { path: String },
    #[error("checkpoint {path} has format version {found}; this solver reads version {VERSION}")]
    Version { path: String, found: u32 },
    #[error("checkpoint {path} is truncated or corrupted ({detail}); delete it and solve again")]
    Corrupt { path: String, detail: String },
    #[error(
        "checkpoint {path} was written for a different scene (from {their_scene}); \
         it cannot be resumed with {our_scene}. Resume with the scene of the \
         interrupted solve, or delete the checkpoint to start over"
    )]
    OtherScene {
        path: String,
        their_scene: String,
        our_scene: String,
    },
    #[error(
        "checkpoint {path} was written with other solver settings ({differences}); \
         resume with the same preset and flags as the interrupted solve, or delete \
         the checkpoint to start over"
    )]
    OtherSettings { path: String, differences: String },
}

/// FNV-1a, 64 bit: a stable hash (std's `DefaultHasher` may change between Rust
/// releases, and a checkpoint must outlive a toolchain upgrade). It guards against
/// mistakes, not against an adversary.
struct Fnv(u64);

impl Fnv {
    fn new() -> Self {
        Fnv(0xcbf2_9ce4_8422_2325)
    }
    fn bytes(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 ^= b as u64;
            self.0 = self.0.wrapping_mul(0x0000_0100_0000_01b3);
        }
    }
    fn u64(&mut self, v: u64) {
        self.bytes(&v.to_le_bytes());
    }
    fn f64(&mut self, v: f64) {
        self.u64(v.to_bits());
    }
    fn str(&mut self, s: &str) {
        self.u64(s.len() as u64);
        self.bytes(s.as_bytes());
    }
}

/// A fingerprint of everything in the scene that the solve reads: geometry (bit
/// exact), materials, patch counts, units, up axis and re-centring. Where the scene
/// came from (paths, line numbers) and the import warnings are left out, so a
/// moved or renamed scene file still resumes.
pub fn scene_fingerprint(scene: &Scene) -> String {
    let mut h = Fnv::new();
    h.u64(scene.polygons.len() as u64);
    for polygon in &scene.polygons {
        h.u64(polygon.vertices.len() as u64);
        for v in &polygon.vertices {
            h.f64(v.x);
            h.f64(v.y);
            h.f64(v.z);
        }
        match &polygon.vertex_normals {
            None => h.u64(0),
            Some(normals) => {
                h.u64(1 + normals.len() as u64);
                for n in normals {
                    h.f64(n.x);
                    h.f64(n.y);
                    h.f64(n.z);
                }
            }
        }
        h.u64(polygon.material as u64);
        h.u64(polygon.patches as u64);
    }
    h.u64(scene.materials.len() as u64);
    for m in &scene.materials {
        h.str(&m.name);
        for v in [m.kd, m.ks, m.emission] {
            h.f64(v.x);
            h.f64(v.y);
            h.f64(v.z);
        }
        h.f64(m.alpha);
    }
    h.f64(scene.units_per_metre);
    h.u64(scene.up_axis.code() as u64);
    h.f64(scene.recentre_offset.x);
    h.f64(scene.recentre_offset.y);
    h.f64(scene.recentre_offset.z);
    // The lights (issue 41), only when there are some, so that the
    // fingerprints of scenes lit by their materials alone do not change. The
    // debug form prints every f64 exactly; a lamp's name is left out.
    if !scene.lights.is_empty() {
        let l = &scene.lights;
        h.str(&format!("{:?}{:?}", l.sun, l.sky));
        for lamp in &l.lamps {
            h.str(&format!(
                "{:?}{:?}{:?}{:?}{:?}",
                lamp.position, lamp.intensity, lamp.radius, lamp.beam, lamp.profile
            ));
        }
    }
    format!("{:016x}", h.0)
}

/// The settings that decide the result, as JSON. The stopping rules (`threshold`,
/// `max_shots`), `threads` (results do not depend on it), `checkpoint_every`,
/// `strict` (an import switch already reflected in the scene) and the preset's name
/// (its values are what count) are left out: a solve stopped at a small shot
/// budget may be resumed with a larger one or a tighter threshold.
pub fn result_settings(settings: &SolverSettings) -> serde_json::Value {
    let mut value = serde_json::to_value(settings).unwrap_or(serde_json::Value::Null);
    if let Some(map) = value.as_object_mut() {
        for key in [
            "threshold",
            "max_shots",
            "threads",
            "checkpoint_every",
            "strict",
            "preset",
        ] {
            map.remove(key);
        }
    }
    value
}

/// Counts and checksums what passes through to the file.
struct Summing<'a, W: Write> {
    inner: &'a mut W,
    crc: crc32fast::Hasher,
    bytes: u64,
}

impl<W: Write> Write for Summing<'_, W> {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        let n = self.inner.write(buf)?;
        self.crc.update(&buf[..n]);
        self.bytes += n as u64;
        Ok(n)
    }
    fn flush(&mut self) -> io::Result<()> {
        self.inner.flush()
    }
}

/// Writes a checkpoint atomically, streaming: `payload` writes the solver's state
/// into the temporary file (through a buffer), then the header gets the lengths
/// and the checksum.
pub fn write(
    path: &Path,
    meta: &Meta,
    payload: impl FnOnce(&mut dyn Write) -> io::Result<()>,
) -> anyhow::Result<()> {
    let meta_bytes = serde_json::to_vec(meta)?;
    #[allow(clippy::disallowed_methods)] // An edge: writes the checkpoint.
    solution::atomic::write_atomically_buffered(path, |file| {
        file.write_all(&[0u8; PREFIX])?;
        let mut summing = Summing {
            inner: &mut *file,
            crc: crc32fast::Hasher::new(),
            bytes: 0,
        };
        summing.write_all(&meta_bytes)?;
        payload(&mut summing)?;
        let payload_len = summing.bytes - meta_bytes.len() as u64;
        let crc = summing.crc.finalize();
        file.seek(SeekFrom::Start(0))?;
        file.write_all(MAGIC)?;
        file.write_all(&VERSION.to_le_bytes())?;
        file.write_all(&(meta_bytes.len() as u32).to_le_bytes())?;
        file.write_all(&payload_len.to_le_bytes())?;
        file.write_all(&crc.to_le_bytes())?;
        Ok(())
    })
    .map_err(|e| anyhow::Error::new(e).context(format!("writing checkpoint {}", path.display())))
}

/// Checksums what is read through it.
struct Checking<R: Read> {
    inner: R,
    crc: crc32fast::Hasher,
}

impl<R: Read> Read for Checking<R> {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        let n = self.inner.read(buf)?;
        self.crc.update(&buf[..n]);
        Ok(n)
    }
}

/// Reads a checkpoint and checks that it belongs to this scene and these
/// settings; streaming, with every length checked before it sizes anything.
pub fn read<T: Payload>(
    path: &Path,
    scene_fp: &str,
    scene_path: &str,
    settings: &serde_json::Value,
) -> Result<(Meta, T), CheckpointError> {
    let name = path.display().to_string();
    let corrupt = |detail: String| CheckpointError::Corrupt {
        path: name.clone(),
        detail,
    };
    let io_error = |source| CheckpointError::Io {
        path: name.clone(),
        source,
    };
    #[allow(clippy::disallowed_methods)] // An edge: `--resume` reads the checkpoint.
    let file = File::open(path).map_err(io_error)?;
    let file_len = file.metadata().map_err(io_error)?.len();
    let mut reader = BufReader::with_capacity(1 << 20, file);
    let mut prefix = [0u8; PREFIX];
    let got = read_up_to(&mut reader, &mut prefix).map_err(io_error)?;
    if got < 8 || &prefix[..8] != MAGIC {
        return Err(CheckpointError::NotACheckpoint { path: name });
    }
    if got < PREFIX {
        return Err(corrupt(format!("{got} bytes, shorter than its header")));
    }
    // The prefix holds PREFIX bytes (checked above), and every slice below has
    // the exact length of its array, so these conversions cannot fail.
    let u32_at = |at: usize| u32::from_le_bytes(prefix[at..at + 4].try_into().unwrap());
    let version = u32_at(8);
    if version != VERSION {
        return Err(CheckpointError::Version {
            path: name,
            found: version,
        });
    }
    let meta_len = u32_at(12) as u64;
    let payload_len = u64::from_le_bytes(prefix[16..24].try_into().unwrap());
    let stored_crc = u32_at(24);
    // The lengths come from the file: check them against its real size before
    // reading (the meta block's buffer is sized by its length, so it is capped too).
    let expected = (PREFIX as u64)
        .checked_add(meta_len)
        .and_then(|n| n.checked_add(payload_len));
    if expected != Some(file_len) {
        return Err(corrupt(format!(
            "header announces {meta_len} + {payload_len} bytes of content, the file has {}",
            file_len - PREFIX as u64
        )));
    }
    if meta_len > MAX_META {
        return Err(corrupt(format!(
            "meta block of {meta_len} bytes, more than {MAX_META}"
        )));
    }
    let mut checking = Checking {
        inner: reader,
        crc: crc32fast::Hasher::new(),
    };
    let mut meta_bytes = vec![0u8; meta_len as usize];
    checking
        .read_exact(&mut meta_bytes)
        .map_err(|e| corrupt(format!("meta block: {e}")))?;
    let meta: Meta =
        serde_json::from_slice(&meta_bytes).map_err(|e| corrupt(format!("meta block: {e}")))?;
    if meta.scene_fingerprint != scene_fp {
        return Err(CheckpointError::OtherScene {
            path: name,
            their_scene: meta.scene_path.clone(),
            our_scene: scene_path.to_string(),
        });
    }
    let differences = settings_differences(&meta.settings, settings);
    if !differences.is_empty() {
        return Err(CheckpointError::OtherSettings {
            path: name,
            differences,
        });
    }
    // A damaged payload usually fails its own checks first (they name the
    // section); one that still decodes fails the checksum.
    let state = T::read_payload(&mut checking, payload_len)
        .map_err(|e| corrupt(format!("solver state: {e}")))?;
    if checking.crc.finalize() != stored_crc {
        return Err(corrupt("checksum mismatch".into()));
    }
    Ok((meta, state))
}

/// Reads until `buf` is full or the file ends; the count read.
fn read_up_to(reader: &mut impl Read, buf: &mut [u8]) -> io::Result<usize> {
    let mut got = 0;
    while got < buf.len() {
        match reader.read(&mut buf[got..]) {
            Ok(0) => break,
            Ok(n) => got += n,
            Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok(got)
}

/// `samples: 4 in the checkpoint, 8 now; …`, empty when equal.
fn settings_differences(theirs: &serde_json::Value, ours: &serde_json::Value) -> String {
    let empty = serde_json::Map::new();
    let a = theirs.as_object().unwrap_or(&empty);
    let b = ours.as_object().unwrap_or(&empty);
    let mut keys: Vec<&String> = a.keys().chain(b.keys()).collect();
    keys.sort();
    keys.dedup();
    let null = serde_json::Value::Null;
    keys.into_iter()
        .filter_map(|k| {
            let (x, y) = (a.get(k).unwrap_or(&null), b.get(k).unwrap_or(&null));
            (x != y).then(|| format!("{k}: {x} in the checkpoint, {y} now"))
        })
        .collect::<Vec<_>>()
        .join("; ")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::settings::Preset;

    fn meta(settings: &SolverSettings) -> Meta {
        Meta {
            scene_fingerprint: "00000000000000aa".into(),
            scene_path: "box.obj".into(),
            settings: result_settings(settings),
            seconds: 1.5,
            shots: 7,
        }
    }

    fn square(z: f64) -> Scene {
        use glam::DVec3;
        Scene {
            lights: Default::default(),
            polygons: vec![crate::scene::Polygon {
                vertices: vec![
                    DVec3::new(0.0, 0.0, z),
                    DVec3::new(1.0, 0.0, z),
                    DVec3::new(1.0, 1.0, z),
                    DVec3::new(0.0, 1.0, z),
                ],
                vertex_normals: None,
                uv_map: None,
                material: 0,
                patches: 1,
                sizes: Default::default(),
                source: Default::default(),
            }],
            materials: vec![crate::scene::Material {
                name: "white".into(),
                kd: DVec3::splat(0.5),
                ks: DVec3::ZERO,
                alpha: 0.3,
                emission: DVec3::ZERO,
                diffuse_texture: None,
                emission_texture: None,
                folded_texture: None,
            }],
            units_per_metre: 1.0,
            up_axis: Default::default(),
            camera: None,
            recentre_offset: DVec3::ZERO,
            warnings: vec![],
        }
    }

    #[test]
    fn scene_fingerprint_sees_the_lights() {
        let a = square(0.0);
        let mut lit = a.clone();
        let position = crate::light::sun::SunPosition::from_direction(glam::DVec3::Y).unwrap();
        let sun = crate::light::sun::Sun::new(position, glam::DVec3::ONE, 0.53).unwrap();
        lit.lights.sun = Some(sun);
        assert_ne!(scene_fingerprint(&a), scene_fingerprint(&lit));
        let mut lower = lit.clone();
        let position = crate::light::sun::SunPosition::from_direction(glam::DVec3::ONE).unwrap();
        lower.lights.sun =
            Some(crate::light::sun::Sun::new(position, glam::DVec3::ONE, 0.53).unwrap());
        assert_ne!(scene_fingerprint(&lit), scene_fingerprint(&lower));
    }

    #[test]
    fn scene_fingerprint_sees_geometry_not_file_names() {
        let a = square(0.0);
        let mut renamed = a.clone();
        renamed.polygons[0].source.file = "elsewhere.obj".into();
        assert_eq!(scene_fingerprint(&a), scene_fingerprint(&renamed));
        // One ulp of one coordinate is a different scene.
        let moved = square(f64::from_bits(1));
        assert_ne!(scene_fingerprint(&a), scene_fingerprint(&moved));
        let mut brighter = a.clone();
        brighter.materials[0].emission.x = 1.0;
        assert_ne!(scene_fingerprint(&a), scene_fingerprint(&brighter));
    }

    /// A test payload: f64s as their bits.
    #[derive(Debug, PartialEq)]
    struct Floats(Vec<f64>);

    impl Payload for Floats {
        fn read_payload(reader: &mut dyn Read, length: u64) -> Result<Self, String> {
            if !length.is_multiple_of(8) {
                return Err(format!("{length} bytes is not a whole number of f64s"));
            }
            let mut out = Vec::new();
            for _ in 0..length / 8 {
                let mut b = [0u8; 8];
                reader.read_exact(&mut b).map_err(|e| e.to_string())?;
                out.push(f64::from_le_bytes(b));
            }
            Ok(Floats(out))
        }
    }

    fn write_floats(path: &Path, meta: &Meta, values: &[f64]) {
        write(path, meta, |w| {
            values
                .iter()
                .try_for_each(|v| w.write_all(&v.to_le_bytes()))
        })
        .unwrap();
    }

    #[test]
    fn round_trip_is_bit_exact() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("c");
        let settings = SolverSettings::preset(Preset::Draft);
        // Values whose shortest decimal form is long, and -0.0: a lossy encoding
        // would change their last bit.
        let mut state: Vec<f64> = (1..200)
            .map(|i| (i as f64).sqrt() * 1e-7 + 1.0 / 3.0)
            .collect();
        state.push(-0.0);
        write_floats(&path, &meta(&settings), &state);
        let (m, back): (Meta, Floats) = read(
            &path,
            "00000000000000aa",
            "box.obj",
            &result_settings(&settings),
        )
        .unwrap();
        assert_eq!(m.shots, 7);
        assert_eq!(back.0.len(), state.len());
        assert!(state
            .iter()
            .zip(&back.0)
            .all(|(a, b)| a.to_bits() == b.to_bits()));
    }

    #[test]
    fn other_scene_settings_and_damage_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("c");
        let settings = SolverSettings::preset(Preset::Draft);
        write_floats(&path, &meta(&settings), &[1.0, 2.0]);
        let ours = result_settings(&settings);

        let err = read::<Floats>(&path, "00000000000000bb", "other.obj", &ours).unwrap_err();
        assert!(matches!(err, CheckpointError::OtherScene { .. }), "{err}");

        let mut other = settings.clone();
        other.samples += 1;
        let err = read::<Floats>(
            &path,
            "00000000000000aa",
            "box.obj",
            &result_settings(&other),
        )
        .unwrap_err();
        assert!(err.to_string().contains("samples"), "{err}");

        // A bigger shot budget or thread count is a legitimate way to resume.
        let mut more = settings.clone();
        more.max_shots *= 10;
        more.threads = Some(1);
        read::<Floats>(
            &path,
            "00000000000000aa",
            "box.obj",
            &result_settings(&more),
        )
        .unwrap();

        let mut bytes = std::fs::read(&path).unwrap();
        let last = bytes.len() - 1;
        bytes[last] ^= 1;
        std::fs::write(&path, &bytes).unwrap();
        let err = read::<Floats>(&path, "00000000000000aa", "box.obj", &ours).unwrap_err();
        assert!(matches!(err, CheckpointError::Corrupt { .. }), "{err}");
        assert!(err.to_string().contains("checksum"), "{err}");

        std::fs::write(&path, &bytes[..PREFIX + 3]).unwrap();
        let err = read::<Floats>(&path, "00000000000000aa", "box.obj", &ours).unwrap_err();
        assert!(matches!(err, CheckpointError::Corrupt { .. }), "{err}");
        assert!(
            err.to_string().contains(&path.display().to_string()),
            "{err}"
        );

        std::fs::write(&path, b"not a checkpoint at all").unwrap();
        let err = read::<Floats>(&path, "00000000000000aa", "box.obj", &ours).unwrap_err();
        assert!(
            matches!(err, CheckpointError::NotACheckpoint { .. }),
            "{err}"
        );
    }

    #[test]
    fn lying_lengths_are_refused_before_allocating() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("c");
        let settings = SolverSettings::preset(Preset::Draft);
        write_floats(&path, &meta(&settings), &[1.0, 2.0]);
        let ours = result_settings(&settings);
        let good = std::fs::read(&path).unwrap();
        // A meta length of 4 GiB − 1 and a payload length that makes the sum
        // match no file: refused by the size check, no buffer of that size made.
        let mut bytes = good.clone();
        bytes[12..16].copy_from_slice(&u32::MAX.to_le_bytes());
        std::fs::write(&path, &bytes).unwrap();
        let err = read::<Floats>(&path, "00000000000000aa", "box.obj", &ours).unwrap_err();
        assert!(err.to_string().contains("header announces"), "{err}");
        // Lengths that add up to the file's size but give the payload's bytes to
        // a meta block: the JSON does not parse, named as the meta block.
        let mut bytes = good;
        let meta_len = u32::from_le_bytes(bytes[12..16].try_into().unwrap());
        bytes[12..16].copy_from_slice(&(meta_len + 8).to_le_bytes());
        bytes[16..24].copy_from_slice(&8u64.to_le_bytes());
        std::fs::write(&path, &bytes).unwrap();
        let err = read::<Floats>(&path, "00000000000000aa", "box.obj", &ours).unwrap_err();
        assert!(err.to_string().contains("meta block"), "{err}");
    }
}
