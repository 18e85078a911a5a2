//! Value checks shared by the writer (which refuses to write an invalid solution)
//! and the reader (which refuses to return one), so both sides enforce one contract.

use super::error::FormatError;
use super::error::Problem;
use super::layout::{self, MAX_CUBE_RESOLUTION, MAX_SH_ORDER};
use super::read::BatchInfo;
use super::{Header, Representation, ScalarType, TextureSlot, TexturedVertex, Vertex};
use std::path::Path;

/// How far from unit length the stored normal and tangent, and how far from zero
/// their dot product, may be. A vector normalized in f32 is within about 1e-7 of
/// unit length, so 1e-3 only refuses frames that were never normalized (or a zero
/// normal of a degenerate polygon), never rounding.
pub const FRAME_TOLERANCE: f32 = 1e-3;

/// The largest finite IEEE half.
pub const F16_MAX: f32 = 65504.0;

fn finite3<T: Into<f64> + Copy + std::fmt::Debug>(what: &str, v: [T; 3]) -> Result<(), Problem> {
    if v.iter().all(|x| (*x).into().is_finite()) {
        Ok(())
    } else {
        Err(Problem::NonFinite {
            what: what.to_string(),
            value: format!("{v:?}"),
        })
    }
}

fn non_negative_finite(what: &str, v: f64) -> Result<(), Problem> {
    if !v.is_finite() {
        return Err(Problem::NonFinite {
            what: what.to_string(),
            value: v.to_string(),
        });
    }
    if v < 0.0 {
        return Err(Problem::Invalid {
            what: format!("{what} is {v}"),
            reason: "it must not be negative".into(),
        });
    }
    Ok(())
}

/// Checks every header value: finite numbers, a positive scale, a camera that
/// [`Camera::validate`](crate::camera::Camera::validate) accepts, ordered bounds,
/// non-negative statistics.
pub fn check_header(h: &Header) -> Result<(), Problem> {
    if !(h.units_per_metre.is_finite() && h.units_per_metre > 0.0) {
        return Err(Problem::Invalid {
            what: format!("header: units_per_metre is {}", h.units_per_metre),
            reason: "it must be finite and positive".into(),
        });
    }
    finite3("header: recentre_offset", h.recentre_offset)?;
    // The header camera obeys the same rules as every other camera in the project
    // (the solver's scene config, the display file, `--camera` flags).
    h.camera.validate().map_err(|e| Problem::Invalid {
        what: format!("header: camera {:?}", h.camera),
        reason: e.to_string(),
    })?;
    finite3("header: bounds_min", h.bounds_min)?;
    finite3("header: bounds_max", h.bounds_max)?;
    if (0..3).any(|k| h.bounds_min[k] > h.bounds_max[k]) {
        return Err(Problem::Invalid {
            what: format!(
                "header: bounds_min {:?} exceeds bounds_max {:?}",
                h.bounds_min, h.bounds_max
            ),
            reason: "bounds must be ordered per axis".into(),
        });
    }
    let s = &h.stats;
    non_negative_finite("header: stats.seconds", s.seconds)?;
    non_negative_finite("header: stats.unshot_fraction", s.unshot_fraction)?;
    non_negative_finite("header: stats.emitted_power", s.emitted_power)?;
    for (k, a) in s.ambient.iter().enumerate() {
        non_negative_finite(&format!("header: stats.ambient[{k}]"), f64::from(*a))?;
    }
    Ok(())
}

/// Checks the representation's parameter against the version-1 limits.
pub fn check_representation(batch: usize, r: Representation) -> Result<(), Problem> {
    match r {
        Representation::Sh { order } => {
            if order > MAX_SH_ORDER {
                return Err(Problem::TooLarge {
                    what: format!("batch {batch}: SH order"),
                    value: order.into(),
                    limit: MAX_SH_ORDER.into(),
                    reason: "f32 evaluation error and shader cost grow as (L + 1)² (see format::MAX_SH_ORDER)",
                });
            }
        }
        Representation::Cube { directions } => {
            let k = crate::cube::resolution_from_directions(directions).ok_or_else(|| {
                Problem::Invalid {
                    what: format!("batch {batch}: cube with {directions} directions"),
                    reason: "a global cube has 6·k² directions for a whole k ≥ 1".into(),
                }
            })?;
            if k > MAX_CUBE_RESOLUTION {
                return Err(Problem::TooLarge {
                    what: format!("batch {batch}: cube resolution k"),
                    value: k.into(),
                    limit: MAX_CUBE_RESOLUTION.into(),
                    reason: "it bounds what a reader sizes from the header",
                });
            }
        }
    }
    Ok(())
}

/// Checks an f16 scale: finite, positive and normal (a subnormal scale would lose
/// precision in `value / scale`).
pub fn check_scalar(batch: usize, s: ScalarType) -> Result<(), Problem> {
    if let ScalarType::F16 { scale } = s {
        if !(scale.is_normal() && scale > 0.0) {
            return Err(Problem::Invalid {
                what: format!("batch {batch}: f16 scale is {scale}"),
                reason: "it must be a positive, finite, normal f32".into(),
            });
        }
    }
    Ok(())
}

/// Checks one vertex: finite values, unit normal and tangent, orthogonal to each
/// other within [`FRAME_TOLERANCE`].
pub fn check_vertex(batch: usize, index: u64, v: &Vertex) -> Result<(), Problem> {
    for (name, x) in [
        ("position", v.position),
        ("normal", v.normal),
        ("tangent", v.tangent),
    ] {
        if !x.iter().all(|c| c.is_finite()) {
            return Err(Problem::NonFinite {
                what: format!("batch {batch}: vertex {index} {name}"),
                value: format!("{x:?}"),
            });
        }
    }
    let dot = |a: [f32; 3], b: [f32; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let n_len = dot(v.normal, v.normal).sqrt();
    let t_len = dot(v.tangent, v.tangent).sqrt();
    let n_dot_t = dot(v.normal, v.tangent);
    if (n_len - 1.0).abs() > FRAME_TOLERANCE
        || (t_len - 1.0).abs() > FRAME_TOLERANCE
        || n_dot_t.abs() > FRAME_TOLERANCE
    {
        return Err(Problem::Invalid {
            what: format!(
                "batch {batch}: vertex {index} frame (normal {:?}, tangent {:?}: lengths {n_len}, {t_len}, n·t {n_dot_t})",
                v.normal, v.tangent
            ),
            reason: format!(
                "normal and tangent must be orthonormal within {FRAME_TOLERANCE}"
            ),
        });
    }
    Ok(())
}

/// A textured batch's fields: spherical harmonics (version 2 defines no textured
/// global cube), a texture index below the file's texture count, and a finite,
/// non-negative factor.
pub fn check_batch_texture(
    batch: usize,
    representation: Representation,
    texture: u32,
    texture_count: u64,
    factor: [f32; 3],
) -> Result<(), Problem> {
    if let Representation::Cube { .. } = representation {
        return Err(Problem::Invalid {
            what: format!("batch {batch}: a textured global-cube batch"),
            reason: "only spherical-harmonic batches may be textured".into(),
        });
    }
    if u64::from(texture) >= texture_count {
        return Err(Problem::Invalid {
            what: format!("batch {batch}: texture index {texture}"),
            reason: format!("the file has {texture_count} textures"),
        });
    }
    finite3(&format!("batch {batch}: texture factor"), factor)?;
    if factor.iter().any(|&x| x < 0.0) {
        return Err(Problem::Invalid {
            what: format!("batch {batch}: texture factor {factor:?}"),
            reason: "it must not be negative".into(),
        });
    }
    Ok(())
}

/// A textured batch's second (emission) slot: a texture index below the
/// file's texture count and a finite, non-negative factor.
pub fn check_emission_slot(
    batch: usize,
    slot: &TextureSlot,
    texture_count: u64,
) -> Result<(), Problem> {
    if u64::from(slot.texture) >= texture_count {
        return Err(Problem::Invalid {
            what: format!("batch {batch}: emission texture index {}", slot.texture),
            reason: format!("the file has {texture_count} textures"),
        });
    }
    finite3(
        &format!("batch {batch}: emission texture factor"),
        slot.factor,
    )?;
    if slot.factor.iter().any(|&x| x < 0.0) {
        return Err(Problem::Invalid {
            what: format!("batch {batch}: emission texture factor {:?}", slot.factor),
            reason: "it must not be negative".into(),
        });
    }
    Ok(())
}

/// A textured vertex: finite UV, finite and non-negative E/π (irradiance cannot
/// be negative; the solver clamps interpolation undershoot before writing).
pub fn check_textured_vertex(batch: usize, index: u64, v: &TexturedVertex) -> Result<(), Problem> {
    if !v.uv.iter().all(|x| x.is_finite()) {
        return Err(Problem::NonFinite {
            what: format!("batch {batch}: textured vertex {index} uv"),
            value: format!("{:?}", v.uv),
        });
    }
    let e = v.irradiance_over_pi;
    finite3(&format!("batch {batch}: textured vertex {index} E/π"), e)?;
    if e.iter().any(|&x| x < 0.0) {
        return Err(Problem::Invalid {
            what: format!("batch {batch}: textured vertex {index} E/π {e:?}"),
            reason: "irradiance must not be negative".into(),
        });
    }
    Ok(())
}

/// The running total of decoded texture bytes against
/// [`layout::MAX_DECODED_TEXTURE_BYTES`].
pub fn check_decoded_texture_bytes(total: u64) -> Result<(), Problem> {
    if total > layout::MAX_DECODED_TEXTURE_BYTES {
        return Err(Problem::TooLarge {
            what: "the decoded size of the textures (RGBA8, bytes)".into(),
            value: total,
            limit: layout::MAX_DECODED_TEXTURE_BYTES,
            reason: "it bounds what decoding a file's textures may allocate",
        });
    }
    Ok(())
}

/// How far outside the header bounds a vertex may lie, relative to the bounds'
/// largest coordinate magnitude: 4 f32 ulps (4 · 2⁻²³ ≈ 4.8e-7). The solver takes
/// the bounds from the stored f32 positions themselves, so they hold exactly; a
/// writer that computes them in f64 and rounds once is off by at most one ulp of
/// the largest coordinate. Anything further out is a header that does not describe
/// its vertices (the runtime places its camera and walk limits by the bounds).
pub const BOUNDS_RELATIVE_SLACK: f32 = 4.0 * f32::EPSILON;

/// The absolute slack [`check_in_bounds`] allows for these bounds.
pub fn bounds_slack(h: &Header) -> f32 {
    let scale = h
        .bounds_min
        .iter()
        .chain(&h.bounds_max)
        .fold(0.0f32, |m, x| m.max(x.abs()));
    BOUNDS_RELATIVE_SLACK * scale
}

/// Checks that a vertex position lies inside the header bounds, within `slack`
/// (from [`bounds_slack`]) on every axis.
pub fn check_in_bounds(
    batch: usize,
    index: u64,
    position: [f32; 3],
    h: &Header,
    slack: f32,
) -> Result<(), Problem> {
    let inside = (0..3)
        .all(|k| position[k] >= h.bounds_min[k] - slack && position[k] <= h.bounds_max[k] + slack);
    if inside {
        Ok(())
    } else {
        Err(Problem::Invalid {
            what: format!(
                "batch {batch}: vertex {index} position {position:?} lies outside the header bounds {:?}..{:?}",
                h.bounds_min, h.bounds_max
            ),
            reason: format!(
                "every vertex must lie inside the bounds (slack {slack:e}, {BOUNDS_RELATIVE_SLACK:e} of the largest coordinate)"
            ),
        })
    }
}

/// Basis terms one vertex of this batch costs per view, as `runtime bench`
/// counts them: (L + 1)² for SH order L, the 4 bilinear taps of a global-cube
/// lookup (whatever its direction count D).
pub fn terms_per_vertex(representation: Representation) -> u64 {
    match representation {
        Representation::Sh { .. } => representation.coefficients_per_channel(),
        Representation::Cube { .. } => 4,
    }
}

/// The per-frame cost of a file: Σ over batches of vertices × [`terms_per_vertex`],
/// per view (a stereo frame costs twice this). Saturates rather than wraps.
pub fn frame_cost(batches: &[BatchInfo]) -> u64 {
    batches.iter().fold(0u64, |sum, b| {
        sum.saturating_add(
            u64::from(b.vertex_count).saturating_mul(terms_per_vertex(b.representation)),
        )
    })
}

/// The default bound on [`frame_cost`]: 10⁸ basis terms per view.
///
/// Measured basis (docs/benchmarks.md, "Runtime"): `runtime bench` on lavapipe,
/// the slowest device the project renders on, sustained 7.1e6 basis terms/s on a
/// frame-bound scene (glossy L = 8, N = 52, no MSAA), a lower bound on its shader
/// throughput. At that rate a file at the bound takes at most 14 s per view there,
/// the longest a frame may take and still serve `bench` and `screenshot` as checks;
/// a hardware GPU evaluates basis terms at least a thousand times faster. A
/// 1M-triangle diffuse scene (about 10⁶ vertices at L = 0, one term each) costs 1%
/// of the bound; 20,000 vertices at the largest order [`super::MAX_SH_ORDER`]
/// (4,225 terms) cost 85%. Larger files are refused unless the user raises the
/// bound with `--max-frame-cost` (see [`check_frame_cost`]).
pub const DEFAULT_MAX_FRAME_COST: u64 = 100_000_000;

/// The command-line flag that overrides [`DEFAULT_MAX_FRAME_COST`].
pub const MAX_FRAME_COST_FLAG: &str = "--max-frame-cost";

/// Refuses a file whose [`frame_cost`] exceeds `limit`. The reader does not call
/// this itself: the runtime does, with the limit its `--max-frame-cost` flag sets.
pub fn check_frame_cost(path: &Path, cost: u64, limit: u64) -> Result<(), FormatError> {
    if cost <= limit {
        return Ok(());
    }
    Err(FormatError::in_file(
        path,
        Problem::FrameCost {
            cost,
            limit,
            flag: MAX_FRAME_COST_FLAG,
        },
    ))
}

/// A batch's vertex and index counts: each at most [`layout::MAX_COUNT`] (indices
/// and draw counts are u32), and the indices a whole number of triangles. The
/// writer checks a batch's lengths and the reader the counts on disk with it.
pub fn check_counts(batch: usize, vertex_count: u64, index_count: u64) -> Result<(), Problem> {
    for (what, count) in [("vertex count", vertex_count), ("index count", index_count)] {
        if count > layout::MAX_COUNT {
            return Err(Problem::TooLarge {
                what: format!("batch {batch}: {what}"),
                value: count,
                limit: layout::MAX_COUNT,
                reason: "indices and draw counts are u32",
            });
        }
    }
    if !index_count.is_multiple_of(3) {
        return Err(Problem::NotTriangles {
            batch,
            count: index_count,
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cubes_must_have_six_squares_of_directions_within_the_cap() {
        let check = |directions| check_representation(0, Representation::Cube { directions });
        assert!(check(6).is_ok());
        assert!(check(6 * 1024 * 1024).is_ok());
        assert!(matches!(check(12), Err(Problem::Invalid { .. })));
        assert!(matches!(
            check(6 * 1025 * 1025),
            Err(Problem::TooLarge { .. })
        ));
    }

    #[test]
    fn frames_must_be_orthonormal() {
        let good = Vertex {
            position: [1.0, 2.0, 3.0],
            normal: [0.0, 1.0, 0.0],
            tangent: [1.0, 0.0, 0.0],
        };
        assert!(check_vertex(0, 0, &good).is_ok());
        let zero_normal = Vertex {
            normal: [0.0; 3],
            ..good
        };
        assert!(check_vertex(0, 0, &zero_normal).is_err());
        let skew = Vertex {
            tangent: [0.0, 1.0, 0.0],
            ..good
        };
        assert!(check_vertex(0, 0, &skew).is_err());
        let nan = Vertex {
            position: [f32::NAN, 0.0, 0.0],
            ..good
        };
        assert!(matches!(
            check_vertex(0, 0, &nan),
            Err(Problem::NonFinite { .. })
        ));
    }

    fn info(representation: Representation, vertex_count: u32) -> BatchInfo {
        BatchInfo {
            representation,
            scalar: ScalarType::F32,
            vertex_count,
            index_count: 0,
            frame_convention: super::super::layout::FRAME_POLYGON_NTB,
            basis_convention: super::super::layout::basis_convention(representation),
            texture: None,
        }
    }

    #[test]
    fn frame_cost_counts_terms_per_vertex_per_view() {
        let diffuse = info(Representation::Sh { order: 0 }, 1_000_000);
        let glossy = info(
            Representation::Sh {
                order: MAX_SH_ORDER,
            },
            1000,
        );
        let cube = info(Representation::Cube { directions: 864 }, 500);
        // 10⁶ · 1 + 1000 · 65² + 500 · 4 (the cube's four bilinear taps).
        assert_eq!(
            frame_cost(&[diffuse, glossy, cube]),
            1_000_000 + 4_225_000 + 2000
        );
        assert_eq!(frame_cost(&[]), 0);
        // A hostile table cannot wrap the sum.
        let huge = info(Representation::Sh { order: u32::MAX }, u32::MAX);
        assert_eq!(frame_cost(&[huge, huge]), u64::MAX);
    }

    #[test]
    fn default_frame_cost_admits_a_million_triangle_diffuse_scene() {
        let path = Path::new("scene.sol");
        // A 1M-triangle mesh has about 0.5-1M vertices; allow 1M at L = 0 with a
        // factor of 10 to spare.
        let diffuse = info(Representation::Sh { order: 0 }, 1_000_000);
        assert!(10 * frame_cost(&[diffuse]) <= DEFAULT_MAX_FRAME_COST);
        check_frame_cost(path, frame_cost(&[diffuse]), DEFAULT_MAX_FRAME_COST).unwrap();
        // 24,000 vertices at the largest order cost 101.4M terms: refused.
        let glossy = info(
            Representation::Sh {
                order: MAX_SH_ORDER,
            },
            24_000,
        );
        let err = check_frame_cost(path, frame_cost(&[glossy]), DEFAULT_MAX_FRAME_COST)
            .unwrap_err()
            .to_string();
        assert!(
            err.starts_with("scene.sol: the per-frame cost is 101400000 basis terms per view"),
            "{err}"
        );
        assert!(err.contains("above the limit of 100000000"), "{err}");
        assert!(err.contains("--max-frame-cost"), "{err}");
    }

    #[test]
    fn vertices_must_lie_inside_the_bounds_within_the_slack() {
        let header = crate::format::tests::sample_solution().header;
        let slack = bounds_slack(&header);
        // The largest coordinate magnitude is 279.6: 4 ulps of it.
        assert_eq!(slack, 279.6 * BOUNDS_RELATIVE_SLACK);
        let edge = header.bounds_max;
        assert!(check_in_bounds(0, 0, edge, &header, slack).is_ok());
        let just_out = [edge[0] + 0.5 * slack, edge[1], edge[2]];
        assert!(check_in_bounds(0, 0, just_out, &header, slack).is_ok());
        let out = [edge[0], edge[1], edge[2] + 1e-3];
        let err = check_in_bounds(2, 7, out, &header, slack).unwrap_err();
        assert!(
            err.to_string().starts_with("batch 2: vertex 7 position"),
            "{err}"
        );
    }
}
