//! Image files, written atomically (temporary file in the same folder, then
//! rename), so an interrupted write never leaves a half file under the final name.

use anyhow::{Context, Result};
use std::path::{Path, PathBuf};

fn temp_path(path: &Path) -> PathBuf {
    let mut name = path
        .file_name()
        .map(|n| n.to_os_string())
        .unwrap_or_default();
    name.push(format!(".tmp-{}", std::process::id()));
    path.with_file_name(name)
}

fn commit(tmp: &Path, path: &Path, result: Result<()>) -> Result<()> {
    match result {
        Ok(()) => std::fs::rename(tmp, path)
            .with_context(|| format!("cannot rename {} to {}", tmp.display(), path.display())),
        Err(e) => {
            let _ = std::fs::remove_file(tmp);
            Err(e)
        }
    }
}

/// Writes 8-bit sRGB RGBA pixels (row 0 at the top) as an RGB PNG.
pub fn write_png(path: &Path, width: u32, height: u32, rgba: &[u8]) -> Result<()> {
    let rgb: Vec<u8> = rgba
        .chunks_exact(4)
        .flat_map(|p| [p[0], p[1], p[2]])
        .collect();
    let image = image::RgbImage::from_raw(width, height, rgb)
        .context("image buffer does not match its size")?;
    let tmp = temp_path(path);
    let result = image
        .save_with_format(&tmp, image::ImageFormat::Png)
        .with_context(|| format!("cannot write {}", path.display()));
    commit(&tmp, path, result)
}

/// Writes linear RGB radiance (f32, row 0 at the top) as an OpenEXR file.
pub fn write_exr(path: &Path, width: u32, height: u32, rgb: &[f32]) -> Result<()> {
    anyhow::ensure!(
        rgb.len() == width as usize * height as usize * 3,
        "radiance buffer does not match its size"
    );
    let tmp = temp_path(path);
    let w = width as usize;
    let result = exr::prelude::write_rgb_file(&tmp, w, height as usize, |x, y| {
        let i = (y * w + x) * 3;
        (rgb[i], rgb[i + 1], rgb[i + 2])
    })
    .with_context(|| format!("cannot write {}", path.display()));
    commit(&tmp, path, result)
}
