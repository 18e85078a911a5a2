//! Image files, written through the contract crate's one atomic writer
//! ([`solution::atomic::write_atomically`]: temporary file in the same folder,
//! fsync, rename, directory fsync), so an interrupted write never leaves a half
//! file under the final name.

use anyhow::{Context, Result};
use std::path::Path;

/// Writes 8-bit sRGB RGBA pixels (row 0 at the top) as an RGB PNG.
pub fn write_png(path: &Path, width: u32, height: u32, rgba: &[u8]) -> Result<()> {
    let rgb: Vec<u8> = rgba
        .chunks_exact(4)
        .flat_map(|p| [p[0], p[1], p[2]])
        .collect();
    let image = image::RgbImage::from_raw(width, height, rgb)
        .context("image buffer does not match its size")?;
    solution::atomic::write_atomically(path, |file| {
        let mut writer = std::io::BufWriter::new(file);
        image
            .write_to(&mut writer, image::ImageFormat::Png)
            .map_err(std::io::Error::other)?;
        std::io::Write::flush(&mut writer)
    })
    .with_context(|| format!("cannot write {}", path.display()))
}

/// Writes linear RGB radiance (f32, row 0 at the top) as an OpenEXR file.
pub fn write_exr(path: &Path, width: u32, height: u32, rgb: &[f32]) -> Result<()> {
    use exr::prelude::{Image, SpecificChannels, Vec2, WritableImage};
    anyhow::ensure!(
        rgb.len() == width as usize * height as usize * 3,
        "radiance buffer does not match its size"
    );
    let w = width as usize;
    let channels = SpecificChannels::rgb(|Vec2(x, y): Vec2<usize>| {
        let i = (y * w + x) * 3;
        (rgb[i], rgb[i + 1], rgb[i + 2])
    });
    let image = Image::from_channels((w, height as usize), channels);
    solution::atomic::write_atomically(path, |file| {
        image
            .write()
            .to_unbuffered(file)
            .map_err(std::io::Error::other)
    })
    .with_context(|| format!("cannot write {}", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names(dir: &Path) -> Vec<String> {
        let mut names: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    }

    #[test]
    fn png_and_exr_read_back_and_leave_no_temporary() {
        let dir = tempfile::tempdir().unwrap();
        let png = dir.path().join("a.png");
        let rgba = [255, 0, 0, 255, 0, 128, 255, 255];
        write_png(&png, 2, 1, &rgba).unwrap();
        let back = image::open(&png).unwrap().to_rgb8();
        assert_eq!(back.as_raw(), &vec![255, 0, 0, 0, 128, 255]);
        let exr_path = dir.path().join("a.exr");
        let rgb = [0.25f32, 0.5, 1.0, 2.0, 4.0, 8.0];
        write_exr(&exr_path, 2, 1, &rgb).unwrap();
        let read = exr::prelude::read_first_rgba_layer_from_file(
            &exr_path,
            |size, _| vec![[0f32; 3]; size.0 * size.1],
            |pixels, pos, (r, g, b, _a): (f32, f32, f32, f32)| {
                pixels[pos.1 * 2 + pos.0] = [r, g, b]
            },
        )
        .unwrap();
        assert_eq!(
            read.layer_data.channel_data.pixels,
            vec![[0.25, 0.5, 1.0], [2.0, 4.0, 8.0]]
        );
        assert_eq!(names(dir.path()), ["a.exr", "a.png"]);
    }

    #[test]
    fn a_failed_write_keeps_the_old_file() {
        let dir = tempfile::tempdir().unwrap();
        let png = dir.path().join("a.png");
        std::fs::write(&png, b"old").unwrap();
        // A buffer that does not match its size is refused before anything is written.
        assert!(write_png(&png, 3, 3, &[0; 4]).is_err());
        assert!(write_exr(&png, 3, 3, &[0.0; 3]).is_err());
        assert_eq!(std::fs::read(&png).unwrap(), b"old");
        assert_eq!(names(dir.path()), ["a.png"]);
    }
}
