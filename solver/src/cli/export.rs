//! `solver export SOLUTION -o OUT.glb|OUT.gltf`: a solution file as glTF 2.0
//! for any glTF viewer or engine (`crate::export` builds it; docs/gltf.md,
//! "Export").

use crate::export::{curve_name, file_name_uri, write_glb, BatchBytes, ExportOptions, Exporter};
use anyhow::{bail, Context, Result};
use solution::atomic::{write_atomically, write_bytes_atomically};
use solution::format::{BatchSection, MappedSolution};
use solution::raster::ToneCurve;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

pub const LONG_ABOUT: &str = "\
Export a solution file as glTF 2.0, for viewing in any glTF viewer or engine and for
reading the radiance back.

Each batch becomes a mesh with, per vertex:
  POSITION   metres, +y up: the stored position plus the header's f64 re-centring
             offset, divided by units_per_metre and rotated from the header's up axis,
             rounded once to f32 (within 2^-24 relative of the exact value)
  NORMAL     the stored normal, rotated the same way
  COLOR_0    linear display value in 0..1: curve(radiance x 2^exposure), the runtime's
             PNG tone map before its sRGB encoding; shown unlit (KHR_materials_unlit,
             white base colour), so a viewer that writes to an sRGB framebuffer with no
             tone map of its own shows the runtime's PNG colours at the vertices
  _RADIANCE  linear radiance, W/(sr m^2) per RGB channel, f32, negative values clamped
             to 0 (for round trips; not exposed, not tone-mapped)
and the header camera as a perspective camera. Diffuse vertices look the same from
everywhere; glossy vertices (SH order >= 1, global cubes) are evaluated toward one eye
(--eye, by default the header camera's), so from the exported camera a viewer matches
the runtime at the vertices. A textured batch (format 2) gets TEXCOORD_0 = (u, 1 - v),
its PNG as a baseColorTexture times its factor, and E/pi (the incident light over pi)
in _RADIANCE and, tone-mapped, in COLOR_0. The file is refused before anything is allocated if it would exceed glTF's
4 GiB limit.";

#[derive(clap::Args, Debug)]
pub struct ExportArgs {
    /// The solution file (.sol); every checksum is verified as it is read.
    pub solution: PathBuf,
    /// Output file: NAME.glb (one binary file) or NAME.gltf (JSON, with its buffer
    /// written beside it as NAME.bin). Written atomically.
    #[arg(short, long, value_name = "OUT")]
    pub out: PathBuf,
    /// Exposure of COLOR_0 in stops: radiance is multiplied by 2^E before the tone
    /// curve, as `runtime screenshot --exposure` does (_RADIANCE is not exposed).
    #[arg(
        long,
        value_name = "E",
        default_value_t = 0.0,
        allow_negative_numbers = true
    )]
    pub exposure: f32,
    /// Tone curve of COLOR_0: clamp (min(x, 1)), reinhard (x/(1+x)) or aces
    /// (Narkowicz's fit), as `runtime screenshot --tonemap`.
    #[arg(long, value_name = "CURVE", default_value = "clamp", value_parser = parse_curve)]
    pub tonemap: ToneCurve,
    /// The point glossy vertices are evaluated toward (original scene coordinates;
    /// default: the header camera's eye). Diffuse vertices do not depend on it; glossy
    /// highlights are baked as seen from here and do not move with the viewer.
    #[arg(long, num_args = 3, value_names = ["X", "Y", "Z"], allow_negative_numbers = true)]
    pub eye: Option<Vec<f64>>,
}

fn parse_curve(text: &str) -> Result<ToneCurve, String> {
    ToneCurve::parse(text).ok_or_else(|| format!("`{text}`: expected clamp, reinhard or aces"))
}

/// Which container the output's extension asks for.
enum Container {
    Glb,
    /// A `.gltf` and its `.bin` (the path given).
    Gltf(PathBuf),
}

fn container(out: &Path) -> Result<Container> {
    let extension = out
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match extension.as_deref() {
        Some("glb") => Ok(Container::Glb),
        Some("gltf") => Ok(Container::Gltf(out.with_extension("bin"))),
        _ => bail!(
            "{}: the output must end in .glb (binary glTF) or .gltf (JSON with a .bin beside it)",
            out.display()
        ),
    }
}

pub fn run(args: ExportArgs) -> Result<ExitCode> {
    let container = container(&args.out)?;
    let glossy_eye = match args.eye.as_deref() {
        None => None,
        Some([x, y, z]) if [x, y, z].iter().all(|v| v.is_finite()) => Some([*x, *y, *z]),
        Some(v) => bail!("--eye {v:?}: three finite coordinates expected"),
    };
    let options = ExportOptions {
        exposure_stops: args.exposure,
        curve: args.tonemap,
        glossy_eye,
    };
    // Every check but the bulk sections' checksums and the coefficients' finite
    // check, which are made batch by batch below as each batch is read.
    #[allow(clippy::disallowed_methods)] // An edge: `solver export` reads the solution.
    let file = MappedSolution::open_deferring_checksums(&args.solution)?;
    let mut exporter = Exporter::new(file.header(), file.batches(), file.textures(), options)
        .with_context(|| format!("cannot export {}", args.solution.display()))?;
    for (i, info) in file.batches().iter().enumerate() {
        verify_batch(&file, i)?;
        let bytes = BatchBytes {
            vertices: file.section_bytes(i, BatchSection::Vertices),
            coefficients: file.section_bytes(i, BatchSection::Coefficients),
            indices: file.section_bytes(i, BatchSection::Indices),
            textured_vertices: file.section_bytes(i, BatchSection::TexturedVertices),
        };
        // Each section's pages go as soon as the exporter has read it for the
        // last time, so the input and the output are not both resident.
        let dropped = exporter
            .add_batch(i, info, bytes, |section| file.release_section(i, section))
            .with_context(|| format!("cannot export {}", args.solution.display()))?;
        if dropped {
            eprintln!(
                "solver: warning: {}: batch {i} is textured and also has an untextured term \
                 (a glossy lobe or emission), which the glTF leaves out",
                args.solution.display()
            );
        }
    }
    for k in 0..file.textures().len() {
        // Decoding verifies the section's CRC-32 and that the PNG decodes (the
        // decoded image, within the reader's caps, is dropped at once); the
        // glTF gets the PNG as stored.
        drop(file.decode_texture(k)?);
        exporter
            .add_texture(k, file.texture_bytes(k))
            .with_context(|| format!("cannot export {}", args.solution.display()))?;
    }
    let bin_uri = match &container {
        Container::Glb => None,
        Container::Gltf(bin) => Some(file_name_uri(
            &bin.file_name().unwrap_or_default().to_string_lossy(),
        )),
    };
    let exported = exporter.finish(bin_uri.as_deref())?;
    #[allow(clippy::disallowed_methods)] // An edge: `solver export` writes the glTF.
    match &container {
        Container::Glb => write_atomically(&args.out, |f| {
            let mut out = std::io::BufWriter::new(f);
            write_glb(&mut out, &exported.json, &exported.bin)?;
            out.flush()
        })?,
        Container::Gltf(bin) => {
            // The buffer first: a .gltf is never left naming a .bin that is not there.
            write_bytes_atomically(bin, &exported.bin)?;
            write_bytes_atomically(&args.out, &exported.json)?;
        }
    }
    eprintln!(
        "solver: wrote {}: {} vertices, {} triangles, {} bytes of buffer; COLOR_0 = {}(radiance × 2^{}) (linear)",
        args.out.display(),
        exported.vertices,
        exported.triangles,
        exported.bin.len(),
        curve_name(options.curve),
        options.exposure_stops
    );
    Ok(ExitCode::SUCCESS)
}

const SECTIONS: [BatchSection; 4] = [
    BatchSection::Vertices,
    BatchSection::Coefficients,
    BatchSection::Indices,
    BatchSection::TexturedVertices,
];

/// The checks `MappedSolution::open` would have made on batch `i`'s sections:
/// their CRC-32s and the coefficients' finite values. Each section's pages are
/// released once checked; the export reads them again from the page cache,
/// one section after another.
fn verify_batch(file: &MappedSolution, i: usize) -> Result<()> {
    let textured = file.batches()[i].texture.is_some();
    for section in SECTIONS {
        if section == BatchSection::TexturedVertices && !textured {
            continue;
        }
        let bytes = file.section_bytes(i, section);
        file.verify_section(i, section, crc32fast::hash(bytes))?;
        if section == BatchSection::Coefficients {
            file.verify_finite_coefficients(i, 0, bytes)?;
        }
        file.release_section(i, section);
    }
    Ok(())
}
