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
//! | P | payload: the solver's `Checkpoint`, as JSON |
//!
//! JSON keeps the payload self-describing and readable with `jq`; serde_json is
//! built with `float_roundtrip`, so every f64 reads back bit-exact and a resumed
//! solve ends with the same numbers as an uninterrupted one.

use crate::scene::Scene;
use crate::settings::SolverSettings;
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};
use std::path::Path;

const MAGIC: &[u8; 8] = b"RADCKPT\0";
/// Bump when the envelope or the meaning of the payload changes.
pub const VERSION: u32 = 1;
const PREFIX: usize = 8 + 4 + 4 + 8 + 4;

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

/// Writes a checkpoint atomically.
pub fn write<T: Serialize>(path: &Path, meta: &Meta, state: &T) -> anyhow::Result<()> {
    let meta_bytes = serde_json::to_vec(meta)?;
    let payload = serde_json::to_vec(state)?;
    let mut crc = crc32fast::Hasher::new();
    crc.update(&meta_bytes);
    crc.update(&payload);
    let mut bytes = Vec::with_capacity(PREFIX + meta_bytes.len() + payload.len());
    bytes.extend_from_slice(MAGIC);
    bytes.extend_from_slice(&VERSION.to_le_bytes());
    bytes.extend_from_slice(&(meta_bytes.len() as u32).to_le_bytes());
    bytes.extend_from_slice(&(payload.len() as u64).to_le_bytes());
    bytes.extend_from_slice(&crc.finalize().to_le_bytes());
    bytes.extend_from_slice(&meta_bytes);
    bytes.extend_from_slice(&payload);
    super::files::write_atomic(path, &bytes)
}

/// Reads a checkpoint and checks that it belongs to this scene and these settings.
pub fn read<T: DeserializeOwned>(
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
    let bytes = std::fs::read(path).map_err(|source| CheckpointError::Io {
        path: name.clone(),
        source,
    })?;
    if bytes.len() < 8 || &bytes[..8] != MAGIC {
        return Err(CheckpointError::NotACheckpoint { path: name });
    }
    if bytes.len() < PREFIX {
        return Err(corrupt(format!(
            "{} bytes, shorter than its header",
            bytes.len()
        )));
    }
    let u32_at =
        |at: usize| u32::from_le_bytes([bytes[at], bytes[at + 1], bytes[at + 2], bytes[at + 3]]);
    let version = u32_at(8);
    if version != VERSION {
        return Err(CheckpointError::Version {
            path: name,
            found: version,
        });
    }
    let meta_len = u32_at(12) as u64;
    let mut payload_len = [0u8; 8];
    payload_len.copy_from_slice(&bytes[16..24]);
    let payload_len = u64::from_le_bytes(payload_len);
    let stored_crc = u32_at(24);
    // The lengths come from the file: check them against its real size before
    // slicing (no allocation is sized by them).
    let expected = (PREFIX as u64)
        .checked_add(meta_len)
        .and_then(|n| n.checked_add(payload_len));
    if expected != Some(bytes.len() as u64) {
        return Err(corrupt(format!(
            "header announces {meta_len} + {payload_len} bytes of content, the file has {}",
            bytes.len() - PREFIX
        )));
    }
    let content = &bytes[PREFIX..];
    if crc32fast::hash(content) != stored_crc {
        return Err(corrupt("checksum mismatch".into()));
    }
    let (meta_bytes, payload) = content.split_at(meta_len as usize);
    let meta: Meta =
        serde_json::from_slice(meta_bytes).map_err(|e| corrupt(format!("meta block: {e}")))?;
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
    let state: T =
        serde_json::from_slice(payload).map_err(|e| corrupt(format!("solver state: {e}")))?;
    Ok((meta, state))
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
            polygons: vec![crate::scene::Polygon {
                vertices: vec![
                    DVec3::new(0.0, 0.0, z),
                    DVec3::new(1.0, 0.0, z),
                    DVec3::new(1.0, 1.0, z),
                    DVec3::new(0.0, 1.0, z),
                ],
                vertex_normals: None,
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
            }],
            units_per_metre: 1.0,
            up_axis: Default::default(),
            camera: None,
            recentre_offset: DVec3::ZERO,
            warnings: vec![],
        }
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

    #[test]
    fn round_trip_is_bit_exact() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("c");
        let settings = SolverSettings::preset(Preset::Draft);
        // Values whose shortest decimal form is long: a lossy float parser would
        // change their last bit.
        let state: Vec<f64> = (1..200)
            .map(|i| (i as f64).sqrt() * 1e-7 + 1.0 / 3.0)
            .collect();
        write(&path, &meta(&settings), &state).unwrap();
        let (m, back): (Meta, Vec<f64>) = read(
            &path,
            "00000000000000aa",
            "box.obj",
            &result_settings(&settings),
        )
        .unwrap();
        assert_eq!(m.shots, 7);
        assert!(state
            .iter()
            .zip(&back)
            .all(|(a, b)| a.to_bits() == b.to_bits()));
    }

    #[test]
    fn other_scene_settings_and_damage_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("c");
        let settings = SolverSettings::preset(Preset::Draft);
        write(&path, &meta(&settings), &vec![1.0f64]).unwrap();
        let ours = result_settings(&settings);

        let err = read::<Vec<f64>>(&path, "00000000000000bb", "other.obj", &ours).unwrap_err();
        assert!(matches!(err, CheckpointError::OtherScene { .. }), "{err}");

        let mut other = settings.clone();
        other.samples += 1;
        let err = read::<Vec<f64>>(
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
        read::<Vec<f64>>(
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
        let err = read::<Vec<f64>>(&path, "00000000000000aa", "box.obj", &ours).unwrap_err();
        assert!(matches!(err, CheckpointError::Corrupt { .. }), "{err}");

        std::fs::write(&path, &bytes[..PREFIX + 3]).unwrap();
        let err = read::<Vec<f64>>(&path, "00000000000000aa", "box.obj", &ours).unwrap_err();
        assert!(matches!(err, CheckpointError::Corrupt { .. }), "{err}");

        std::fs::write(&path, b"not a checkpoint at all").unwrap();
        let err = read::<Vec<f64>>(&path, "00000000000000aa", "box.obj", &ours).unwrap_err();
        assert!(
            matches!(err, CheckpointError::NotACheckpoint { .. }),
            "{err}"
        );
    }
}
