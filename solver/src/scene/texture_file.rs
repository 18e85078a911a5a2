//! Reading a diffuse texture file (`map_Kd`) through the `image` crate: PNG or
//! JPEG, sizes checked from the header before anything is decoded.
//!
//! A texture that cannot be used is never an error: the material keeps its
//! flat Kd and a warning names the file and why (missing, unreadable,
//! truncated or corrupt, an unsupported format, or larger than
//! [`MAX_TEXTURE_SIZE`] / [`MAX_TEXTURE_TEXELS`]). A tiny PNG can declare
//! 65535 × 65535 texels (16 GiB of RGBA); the header is read first and such a
//! file refused before any allocation beyond the file itself, and the decoder
//! runs under `image::Limits` as a second guard.
//!
//! A file named with the wrong letter case (`SP_LUK.JPG` for `sp_luk.JPG`, as
//! scenes authored on Windows often do) is found in its folder and read, with a
//! warning naming both spellings ([`super::path_case`]).

use super::{SceneTexture, SourceRef, Warning};
use std::io::Cursor;
use std::path::Path;
use std::sync::Arc;

/// The largest width or height read, in texels (16384 is also the solution
/// format's limit, and what every GPU guarantees for a 2-D image).
pub const MAX_TEXTURE_SIZE: u32 = 16384;
/// The most texels read from one texture: 4096² = 16.8 M, about 64 MiB as
/// RGBA8 for the solution file and 300 MiB as the solver's linear pyramid
/// (12 bytes a texel, 1.5 × for the levels). The memory budget counts both.
pub const MAX_TEXTURE_TEXELS: u64 = 4096 * 4096;
/// Texture files larger than this are not read (a 4096² PNG of noise is
/// about 64 MiB; JPEGs are smaller).
pub const MAX_TEXTURE_FILE_BYTES: u64 = 256 << 20;

/// Loads `path` for the material at `source`, or decodes `bytes` when the
/// texture is not a file of its own (a glTF image in a buffer or a data URI;
/// `path` then names it); `None` (with a warning in `warnings`) when it
/// cannot be used. `statement` is `map_Kd` or `map_Ke`: the warning names
/// it and the flat value (Kd or Ke) used instead.
pub(crate) fn load_texture(
    path: &Path,
    bytes: Option<&[u8]>,
    source: &SourceRef,
    statement: &str,
    warnings: &mut Vec<Warning>,
) -> Option<Arc<SceneTexture>> {
    let flat = format!(
        "the flat {}",
        statement.strip_prefix("map_").unwrap_or(statement)
    );
    let image = load_rgba(path, bytes, source, (statement, &flat), warnings)?;
    match SceneTexture::from_rgba(path.to_path_buf(), image.width, image.height, image.rgba) {
        Some(t) => Some(Arc::new(t)),
        None => {
            warn_unusable(
                path,
                source,
                (statement, &flat),
                "decoded to an image of zero size",
                warnings,
            );
            None
        }
    }
}

/// A decoded image: `width × height × 4` bytes of RGBA8, rows top to bottom,
/// as stored (no colour decoding).
pub(crate) struct Rgba8 {
    pub width: u32,
    pub height: u32,
    pub rgba: Vec<u8>,
}

/// Reads and decodes an image as [`load_texture`] does, under the same caps,
/// but keeps its 8-bit channels as stored: for data textures (glTF's
/// metallic-roughness texture is linear, not sRGB). `(statement, flat)` name
/// the texture and what is used instead in the warning given when it cannot be
/// used.
pub(crate) fn load_rgba(
    path: &Path,
    bytes: Option<&[u8]>,
    source: &SourceRef,
    (statement, flat): (&str, &str),
    warnings: &mut Vec<Warning>,
) -> Option<Rgba8> {
    let image = match bytes {
        Some(bytes) => decode(bytes),
        None => read_any_case(path, source, statement, warnings),
    };
    match image {
        Ok(image) => Some(image),
        Err(why) => {
            warn_unusable(path, source, (statement, flat), &why, warnings);
            None
        }
    }
}

fn warn_unusable(
    path: &Path,
    source: &SourceRef,
    (statement, flat): (&str, &str),
    why: &str,
    warnings: &mut Vec<Warning>,
) {
    warnings.push(Warning {
        source: source.clone(),
        message: format!(
            "{statement} texture {}: {why}; {flat} is used",
            path.display()
        ),
    });
}

/// Reads `path`; when no file has that name, reads the one file in its folder
/// whose name differs from it only in letter case, with a warning naming both
/// spellings. Several such files are refused, each named: which one is meant
/// cannot be told.
#[allow(clippy::disallowed_methods)] // An edge: an importer reads the textures its scene names.
fn read_any_case(
    path: &Path,
    source: &SourceRef,
    statement: &str,
    warnings: &mut Vec<Warning>,
) -> Result<Rgba8, String> {
    let missing =
        matches!(std::fs::metadata(path), Err(e) if e.kind() == std::io::ErrorKind::NotFound);
    if !missing {
        return read(path);
    }
    match super::path_case::case_variants(path).as_slice() {
        [] => read(path),
        [found] => {
            warnings.push(Warning {
                source: source.clone(),
                message: format!(
                    "{statement} texture {}: no file has that name; {} differs from it only in \
                     letter case and is read instead (rename the file, or spell the name as the \
                     file is, to silence this)",
                    path.display(),
                    found.display()
                ),
            });
            read(found)
        }
        several => Err(format!(
            "cannot be read (no file has that name), and {} files differ from it only in \
             letter case ({}): which one is meant cannot be told; spell the name as one of \
             them is",
            several.len(),
            several
                .iter()
                .map(|p| p.display().to_string())
                .collect::<Vec<_>>()
                .join(", ")
        )),
    }
}

#[allow(clippy::disallowed_methods)] // An edge: an importer reads the textures its scene names.
fn read(path: &Path) -> Result<Rgba8, String> {
    let length = std::fs::metadata(path)
        .map_err(|e| format!("cannot be read ({e})"))?
        .len();
    if length > MAX_TEXTURE_FILE_BYTES {
        return Err(format!(
            "the file has {length} bytes, more than the {MAX_TEXTURE_FILE_BYTES} read"
        ));
    }
    let bytes = std::fs::read(path).map_err(|e| format!("cannot be read ({e})"))?;
    decode(&bytes)
}

/// Decodes an encoded PNG or JPEG, its size checked from its header before
/// anything is decoded.
fn decode(bytes: &[u8]) -> Result<Rgba8, String> {
    if bytes.len() as u64 > MAX_TEXTURE_FILE_BYTES {
        return Err(format!(
            "the image has {} bytes, more than the {MAX_TEXTURE_FILE_BYTES} read",
            bytes.len()
        ));
    }
    let reader = |bytes: &[u8]| {
        image::ImageReader::new(Cursor::new(bytes.to_vec()))
            .with_guessed_format()
            .map_err(|e| format!("cannot be read ({e})"))
    };
    let header = reader(bytes)?;
    if header.format().is_none() {
        return Err("is neither a PNG nor a JPEG file".to_owned());
    }
    let (width, height) = header
        .into_dimensions()
        .map_err(|e| format!("its header cannot be read ({e})"))?;
    check_size(width, height)?;
    let mut decoder = reader(bytes)?;
    let mut limits = image::Limits::default();
    limits.max_image_width = Some(width);
    limits.max_image_height = Some(height);
    // RGBA8 plus the decoder's own buffer of at most the same size.
    limits.max_alloc = Some(16 * u64::from(width) * u64::from(height) + (1 << 20));
    decoder.limits(limits);
    let image = decoder
        .decode()
        .map_err(|e| format!("cannot be decoded (truncated or corrupt?): {e}"))?;
    let rgba = image.to_rgba8();
    drop(image);
    Ok(Rgba8 {
        width: rgba.width(),
        height: rgba.height(),
        rgba: rgba.into_raw(),
    })
}

fn check_size(width: u32, height: u32) -> Result<(), String> {
    if width == 0 || height == 0 {
        return Err(format!("its header declares {width} × {height} texels"));
    }
    if width > MAX_TEXTURE_SIZE || height > MAX_TEXTURE_SIZE {
        return Err(format!(
            "its header declares {width} × {height} texels, more than {MAX_TEXTURE_SIZE} on a side; \
             not decoded"
        ));
    }
    if u64::from(width) * u64::from(height) > MAX_TEXTURE_TEXELS {
        return Err(format!(
            "its header declares {width} × {height} texels, more than the {MAX_TEXTURE_TEXELS} \
             (4096²) read; not decoded (scale it down)"
        ));
    }
    Ok(())
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::scene::{load_scene, ImportOptions};
    use glam::DVec3;

    /// A PNG of `w` × `h` RGB texels, texel (x, y) = `code(x, y)` grey.
    pub(crate) fn png(w: u32, h: u32, code: impl Fn(u32, u32) -> u8) -> Vec<u8> {
        let image = image::RgbImage::from_fn(w, h, |x, y| image::Rgb([code(x, y); 3]));
        let mut bytes = Vec::new();
        image
            .write_to(&mut Cursor::new(&mut bytes), image::ImageFormat::Png)
            .unwrap();
        bytes
    }

    /// A PNG whose IHDR declares `w` × `h` texels, with a one-byte IDAT: 57
    /// bytes in all.
    fn lying_png(w: u32, h: u32) -> Vec<u8> {
        let chunk = |kind: &[u8], data: &[u8]| {
            let mut out = (data.len() as u32).to_be_bytes().to_vec();
            out.extend_from_slice(kind);
            out.extend_from_slice(data);
            let mut crc = crc32fast::Hasher::new();
            crc.update(kind);
            crc.update(data);
            out.extend(crc.finalize().to_be_bytes());
            out
        };
        let mut ihdr = w.to_be_bytes().to_vec();
        ihdr.extend(h.to_be_bytes());
        ihdr.extend([8, 2, 0, 0, 0]); // 8-bit RGB, deflate, no filter, no interlace
        let mut out = vec![0x89, b'P', b'N', b'G', b'\r', b'\n', 0x1A, b'\n'];
        out.extend(chunk(b"IHDR", &ihdr));
        out.extend(chunk(b"IDAT", &[0]));
        out.extend(chunk(b"IEND", &[]));
        out
    }

    fn load(path: &Path) -> (Option<Arc<SceneTexture>>, Vec<Warning>) {
        let mut warnings = Vec::new();
        let t = load_texture(path, None, &SourceRef::default(), "map_Kd", &mut warnings);
        (t, warnings)
    }

    #[test]
    fn a_png_and_a_jpeg_decode_to_linear_texels() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("half.png");
        std::fs::write(&path, png(4, 2, |x, _| if x < 2 { 128 } else { 255 })).unwrap();
        let (t, warnings) = load(&path);
        let t = t.unwrap();
        assert!(warnings.is_empty(), "{warnings:?}");
        assert_eq!((t.width, t.height, t.rgba.len()), (4, 2, 32));
        // The mean of the linear values, (0.2159 + 1) / 2, not of the codes.
        assert!(
            (t.texture.mean().x - 0.607_93).abs() < 1e-4,
            "{}",
            t.texture.mean()
        );
        // JPEG is lossy: a uniform grey 128 comes back within a code or two.
        let jpeg = dir.path().join("grey.jpg");
        image::RgbImage::from_pixel(16, 16, image::Rgb([128; 3]))
            .save(&jpeg)
            .unwrap();
        let (t, warnings) = load(&jpeg);
        assert!(warnings.is_empty(), "{warnings:?}");
        assert!((t.unwrap().texture.mean().x - 0.2159).abs() < 0.01);
    }

    #[test]
    fn bad_texture_files_warn_naming_the_file_and_give_no_texture() {
        let dir = tempfile::tempdir().unwrap();
        let good = png(64, 64, |x, y| ((x * 7 + y * 13) % 256) as u8);
        let cases: Vec<(&str, Vec<u8>, &str)> = vec![
            (
                "truncated.png",
                good[..good.len() / 2].to_vec(),
                "cannot be decoded",
            ),
            ("huge.png", lying_png(65535, 65535), "65535 × 65535"),
            ("wide.png", lying_png(5000, 4000), "4096²"),
            (
                "text.png",
                b"not an image at all".to_vec(),
                "neither a PNG nor a JPEG",
            ),
        ];
        for (name, bytes, words) in cases {
            let path = dir.path().join(name);
            std::fs::write(&path, &bytes).unwrap();
            let (t, warnings) = load(&path);
            assert!(t.is_none(), "{name}");
            assert_eq!(warnings.len(), 1, "{name}: {warnings:?}");
            let message = &warnings[0].message;
            assert!(
                message.contains(name) && message.contains(words),
                "{message}"
            );
            assert!(message.ends_with("the flat Kd is used"), "{message}");
        }
        let (t, warnings) = load(&dir.path().join("missing.png"));
        assert!(t.is_none());
        assert!(
            warnings[0].message.contains("missing.png: cannot be read"),
            "{warnings:?}"
        );
    }

    /// A texture named with the wrong letter case (Sponza's MTL names
    /// `SP_LUK.JPG` for `sp_luk.JPG`) is read, with a warning naming both
    /// spellings, through an MTL and a glTF `uri` alike; two files that differ
    /// only in case are refused, both named.
    #[test]
    fn a_texture_named_in_the_wrong_case_is_found_in_its_folder() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("sp_luk.png"), png(2, 2, |_, _| 128)).unwrap();
        let (t, warnings) = load(&dir.path().join("SP_LUK.PNG"));
        assert!(t.is_some(), "{warnings:?}");
        assert_eq!(warnings.len(), 1, "{warnings:?}");
        let message = &warnings[0].message;
        assert!(
            message.contains("SP_LUK.PNG: no file has that name")
                && message.contains("sp_luk.png differs from it only in letter case"),
            "{message}"
        );
        // The texture read is the file's, under its own name.
        assert!((t.unwrap().texture.mean().x - 0.2159).abs() < 1e-3);

        // Through an MTL: the material is textured, and the warning says so.
        std::fs::write(
            dir.path().join("s.mtl"),
            "newmtl floor\nKd 1 1 1\nmap_Kd SP_LUK.PNG\nnewmtl light\nKe 1 1 1\n",
        )
        .unwrap();
        let obj = "mtllib s.mtl\nv 0 0 0\nv 2 0 0\nv 2 0 -1\nv 0 0 -1\n\
                   v 0 1 0\nv 1 1 0\nv 1 1 -1\nv 0 1 -1\n\
                   vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n\
                   usemtl floor\nf 1/1 2/2 3/3 4/4\nusemtl light\nf 5 8 7 6\n";
        let path = dir.path().join("s.obj");
        std::fs::write(&path, obj).unwrap();
        let scene = load_scene(&path, &ImportOptions::default()).unwrap().scene;
        let floor = &scene.materials[scene.polygons[0].material];
        assert!(floor.diffuse_texture.is_some(), "{:?}", scene.warnings);
        assert!(
            scene
                .warnings
                .iter()
                .any(|w| w.message.contains("only in letter case")),
            "{:?}",
            scene.warnings
        );

        // Two candidates: refused, both named, and the flat Kd is used.
        std::fs::write(dir.path().join("Sp_Luk.png"), png(2, 2, |_, _| 255)).unwrap();
        let (t, warnings) = load(&dir.path().join("SP_LUK.PNG"));
        assert!(t.is_none());
        assert_eq!(warnings.len(), 1, "{warnings:?}");
        let message = &warnings[0].message;
        assert!(
            message.contains("2 files differ from it only in letter case")
                && message.contains("Sp_Luk.png")
                && message.contains("sp_luk.png")
                && message.ends_with("the flat Kd is used"),
            "{message}"
        );
    }

    #[test]
    fn an_obj_with_vt_and_map_kd_imports_textured() {
        // A floor quad mapped onto a 2 × 2 texture and a light; the OBJ writes
        // UVs that are an affine image of the quad, so the fit is exact.
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(
            dir.path().join("t.png"),
            png(2, 2, |x, _| [60, 250][x as usize]),
        )
        .unwrap();
        std::fs::write(
            dir.path().join("s.mtl"),
            "newmtl floor\nKd 0.5 0.5 0.5\nmap_Kd t.png\nnewmtl dark\nKd 0.01\nmap_Kd t.png\n\
             newmtl gone\nKd 0.7\nmap_Kd absent.png\nnewmtl light\nKe 1 1 1\n",
        )
        .unwrap();
        let obj = "mtllib s.mtl\nv 0 0 0\nv 2 0 0\nv 2 0 -1\nv 0 0 -1\n\
                   v 0 1 0\nv 1 1 0\nv 1 1 -1\nv 0 1 -1\n\
                   vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n\
                   usemtl floor\nf 1/1 2/2 3/3 4/4\nusemtl dark\nf 1/1 2/2 3/3 4/4\n\
                   usemtl gone\nf 1/1 2/2 3/3 4/4\nusemtl light\nf 5 8 7 6\n";
        let path = dir.path().join("s.obj");
        std::fs::write(&path, obj).unwrap();
        let scene = load_scene(&path, &ImportOptions::default()).unwrap().scene;
        let floor = &scene.polygons[0];
        let map = floor.uv_map.unwrap();
        // Corner 3 (2, 0, −1), re-centred, has UV (1, 1).
        let corner = DVec3::new(2.0, 0.0, -1.0) - scene.recentre_offset;
        assert!((map.at(corner) - glam::DVec2::ONE).length() < 1e-12);
        let material = &scene.materials[floor.material];
        assert!(material.diffuse_texture.is_some());
        // Kd ⊙ texture: texel (1, *) (centre u = 0.75) is code 250, 0.956
        // linear, times 0.5.
        let kd = material.kd_at(Some(glam::DVec2::new(0.75, 0.5)));
        assert!((kd.x - 0.5 * 0.9560).abs() < 1e-3, "{kd}");
        let warned = |words: &str| scene.warnings.iter().any(|w| w.message.contains(words));
        assert!(warned("very dark reflectance"), "{:?}", scene.warnings);
        assert!(warned("absent.png: cannot be read"), "{:?}", scene.warnings);
        assert!(!warned("not yet modelled"), "{:?}", scene.warnings);
    }

    /// `map_Ke` through the same reader: Le = Ke ⊙ texture(uv), decoded from
    /// sRGB; a missing file or a material without `vt` warns (naming the
    /// file) and keeps the flat Ke.
    #[test]
    fn an_obj_with_map_ke_imports_an_emission_texture_or_warns_and_keeps_flat_ke() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(
            dir.path().join("e.png"),
            png(2, 1, |x, _| [128, 255][x as usize]),
        )
        .unwrap();
        std::fs::write(
            dir.path().join("s.mtl"),
            "newmtl screen\nKe 2 2 2\nmap_Ke e.png\nnewmtl lost\nKe 3 3 3\nmap_Ke nowhere.png\n\
             newmtl bare\nKe 4 4 4\nmap_Ke e.png\nnewmtl floor\nKd 0.5\n",
        )
        .unwrap();
        let obj = "mtllib s.mtl\nv 0 0 0\nv 2 0 0\nv 2 0 -1\nv 0 0 -1\n\
                   vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n\
                   usemtl screen\nf 1/1 2/2 3/3 4/4\nusemtl lost\nf 1/1 2/2 3/3 4/4\n\
                   usemtl bare\nf 1 2 3 4\nusemtl floor\nf 4 3 2 1\n";
        let path = dir.path().join("s.obj");
        std::fs::write(&path, obj).unwrap();
        let scene = load_scene(&path, &ImportOptions::default()).unwrap().scene;
        let material = |name: &str| scene.materials.iter().find(|m| m.name == name).unwrap();
        let screen = material("screen");
        assert!(screen.emission_texture.is_some());
        // Texel 0 (u = 0.25) is code 128: 2 × 0.2159 (IEC 61966-2-1), not 2 × 0.502.
        let le = screen.emission_at(Some(glam::DVec2::new(0.25, 0.5)));
        assert!((le.x - 2.0 * 0.215_86).abs() < 1e-4, "{le}");
        let le = screen.emission_at(Some(glam::DVec2::new(0.75, 0.5)));
        assert!((le.x - 2.0).abs() < 1e-12, "{le}");
        for (name, flat) in [("lost", 3.0), ("bare", 4.0)] {
            let m = material(name);
            assert!(m.emission_texture.is_none(), "{name}");
            assert_eq!(m.emission_at(Some(glam::DVec2::ZERO)), DVec3::splat(flat));
        }
        let warned = |words: &[&str]| {
            scene
                .warnings
                .iter()
                .any(|w| words.iter().all(|k| w.to_string().contains(k)))
        };
        assert!(
            warned(&[
                "s.mtl:6",
                "map_Ke texture",
                "nowhere.png: cannot be read",
                "flat Ke"
            ]),
            "{:?}",
            scene.warnings
        );
        assert!(
            warned(&[
                "s.mtl:9",
                "map_Ke texture",
                "texture coordinates",
                "flat Ke"
            ]),
            "{:?}",
            scene.warnings
        );
    }
}
