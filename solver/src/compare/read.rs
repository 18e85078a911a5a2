//! Reading images for `solver compare`: OpenEXR (through the `exr` crate) and
//! NumPy `.npy` float32 H×W×3 arrays (through [`super::npy`]). The format is told
//! by the file's magic bytes, not its name. Every error names the file.

use super::image::{IdChannel, Image, LoadedImage};
use super::npy::{read_npy, NpyError};
use std::collections::HashMap;
use std::io::Read;
use std::path::{Path, PathBuf};

/// The largest image accepted, in pixels (8192 × 8192). The EXR header's declared
/// size is checked against it before any pixel is decoded, because a compressed
/// file can declare far more pixels than its bytes suggest.
pub const MAX_PIXELS: usize = 8192 * 8192;

const EXR_MAGIC: [u8; 4] = [0x76, 0x2f, 0x31, 0x01];
const NPY_MAGIC: &[u8; 6] = b"\x93NUMPY";

/// Why an image file could not be read.
#[derive(Debug, thiserror::Error)]
pub enum ReadError {
    #[error("cannot read {}: {source}", path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{}: neither an OpenEXR nor a .npy file (unknown magic bytes)", path.display())]
    UnknownFormat { path: PathBuf },
    #[error("{}: {source}", path.display())]
    Npy { path: PathBuf, source: NpyError },
    #[error("{}: the array has shape {shape:?}; an image must be (height, width, 3)", path.display())]
    NpyShape { path: PathBuf, shape: Vec<usize> },
    #[error("{}: invalid OpenEXR file: {source}", path.display())]
    Exr {
        path: PathBuf,
        source: exr::error::Error,
    },
    #[error("{}: image is {width}×{height}, more than the {MAX_PIXELS}-pixel limit", path.display())]
    TooLarge {
        path: PathBuf,
        width: usize,
        height: usize,
    },
    #[error("{}: image has no pixels ({width}×{height})", path.display())]
    Empty {
        path: PathBuf,
        width: usize,
        height: usize,
    },
    #[error("{}: OpenEXR file lacks the channel '{channel}' (it has: {present})", path.display())]
    MissingChannel {
        path: PathBuf,
        channel: String,
        present: String,
    },
    #[error("{}: channel '{channel}' is {actual:?} but 'R' is {expected:?}", path.display())]
    ChannelSize {
        path: PathBuf,
        channel: String,
        expected: (usize, usize),
        actual: (usize, usize),
    },
    #[error("{}: channel '{channel}' at pixel ({x}, {y}) holds {value}, not an integer index ≥ −1", path.display())]
    BadId {
        path: PathBuf,
        channel: String,
        x: usize,
        y: usize,
        value: f32,
    },
    #[error("{}: header attribute '{attribute}' is not a JSON array of strings: {reason}", path.display())]
    BadNames {
        path: PathBuf,
        attribute: String,
        reason: String,
    },
}

/// Reads an OpenEXR or `.npy` image, with any reference channels it carries.
pub fn read_image(path: &Path) -> Result<LoadedImage, ReadError> {
    let io = |source| ReadError::Io {
        path: path.to_path_buf(),
        source,
    };
    #[allow(clippy::disallowed_methods)] // An edge: `solver compare` reads the images it is given.
    let mut file = std::fs::File::open(path).map_err(io)?;
    let len = file.metadata().map_err(io)?.len();
    let mut magic = [0u8; 6];
    let got = read_up_to(&mut file, &mut magic).map_err(io)?;
    drop(file);
    if got >= 4 && magic[..4] == EXR_MAGIC {
        read_exr(path)
    } else if got == 6 && &magic == NPY_MAGIC {
        #[allow(clippy::disallowed_methods)]
        // An edge: `solver compare` reads the images it is given.
        let file = std::fs::File::open(path).map_err(io)?;
        read_npy_image(path, std::io::BufReader::new(file), len).map(LoadedImage::plain)
    } else {
        Err(ReadError::UnknownFormat {
            path: path.to_path_buf(),
        })
    }
}

fn read_up_to(reader: &mut impl Read, buf: &mut [u8]) -> std::io::Result<usize> {
    let mut got = 0;
    while got < buf.len() {
        match reader.read(&mut buf[got..])? {
            0 => break,
            n => got += n,
        }
    }
    Ok(got)
}

/// Reads a `.npy` stream as an image: float32, shape (height, width, 3).
pub fn read_npy_image(path: &Path, reader: impl Read, len: u64) -> Result<Image, ReadError> {
    let array = read_npy(reader, len).map_err(|source| ReadError::Npy {
        path: path.to_path_buf(),
        source,
    })?;
    let &[height, width, 3] = array.shape.as_slice() else {
        return Err(ReadError::NpyShape {
            path: path.to_path_buf(),
            shape: array.shape,
        });
    };
    check_size(path, width, height)?;
    Ok(Image {
        width,
        height,
        rgb: array.data,
    })
}

fn check_size(path: &Path, width: usize, height: usize) -> Result<(), ReadError> {
    if width == 0 || height == 0 {
        return Err(ReadError::Empty {
            path: path.to_path_buf(),
            width,
            height,
        });
    }
    if width.saturating_mul(height) > MAX_PIXELS {
        return Err(ReadError::TooLarge {
            path: path.to_path_buf(),
            width,
            height,
        });
    }
    Ok(())
}

/// One decoded channel: its size and values (row 0 at the top).
struct Channel {
    size: (usize, usize),
    values: Vec<f32>,
}

/// Reads an OpenEXR file: `R`, `G`, `B` are required; `se.R`, `se.G`, `se.B`,
/// `material_id`, `object_id` and the text attributes `materials`, `objects`
/// (JSON arrays of names) are read where present. Channels of every layer are
/// looked up by their full name (`layer.channel` in a named layer).
fn read_exr(path: &Path) -> Result<LoadedImage, ReadError> {
    let exr_error = |source| ReadError::Exr {
        path: path.to_path_buf(),
        source,
    };
    #[allow(clippy::disallowed_methods)] // An edge: `solver compare` reads the images it is given.
    let meta = exr::meta::MetaData::read_from_file(path, false).map_err(exr_error)?;
    for header in meta.headers.iter() {
        check_size(path, header.layer_size.x(), header.layer_size.y())?;
    }
    use exr::prelude::{ReadChannels, ReadLayers};
    #[allow(clippy::disallowed_methods)] // An edge: `solver compare` reads the images it is given.
    let image = exr::prelude::read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .all_layers()
        .all_attributes()
        .from_file(path)
        .map_err(exr_error)?;

    let mut channels: HashMap<String, Channel> = HashMap::new();
    let mut texts: HashMap<String, String> = HashMap::new();
    collect_texts(&image.attributes.other, &mut texts);
    for layer in &image.layer_data {
        collect_texts(&layer.attributes.other, &mut texts);
        let prefix = match &layer.attributes.layer_name {
            Some(name) => format!("{name}."),
            None => String::new(),
        };
        for channel in &layer.channel_data.list {
            channels.insert(
                format!("{prefix}{}", channel.name),
                Channel {
                    size: (layer.size.x(), layer.size.y()),
                    values: channel.sample_data.values_as_f32().collect(),
                },
            );
        }
    }

    let take =
        |name: &str| -> Result<Option<Vec<f32>>, ReadError> { take_channel(path, &channels, name) };
    let present = || {
        let mut names: Vec<&str> = channels.keys().map(String::as_str).collect();
        names.sort_unstable();
        names.join(", ")
    };
    let mut rgb_planes = Vec::with_capacity(3);
    for name in ["R", "G", "B"] {
        let plane = take(name)?.ok_or_else(|| ReadError::MissingChannel {
            path: path.to_path_buf(),
            channel: name.into(),
            present: present(),
        })?;
        rgb_planes.push(plane);
    }
    let (width, height) = channels["R"].size;
    let image = Image {
        width,
        height,
        rgb: interleave(&rgb_planes),
    };

    let se_planes = [take("se.R")?, take("se.G")?, take("se.B")?];
    let standard_error = match se_planes {
        [Some(r), Some(g), Some(b)] => Some(interleave(&[r, g, b])),
        _ => None,
    };
    let ids = |channel: &str, attribute: &str| -> Result<Option<IdChannel>, ReadError> {
        let Some(values) = take(channel)? else {
            return Ok(None);
        };
        let ids = to_ids(path, channel, width, &values)?;
        let names = match texts.get(attribute) {
            Some(text) => parse_names(path, attribute, text)?,
            None => Vec::new(),
        };
        Ok(Some(IdChannel { ids, names }))
    };
    Ok(LoadedImage {
        material_id: ids("material_id", "materials")?,
        object_id: ids("object_id", "objects")?,
        standard_error,
        image,
    })
}

fn collect_texts(
    attributes: &HashMap<exr::meta::attribute::Text, exr::meta::attribute::AttributeValue>,
    texts: &mut HashMap<String, String>,
) {
    for (name, value) in attributes {
        if let exr::meta::attribute::AttributeValue::Text(text) = value {
            texts.insert(name.to_string(), text.to_string());
        }
    }
}

/// A channel's values, checked to be the size of `R`.
fn take_channel(
    path: &Path,
    channels: &HashMap<String, Channel>,
    name: &str,
) -> Result<Option<Vec<f32>>, ReadError> {
    let Some(channel) = channels.get(name) else {
        return Ok(None);
    };
    if let Some(r) = channels.get("R") {
        if r.size != channel.size {
            return Err(ReadError::ChannelSize {
                path: path.to_path_buf(),
                channel: name.into(),
                expected: r.size,
                actual: channel.size,
            });
        }
    }
    Ok(Some(channel.values.clone()))
}

fn interleave(planes: &[Vec<f32>]) -> Vec<f32> {
    let n = planes[0].len();
    (0..n)
        .flat_map(|i| planes.iter().map(move |p| p[i]))
        .collect()
}

/// Converts an id channel (f32 holding integers, −1 for no hit) to indices.
fn to_ids(path: &Path, channel: &str, width: usize, values: &[f32]) -> Result<Vec<i32>, ReadError> {
    // f32 holds every integer up to 2^24 exactly; beyond it an index is ambiguous.
    const LARGEST: f32 = (1 << 24) as f32;
    values
        .iter()
        .enumerate()
        .map(|(i, &v)| {
            if v.fract() == 0.0 && (-1.0..=LARGEST).contains(&v) {
                Ok(v as i32)
            } else {
                Err(ReadError::BadId {
                    path: path.to_path_buf(),
                    channel: channel.into(),
                    x: i % width,
                    y: i / width,
                    value: v,
                })
            }
        })
        .collect()
}

fn parse_names(path: &Path, attribute: &str, text: &str) -> Result<Vec<String>, ReadError> {
    serde_json::from_str::<Vec<String>>(text).map_err(|e| ReadError::BadNames {
        path: path.to_path_buf(),
        attribute: attribute.into(),
        reason: e.to_string(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use exr::prelude::*;

    /// Writes `rgb` exactly as `runtime screenshot` does (runtime/src/cli/output.rs,
    /// `write_exr`): `exr::prelude::write_rgb_file` with f32 R, G, B.
    fn write_like_runtime(path: &Path, width: usize, height: usize, rgb: &[f32]) {
        write_rgb_file(path, width, height, |x, y| {
            let i = (y * width + x) * 3;
            (rgb[i], rgb[i + 1], rgb[i + 2])
        })
        .unwrap();
    }

    /// Writes an EXR in the reference path tracer's contract: R, G, B, se.R, se.G,
    /// se.B, material_id, object_id, and the `materials` / `objects` attributes.
    fn write_reference(
        path: &Path,
        width: usize,
        height: usize,
        channels: &[(&str, Vec<f32>)],
        attributes: &[(&str, &str)],
    ) {
        let list = channels
            .iter()
            .map(|(name, values)| AnyChannel::new(*name, FlatSamples::F32(values.clone())))
            .collect();
        let mut layer_attributes = LayerAttributes::default();
        for (name, text) in attributes {
            layer_attributes
                .other
                .insert(Text::from(*name), AttributeValue::Text(Text::from(*text)));
        }
        let layer = Layer::new(
            (width, height),
            layer_attributes,
            Encoding::FAST_LOSSLESS,
            AnyChannels::sort(list),
        );
        exr::prelude::Image::from_layer(layer)
            .write()
            .to_file(path)
            .unwrap();
    }

    fn ramp(n: usize, scale: f32) -> Vec<f32> {
        (0..n).map(|i| scale * (i as f32 + 0.5)).collect()
    }

    #[test]
    fn reads_the_runtime_screenshot_exr_exactly() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("shot.exr");
        let (w, h) = (5, 3);
        let rgb = ramp(w * h * 3, 0.37);
        write_like_runtime(&path, w, h, &rgb);
        let loaded = read_image(&path).unwrap();
        assert_eq!((loaded.image.width, loaded.image.height), (w, h));
        // f32 channels round-trip bit for bit; row 0 is the top row on both sides.
        assert_eq!(loaded.image.rgb, rgb);
        assert!(loaded.standard_error.is_none() && loaded.material_id.is_none());
    }

    #[test]
    fn reads_the_reference_contract() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("truth.exr");
        let (w, h) = (4, 2);
        let n = w * h;
        let channels = [
            ("R", ramp(n, 1.0)),
            ("G", ramp(n, 2.0)),
            ("B", ramp(n, 3.0)),
            ("se.R", ramp(n, 0.1)),
            ("se.G", ramp(n, 0.2)),
            ("se.B", ramp(n, 0.3)),
            ("material_id", vec![0.0, 0.0, 1.0, 1.0, -1.0, 2.0, 2.0, 0.0]),
            ("object_id", vec![3.0; n]),
        ];
        write_reference(
            &path,
            w,
            h,
            &channels,
            &[
                ("materials", r#"["white", "red", "lamp"]"#),
                ("objects", "[]"),
            ],
        );
        let loaded = read_image(&path).unwrap();
        assert_eq!(&loaded.image.rgb[..6], &[0.5, 1.0, 1.5, 1.5, 3.0, 4.5]);
        let se = loaded.standard_error.unwrap();
        assert!((se[3] - 0.15).abs() < 1e-7 && (se[5] - 0.45).abs() < 1e-7);
        let materials = loaded.material_id.unwrap();
        assert_eq!(materials.ids, vec![0, 0, 1, 1, -1, 2, 2, 0]);
        assert_eq!(materials.names, vec!["white", "red", "lamp"]);
        assert_eq!(materials.name(-1), "(no hit)");
        let objects = loaded.object_id.unwrap();
        assert_eq!(objects.name(3), "#3");
    }

    #[test]
    fn bad_exr_contents_are_refused_with_the_file_name() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("bad.exr");
        let n = 4;
        let rgb = || {
            vec![
                ("R", vec![1.0; n]),
                ("G", vec![1.0; n]),
                ("B", vec![1.0; n]),
            ]
        };
        let mut channels = rgb();
        channels.push(("material_id", vec![0.0, 0.5, 1.0, 1.0]));
        write_reference(&path, 2, 2, &channels, &[]);
        let err = read_image(&path).unwrap_err();
        assert!(matches!(err, ReadError::BadId { x: 1, y: 0, .. }), "{err}");
        assert!(err.to_string().contains("bad.exr"));

        let mut channels = rgb();
        channels.push(("object_id", vec![0.0; n]));
        write_reference(&path, 2, 2, &channels, &[("objects", "{not json")]);
        assert!(matches!(read_image(&path), Err(ReadError::BadNames { .. })));

        write_reference(
            &path,
            2,
            2,
            &[("R", vec![1.0; n]), ("B", vec![1.0; n])],
            &[],
        );
        let err = read_image(&path).unwrap_err();
        assert!(
            matches!(&err, ReadError::MissingChannel { channel, .. } if channel == "G"),
            "{err}"
        );

        // A truncated file is an error, not a panic.
        write_like_runtime(&path, 8, 8, &[0.25; 192]);
        let bytes = std::fs::read(&path).unwrap();
        for cut in [4, 40, bytes.len() / 2, bytes.len() - 3] {
            std::fs::write(&path, &bytes[..cut]).unwrap();
            assert!(read_image(&path).is_err(), "cut at {cut}");
        }
    }

    #[test]
    fn npy_images_need_three_channels_and_unknown_files_are_named() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.npy");
        let mut bytes = Vec::new();
        crate::compare::npy::write_npy(&mut bytes, &[2, 3, 3], &ramp(18, 1.0)).unwrap();
        std::fs::write(&path, &bytes).unwrap();
        let image = read_image(&path).unwrap().image;
        assert_eq!((image.width, image.height), (3, 2));
        assert_eq!(image.rgb[17], 17.5);

        bytes.clear();
        crate::compare::npy::write_npy(&mut bytes, &[2, 3, 4], &ramp(24, 1.0)).unwrap();
        std::fs::write(&path, &bytes).unwrap();
        assert!(matches!(read_image(&path), Err(ReadError::NpyShape { .. })));
        bytes.clear();
        crate::compare::npy::write_npy(&mut bytes, &[0, 3, 3], &[]).unwrap();
        std::fs::write(&path, &bytes).unwrap();
        assert!(matches!(read_image(&path), Err(ReadError::Empty { .. })));

        std::fs::write(&path, b"P6\n2 2\n255\n").unwrap();
        let err = read_image(&path).unwrap_err();
        assert!(
            matches!(err, ReadError::UnknownFormat { .. }) && err.to_string().contains("a.npy")
        );
        let missing = dir.path().join("missing.exr");
        assert!(read_image(&missing)
            .unwrap_err()
            .to_string()
            .contains("missing.exr"));
    }
}
