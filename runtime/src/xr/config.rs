//! Comfort and control settings for `runtime xr`, read from a TOML file
//! (`config/xr.toml`; see that file for what each key means).
//!
//! Every key is optional and defaults to [`XrConfig::default`], which is the
//! value `config/xr.toml` states (a test keeps the two equal). Unknown keys and
//! out-of-range values are refused with the file and line.

use serde::Deserialize;
use std::ops::Range;
use std::path::Path;
use toml::Spanned;

/// The file `runtime xr` reads when `--config` is not given (relative to the
/// working directory; defaults apply when it does not exist).
pub const DEFAULT_CONFIG_PATH: &str = "config/xr.toml";

/// The reference space the head is tracked in.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
pub enum ReferenceSpace {
    /// `XR_REFERENCE_SPACE_TYPE_LOCAL`: origin where the head was at start-up,
    /// at head height.
    #[serde(rename = "local", alias = "LOCAL")]
    Local,
    /// `XR_REFERENCE_SPACE_TYPE_STAGE`: origin on the floor of the play area.
    #[serde(rename = "stage", alias = "STAGE")]
    Stage,
}

/// The settings, in metres, seconds and degrees.
#[derive(Clone, Debug, PartialEq)]
pub struct XrConfig {
    pub reference_space: ReferenceSpace,
    /// One snap turn, degrees, in (0, 180].
    pub snap_turn_deg: f64,
    /// Walking speed at full thumbstick deflection, metres per second, in [0, 10].
    pub walk_speed_m_s: f64,
    /// Deflection ignored around the stick's centre, in [0, 0.9].
    pub thumbstick_deadzone: f64,
    /// STAGE only: height of the stored camera eye above the floor, metres, in
    /// (0, 3]. The default, `solution::view::EYE_HEIGHT_M` (1.6 m), is the
    /// height at which the solver stands a default view above its floor.
    pub camera_eye_height_m: f64,
    /// IPD override, metres, in [0.04, 0.09] (the adult range is about
    /// 0.054–0.074 m); `None` keeps the headset's eye poses.
    pub ipd_m: Option<f64>,
}

impl Default for XrConfig {
    fn default() -> Self {
        XrConfig {
            reference_space: ReferenceSpace::Local,
            snap_turn_deg: 30.0,
            walk_speed_m_s: 1.4,
            thumbstick_deadzone: 0.2,
            camera_eye_height_m: solution::view::EYE_HEIGHT_M,
            ipd_m: None,
        }
    }
}

/// Why a config file was refused.
#[derive(Debug, thiserror::Error)]
pub enum ConfigError {
    #[error("cannot read the XR config {file}: {source}")]
    Io {
        file: String,
        source: std::io::Error,
    },
    #[error("{file}:{line}: {message}")]
    Invalid {
        file: String,
        line: usize,
        message: String,
    },
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawConfig {
    reference_space: Option<Spanned<ReferenceSpace>>,
    snap_turn_deg: Option<Spanned<f64>>,
    walk_speed_m_s: Option<Spanned<f64>>,
    thumbstick_deadzone: Option<Spanned<f64>>,
    camera_eye_height_m: Option<Spanned<f64>>,
    ipd_m: Option<Spanned<f64>>,
}

fn line_of(text: &str, offset: usize) -> usize {
    text.as_bytes()[..offset.min(text.len())]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
        + 1
}

impl XrConfig {
    /// Reads `path`.
    pub fn load(path: &Path) -> Result<XrConfig, ConfigError> {
        let file = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|source| ConfigError::Io {
            file: file.clone(),
            source,
        })?;
        XrConfig::parse(&text, &file)
    }

    /// Reads `path` if given; otherwise [`DEFAULT_CONFIG_PATH`] if it exists,
    /// else the defaults.
    pub fn load_or_default(path: Option<&Path>) -> Result<XrConfig, ConfigError> {
        match path {
            Some(p) => XrConfig::load(p),
            None => {
                let default = Path::new(DEFAULT_CONFIG_PATH);
                if default.is_file() {
                    XrConfig::load(default)
                } else {
                    Ok(XrConfig::default())
                }
            }
        }
    }

    /// Parses TOML text; `file` names the source in errors.
    pub fn parse(text: &str, file: &str) -> Result<XrConfig, ConfigError> {
        let invalid = |span: Option<Range<usize>>, message: String| ConfigError::Invalid {
            file: file.to_string(),
            line: span.map(|s| line_of(text, s.start)).unwrap_or(1),
            message,
        };
        let raw: RawConfig = toml::from_str(text)
            .map_err(|e| invalid(e.span(), e.message().trim().replace('\n', "; ")))?;
        let mut config = XrConfig::default();
        // Each number is checked against its range, reported at its own line.
        let checked = |value: &Option<Spanned<f64>>,
                       key: &str,
                       ok: &dyn Fn(f64) -> bool,
                       range: &str|
         -> Result<Option<f64>, ConfigError> {
            match value {
                None => Ok(None),
                Some(v) if v.get_ref().is_finite() && ok(*v.get_ref()) => Ok(Some(*v.get_ref())),
                Some(v) => Err(invalid(
                    Some(v.span()),
                    format!("{key} = {} is outside {range}", v.get_ref()),
                )),
            }
        };
        if let Some(space) = &raw.reference_space {
            config.reference_space = *space.get_ref();
        }
        if let Some(v) = checked(
            &raw.snap_turn_deg,
            "snap_turn_deg",
            &|v| v > 0.0 && v <= 180.0,
            "(0, 180] degrees",
        )? {
            config.snap_turn_deg = v;
        }
        if let Some(v) = checked(
            &raw.walk_speed_m_s,
            "walk_speed_m_s",
            &|v| (0.0..=10.0).contains(&v),
            "[0, 10] m/s",
        )? {
            config.walk_speed_m_s = v;
        }
        if let Some(v) = checked(
            &raw.thumbstick_deadzone,
            "thumbstick_deadzone",
            &|v| (0.0..=0.9).contains(&v),
            "[0, 0.9]",
        )? {
            config.thumbstick_deadzone = v;
        }
        if let Some(v) = checked(
            &raw.camera_eye_height_m,
            "camera_eye_height_m",
            &|v| v > 0.0 && v <= 3.0,
            "(0, 3] m",
        )? {
            config.camera_eye_height_m = v;
        }
        config.ipd_m = checked(
            &raw.ipd_m,
            "ipd_m",
            &|v| (0.04..=0.09).contains(&v),
            "[0.04, 0.09] m",
        )?;
        Ok(config)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shipped_file_states_the_defaults() {
        let text = include_str!("../../../config/xr.toml");
        let config = XrConfig::parse(text, "config/xr.toml").unwrap();
        assert_eq!(config, XrConfig::default());
    }

    #[test]
    fn reads_every_key() {
        let text = "reference_space = \"STAGE\"\nsnap_turn_deg = 45\nwalk_speed_m_s = 2.0\n\
                    thumbstick_deadzone = 0.1\ncamera_eye_height_m = 1.2\nipd_m = 0.07\n";
        let c = XrConfig::parse(text, "x.toml").unwrap();
        assert_eq!(
            c,
            XrConfig {
                reference_space: ReferenceSpace::Stage,
                snap_turn_deg: 45.0,
                walk_speed_m_s: 2.0,
                thumbstick_deadzone: 0.1,
                camera_eye_height_m: 1.2,
                ipd_m: Some(0.07),
            }
        );
        // An empty file is all defaults.
        assert_eq!(XrConfig::parse("", "x").unwrap(), XrConfig::default());
    }

    #[test]
    fn errors_name_file_line_and_value() {
        let e = XrConfig::parse("# c\nsnap_turn_deg = 30\nsnap_turn = 45\n", "xr.toml")
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("xr.toml:3:") && e.contains("snap_turn"),
            "{e}"
        );
        let e = XrConfig::parse("\n\nwalk_speed_m_s = -1\n", "xr.toml")
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("xr.toml:3:") && e.contains("-1"), "{e}");
        let e = XrConfig::parse("ipd_m = 0.5\n", "xr.toml")
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("xr.toml:1:") && e.contains("ipd_m = 0.5"),
            "{e}"
        );
        let e = XrConfig::parse("reference_space = \"floor\"\n", "xr.toml")
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("xr.toml:1:") && e.contains("floor"), "{e}");
        let e = XrConfig::parse("snap_turn_deg = nan\n", "xr.toml")
            .unwrap_err()
            .to_string();
        assert!(e.contains("snap_turn_deg = NaN"), "{e}");
        assert!(XrConfig::parse("snap_turn_deg = 0\n", "x").is_err());
        assert!(XrConfig::parse("snap_turn_deg = \"30\"\n", "x").is_err());
    }

    #[test]
    fn missing_explicit_file_is_an_error() {
        let e = XrConfig::load_or_default(Some(Path::new("/nonexistent/xr.toml")))
            .unwrap_err()
            .to_string();
        assert!(e.contains("/nonexistent/xr.toml"), "{e}");
    }
}
