//! Issue 41's additions to the file (format 1.1, 2.1 and 3.1): the exposure
//! key, the lights as a JSON record, and the visible environment (the sky
//! baked into an equirectangular texture, and the sun's disc).
//!
//! The environment is one texture whatever the sky's kind (uniform, CIE
//! overcast, clear, a map), baked at solve time by evaluating the sky at each
//! texel's centre, so that the runtime and the CPU reference renderer have one
//! code path for every sky. `docs/solution-format.md`, "Lights and the visible
//! sky (format x.1)", is the specification.

use super::error::Problem;
use super::layout::{Fields, FieldsMut};
use crate::camera::UpAxis;

/// Issue 41's part of a solution. A solution with `Some` is written as the
/// minor version 1 of its major version; one with `None` (or an empty
/// `Lighting`, see [`Lighting::is_empty`]) as x.0, byte for byte what older
/// writers wrote.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct Lighting {
    /// The log-average radiance of the solution's vertices, area-weighted:
    /// exp(mean log(δ + luminance)) (Reinhard et al. 2002, "Photographic tone
    /// reproduction", eq. 1), W·sr⁻¹·m⁻²; finite, ≥ 0, and 0 when not
    /// computed. A viewer exposes so that this radiance shows at the key
    /// value 0.18.
    pub exposure_key: f32,
    /// The scene's lights (sun, sky, lamps, each with its power at import) as
    /// UTF-8 JSON text, a record for `solver info`: nothing is drawn from it.
    pub lights_json: Option<String>,
    /// The sky and the sun disc as seen from the scene, drawn behind the
    /// geometry.
    pub environment: Option<Environment>,
}

impl Lighting {
    /// Nothing to store: the writer writes such a solution as x.0 and the
    /// reader of an x.1 file with nothing in it gives `None`.
    pub fn is_empty(&self) -> bool {
        self.exposure_key == 0.0 && self.lights_json.is_none() && self.environment.is_none()
    }
}

/// The visible sky as an equirectangular RGB texture (radiance, W·sr⁻¹·m⁻²
/// per channel), plus the sun's disc drawn analytically on top of it.
///
/// Orientation ([`equirect_direction`]): the polar axis is the file's up axis;
/// row 0 is the zenith, the last row the nadir (v = θ/π, θ from up); column
/// 0 starts at azimuth 0, the +x axis, and the azimuth φ = 2πu grows toward
/// up × x.
#[derive(Clone, Debug, PartialEq)]
pub struct Environment {
    pub width: u32,
    pub height: u32,
    /// `width × height` texels, row-major from the zenith row; finite, ≥ 0.
    pub texels: Vec<[f32; 3]>,
    pub sun: Option<SunDisc>,
}

/// The sun as it is seen: a disc of uniform radiance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SunDisc {
    /// Unit vector toward the sun, in the scene frame.
    pub direction: [f32; 3],
    /// In (0, 90] degrees.
    pub angular_diameter_deg: f32,
    /// The disc's radiance, E⊥ / Ω, W·sr⁻¹·m⁻² per channel; finite, ≥ 0.
    pub radiance: [f32; 3],
}

/// The most texels an environment may have (2²⁸: 3 GiB of f32 RGB), so that a
/// hostile size is refused before anything is allocated.
pub const MAX_ENVIRONMENT_TEXELS: u64 = 1 << 28;
/// The size of the environment section's prefix before its texels.
pub const ENVIRONMENT_PREFIX_LEN: usize = 48;
/// Texel format code: RGB, three little-endian f32 per texel.
pub const TEXELS_RGB_F32: u32 = 1;
/// Bytes of one [`TEXELS_RGB_F32`] texel.
pub const TEXEL_LEN: u64 = 12;
/// The width and height the solver bakes: 0.7° per texel, finer than the
/// sky's features (the clear sky's circumsolar peak spans several degrees);
/// the sun's disc is drawn analytically, not from the texels.
pub const DEFAULT_ENVIRONMENT_SIZE: (u32, u32) = (256, 128);

/// Environment-section prefix field offsets.
pub mod prefix {
    pub const TEXEL_FORMAT: usize = 0;
    pub const WIDTH: usize = 4;
    pub const HEIGHT: usize = 8;
    pub const RESERVED_0: usize = 12;
    pub const SUN_DIRECTION: usize = 16;
    pub const SUN_DIAMETER_DEG: usize = 28;
    pub const SUN_RADIANCE: usize = 32;
    pub const RESERVED_1: usize = 44;
}

/// The equirectangular frame of an up axis: (e₁, e₂, up) with e₁ = +x and
/// e₂ = up × e₁, so the azimuth turns counter-clockwise seen from above.
pub fn equirect_frame(up: UpAxis) -> [[f64; 3]; 3] {
    let e2 = match up {
        UpAxis::PosY => [0.0, 0.0, -1.0],
        UpAxis::NegY => [0.0, 0.0, 1.0],
        UpAxis::PosZ => [0.0, 1.0, 0.0],
        UpAxis::NegZ => [0.0, -1.0, 0.0],
    };
    [[1.0, 0.0, 0.0], e2, up.vector()]
}

/// The unit direction at texture coordinates (u, v): φ = 2πu, θ = πv from
/// up, d = sin θ (cos φ e₁ + sin φ e₂) + cos θ up.
pub fn equirect_direction(up: UpAxis, u: f64, v: f64) -> [f64; 3] {
    let [e1, e2, n] = equirect_frame(up);
    let (phi, theta) = (std::f64::consts::TAU * u, std::f64::consts::PI * v);
    let (s, c) = (theta.sin(), theta.cos());
    std::array::from_fn(|k| s * (phi.cos() * e1[k] + phi.sin() * e2[k]) + c * n[k])
}

/// The inverse of [`equirect_direction`]: u in [0, 1), v in [0, 1]. A zero
/// direction gives (0, 0).
pub fn equirect_uv(up: UpAxis, direction: [f64; 3]) -> (f64, f64) {
    let [e1, e2, n] = equirect_frame(up);
    let dot = |a: [f64; 3]| a[0] * direction[0] + a[1] * direction[1] + a[2] * direction[2];
    let len = dot(direction).sqrt();
    if len.is_nan() || len <= 0.0 {
        return (0.0, 0.0);
    }
    let phi = dot(e2).atan2(dot(e1)).rem_euclid(std::f64::consts::TAU);
    let theta = (dot(n) / len).clamp(-1.0, 1.0).acos();
    (
        (phi / std::f64::consts::TAU).rem_euclid(1.0),
        theta / std::f64::consts::PI,
    )
}

impl Environment {
    /// The direction of texel (column `i`, row `j`)'s centre.
    pub fn texel_direction(&self, up: UpAxis, i: u32, j: u32) -> [f64; 3] {
        let u = (f64::from(i) + 0.5) / f64::from(self.width);
        let v = (f64::from(j) + 0.5) / f64::from(self.height);
        equirect_direction(up, u, v)
    }

    /// The sky toward `direction`, bilinear between texel centres: u wraps,
    /// v clamps at the poles' rows (what a GPU sampler with REPEAT in u and
    /// CLAMP_TO_EDGE in v gives). Without the sun.
    pub fn sky(&self, up: UpAxis, direction: [f64; 3]) -> [f32; 3] {
        let (w, h) = (self.width as usize, self.height as usize);
        if w == 0 || h == 0 || self.texels.len() < w * h {
            return [0.0; 3];
        }
        let (u, v) = equirect_uv(up, direction);
        let x = u * w as f64 - 0.5;
        let y = (v * h as f64 - 0.5).clamp(0.0, (h - 1) as f64);
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = ((x - x0) as f32, (y - y0) as f32);
        let col = |k: f64| (k as i64).rem_euclid(w as i64) as usize;
        let (c0, c1) = (col(x0), col(x0 + 1.0));
        let r0 = y0 as usize;
        let r1 = (r0 + 1).min(h - 1);
        let t = |c: usize, r: usize| self.texels[r * w + c];
        let (a, b, c, d) = (t(c0, r0), t(c1, r0), t(c0, r1), t(c1, r1));
        std::array::from_fn(|k| {
            let top = a[k] + (b[k] - a[k]) * fx;
            let bottom = c[k] + (d[k] - c[k]) * fx;
            top + (bottom - top) * fy
        })
    }

    /// What a viewer looking along `direction` sees: the sky, plus the sun's
    /// radiance inside its disc.
    pub fn radiance(&self, up: UpAxis, direction: [f64; 3]) -> [f32; 3] {
        let mut sky = self.sky(up, direction);
        if let Some(sun) = &self.sun {
            if sun.contains(direction) {
                for (s, r) in sky.iter_mut().zip(sun.radiance) {
                    *s += r;
                }
            }
        }
        sky
    }
}

impl SunDisc {
    /// Whether `direction` (any length) lies within the disc's angular radius.
    pub fn contains(&self, direction: [f64; 3]) -> bool {
        let len = direction.iter().map(|x| x * x).sum::<f64>().sqrt();
        if len.is_nan() || len <= 0.0 {
            return false;
        }
        let cos = (0..3)
            .map(|k| direction[k] * f64::from(self.direction[k]))
            .sum::<f64>()
            / len;
        cos >= (0.5 * f64::from(self.angular_diameter_deg))
            .to_radians()
            .cos()
    }
}

fn invalid(what: &str, reason: impl Into<String>) -> Problem {
    Problem::Invalid {
        what: what.to_string(),
        reason: reason.into(),
    }
}

fn non_negative(what: &str, values: &[f32]) -> Result<(), Problem> {
    for (k, &x) in values.iter().enumerate() {
        if !x.is_finite() {
            return Err(Problem::NonFinite {
                what: format!("{what}[{k}]"),
                value: x.to_string(),
            });
        }
        if x < 0.0 {
            return Err(invalid(
                &format!("{what}[{k}] is {x}"),
                "it must not be negative",
            ));
        }
    }
    Ok(())
}

/// The exposure key: finite and ≥ 0.
pub(crate) fn check_exposure_key(key: f32) -> Result<(), Problem> {
    non_negative("header: exposure_key", &[key])
}

/// The texel count of a `width × height` environment, refused when either is
/// zero or the product exceeds [`MAX_ENVIRONMENT_TEXELS`].
fn texel_count(what: &str, width: u32, height: u32) -> Result<u64, Problem> {
    let count = u64::from(width) * u64::from(height);
    if count == 0 {
        return Err(invalid(
            &format!("{what}: size {width} × {height}"),
            "an environment has at least one texel",
        ));
    }
    if count > MAX_ENVIRONMENT_TEXELS {
        return Err(Problem::TooLarge {
            what: format!("{what}: {width} × {height} texels"),
            value: count,
            limit: MAX_ENVIRONMENT_TEXELS,
            reason: "the format caps an environment at 2²⁸ texels",
        });
    }
    Ok(count)
}

fn check_sun(what: &str, sun: &SunDisc) -> Result<(), Problem> {
    let d = sun.angular_diameter_deg;
    if !(d > 0.0 && d <= 90.0) {
        return Err(invalid(
            &format!("{what}: sun angular diameter {d}°"),
            "it must lie in (0, 90] degrees",
        ));
    }
    non_negative(&format!("{what}: sun radiance"), &sun.radiance)?;
    let len = sun.direction.iter().map(|x| x * x).sum::<f32>().sqrt();
    if (len - 1.0).abs().is_nan() || (len - 1.0).abs() > 1e-3 {
        return Err(invalid(
            &format!("{what}: sun direction {:?}", sun.direction),
            "it must be a unit vector (within 1e-3)",
        ));
    }
    Ok(())
}

/// The writer's checks of a solution's lighting: a valid key, UTF-8 is given
/// by `String`, and an environment of a valid size with finite, non-negative
/// texels and a valid sun.
pub(crate) fn check_lighting(lighting: &Lighting) -> Result<(), Problem> {
    check_exposure_key(lighting.exposure_key)?;
    if let Some(env) = &lighting.environment {
        let what = "the environment";
        let count = texel_count(what, env.width, env.height)?;
        if env.texels.len() as u64 != count {
            return Err(invalid(
                &format!("{what}: {} texels", env.texels.len()),
                format!("a {} × {} texture has {count}", env.width, env.height),
            ));
        }
        for (k, texel) in env.texels.iter().enumerate() {
            non_negative(&format!("{what}: texel {k}"), texel)?;
        }
        if let Some(sun) = &env.sun {
            check_sun(what, sun)?;
        }
    }
    Ok(())
}

/// The environment section's bytes: prefix, then the texels.
pub(crate) fn environment_section_bytes(env: &Environment) -> Vec<u8> {
    let mut bytes = vec![0u8; ENVIRONMENT_PREFIX_LEN];
    let mut f = FieldsMut::new(&mut bytes);
    f.u32(prefix::TEXEL_FORMAT, TEXELS_RGB_F32);
    f.u32(prefix::WIDTH, env.width);
    f.u32(prefix::HEIGHT, env.height);
    if let Some(sun) = &env.sun {
        f.f32x3(prefix::SUN_DIRECTION, sun.direction);
        f.f32(prefix::SUN_DIAMETER_DEG, sun.angular_diameter_deg);
        f.f32x3(prefix::SUN_RADIANCE, sun.radiance);
    }
    bytes.reserve(env.texels.len() * TEXEL_LEN as usize);
    for texel in &env.texels {
        for x in texel {
            bytes.extend_from_slice(&x.to_le_bytes());
        }
    }
    bytes
}

/// The environment section's length for a `width × height` texture.
pub(crate) fn environment_section_len(env: &Environment) -> u64 {
    ENVIRONMENT_PREFIX_LEN as u64 + env.texels.len() as u64 * TEXEL_LEN
}

/// Reads and checks an environment section (`what` names it in errors): its
/// prefix, the texel count against the cap and the section's length (before
/// allocating), the sun, then every texel.
pub(crate) fn read_environment_section(
    what: &str,
    bytes: &[u8],
    newer: bool,
) -> Result<Environment, Problem> {
    let f = Fields::new(bytes, ENVIRONMENT_PREFIX_LEN).ok_or_else(|| Problem::BadLength {
        what: format!("{what}'s length"),
        value: bytes.len() as u64,
        reason: format!("it holds at least the {ENVIRONMENT_PREFIX_LEN}-byte prefix"),
    })?;
    let format = f.u32(prefix::TEXEL_FORMAT);
    if format != TEXELS_RGB_F32 {
        return Err(Problem::UnknownCode {
            field: format!("{what}: texel format"),
            code: format,
        });
    }
    for at in [prefix::RESERVED_0, prefix::RESERVED_1] {
        if f.u32(at) != 0 && !newer {
            return Err(Problem::Reserved {
                field: format!("{what}: reserved word at byte {at}"),
                value: f.u32(at).into(),
            });
        }
    }
    let (width, height) = (f.u32(prefix::WIDTH), f.u32(prefix::HEIGHT));
    let count = texel_count(what, width, height)?;
    let expected = ENVIRONMENT_PREFIX_LEN as u128 + u128::from(count) * u128::from(TEXEL_LEN);
    if expected != bytes.len() as u128 {
        return Err(Problem::SizeMismatch {
            what: what.to_string(),
            count,
            unit: "texels",
            expected,
            section: what.to_string(),
            actual: bytes.len() as u64,
        });
    }
    let diameter = f.f32(prefix::SUN_DIAMETER_DEG);
    let sun = SunDisc {
        direction: f.f32x3(prefix::SUN_DIRECTION),
        angular_diameter_deg: diameter,
        radiance: f.f32x3(prefix::SUN_RADIANCE),
    };
    let sun = if diameter == 0.0 {
        let zero = sun.direction.iter().chain(&sun.radiance).all(|&x| x == 0.0);
        if !zero {
            return Err(invalid(
                &format!("{what}: sun {sun:?}"),
                "without a disc (diameter 0) the sun's direction and radiance are zero",
            ));
        }
        None
    } else {
        check_sun(what, &sun)?;
        Some(sun)
    };
    // The count is tied to the section's length above, so this allocation is
    // at most the section's bytes.
    let mut texels = Vec::with_capacity(count as usize);
    for (k, raw) in bytes[ENVIRONMENT_PREFIX_LEN..]
        .chunks_exact(TEXEL_LEN as usize)
        .enumerate()
    {
        let t = Fields::new(raw, TEXEL_LEN as usize).map_or([0.0; 3], |t| t.f32x3(0));
        non_negative(&format!("{what}: texel {k}"), &t)?;
        texels.push(t);
    }
    Ok(Environment {
        width,
        height,
        texels,
        sun,
    })
}
