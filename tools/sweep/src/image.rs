//! Reading the runtime's linear-radiance EXR screenshots.

use anyhow::Context;
use std::path::Path;

/// A linear RGB image as f64 values, row-major, three per pixel.
#[derive(Clone, Debug, PartialEq)]
pub struct RgbImage {
    pub width: usize,
    pub height: usize,
    pub values: Vec<f64>,
}

/// Reads the first RGB(A) layer of an EXR file (alpha, if any, is ignored).
pub fn read_exr(path: &Path) -> anyhow::Result<RgbImage> {
    use exr::prelude::*;
    let image = read_first_rgba_layer_from_file(
        path,
        |resolution, _channels| {
            (
                resolution.width(),
                vec![0.0f64; resolution.width() * resolution.height() * 3],
            )
        },
        |(width, values): &mut (usize, Vec<f64>), position, (r, g, b, _a): (f32, f32, f32, f32)| {
            let k = (position.y() * *width + position.x()) * 3;
            values[k] = r as f64;
            values[k + 1] = g as f64;
            values[k + 2] = b as f64;
        },
    )
    .with_context(|| format!("reading EXR {}", path.display()))?;
    let size = image.layer_data.size;
    let (_, values) = image.layer_data.channel_data.pixels;
    Ok(RgbImage {
        width: size.width(),
        height: size.height(),
        values,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_back_what_exr_wrote() {
        let dir = std::env::temp_dir().join(format!("sweep-exr-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("t.exr");
        // 3 × 2 pixels, each channel a distinct value exactly representable in f32.
        exr::prelude::write_rgb_file(&path, 3, 2, |x, y| {
            let base = (y * 3 + x) as f32;
            (base, base + 0.25, base + 0.5)
        })
        .unwrap();
        let image = read_exr(&path).unwrap();
        assert_eq!((image.width, image.height), (3, 2));
        assert_eq!(&image.values[..6], &[0.0, 0.25, 0.5, 1.0, 1.25, 1.5]);
        assert_eq!(image.values[5 * 3 + 2], 5.5);
        std::fs::remove_dir_all(&dir).ok();
        assert!(read_exr(&path).is_err());
    }
}
