//! Value checks shared by the writer (which refuses to write an invalid solution)
//! and the reader (which refuses to return one), so both sides enforce one contract.

use super::error::Problem;
use super::layout::{MAX_CUBE_RESOLUTION, MAX_SH_ORDER};
use super::{Header, Representation, ScalarType, Vertex};

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

/// Checks every header value: finite numbers, a positive scale, a usable camera,
/// ordered bounds, non-negative statistics.
pub fn check_header(h: &Header) -> Result<(), Problem> {
    if !(h.units_per_metre.is_finite() && h.units_per_metre > 0.0) {
        return Err(Problem::Invalid {
            what: format!("header: units_per_metre is {}", h.units_per_metre),
            reason: "it must be finite and positive".into(),
        });
    }
    finite3("header: recentre_offset", h.recentre_offset)?;
    let cam = &h.camera;
    finite3("header: camera eye", cam.eye)?;
    finite3("header: camera target", cam.target)?;
    finite3("header: camera up", cam.up)?;
    if cam.eye == cam.target {
        return Err(Problem::Invalid {
            what: format!("header: camera eye and target are both {:?}", cam.eye),
            reason: "the view direction is undefined".into(),
        });
    }
    if cam.up == [0.0; 3] {
        return Err(Problem::Invalid {
            what: "header: camera up is the zero vector".into(),
            reason: "the camera's roll is undefined".into(),
        });
    }
    if !(cam.fov_y_deg.is_finite() && cam.fov_y_deg > 0.0 && cam.fov_y_deg < 180.0) {
        return Err(Problem::Invalid {
            what: format!("header: camera fov_y_deg is {}", cam.fov_y_deg),
            reason: "it must lie strictly between 0 and 180 degrees".into(),
        });
    }
    if cam.width == 0 || cam.height == 0 {
        return Err(Problem::Invalid {
            what: format!("header: camera image is {}x{}", cam.width, cam.height),
            reason: "both sides must be at least one pixel".into(),
        });
    }
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
                    reason: "no lobe in the design notes needs more (α = 0.02 needs about 100)",
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
}
