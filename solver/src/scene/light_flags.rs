//! Lights asked for on the command line (`solver solve --sun AZIMUTH,ELEVATION
//! --sky KIND`), so that an OBJ can be lit without a scene config. They are
//! applied at import, over the scene's own lights, once the scene's up and
//! north are known: a flag replaces the scene's sun or sky.

use super::SceneError;
use crate::light::sky::{Sky, SkyModel};
use crate::light::sun::{SceneAxes, Sun, SunPosition, DEFAULT_ANGULAR_DIAMETER_DEG};
use crate::light::Lights;
use glam::DVec3;
use std::path::Path;

/// The sun's illuminance when `--sun` gives none: bright direct sunlight on
/// a plane facing the sun, about 100 klux at sea level on a clear day.
pub const DEFAULT_SUN_LUX: f64 = 100_000.0;

/// A uniform or overcast sky's horizontal illuminance when `--sky` gives
/// none: about an overcast day's 10 klux.
pub const DEFAULT_SKY_LUX: f64 = 10_000.0;

/// `--sun AZIMUTH,ELEVATION[,LUX]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SunFlag {
    /// Degrees clockwise from north, seen from above.
    pub azimuth_deg: f64,
    /// Degrees above the horizon.
    pub elevation_deg: f64,
    /// Illuminance on a plane facing the sun, white.
    pub lux: f64,
}

/// The sky kinds a flag can name.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SkyFlagKind {
    Uniform,
    Overcast,
    Clear,
}

/// `--sky KIND[,VALUE]`: VALUE is the horizontal illuminance in lux for a
/// uniform or overcast sky, the turbidity for a clear one.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SkyFlag {
    pub kind: SkyFlagKind,
    pub value: Option<f64>,
}

/// The command line's lights; empty by default.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct LightFlags {
    pub sun: Option<SunFlag>,
    pub sky: Option<SkyFlag>,
}

impl LightFlags {
    pub fn is_empty(&self) -> bool {
        self.sun.is_none() && self.sky.is_none()
    }

    /// `lights` with the flags' sun and sky in place of the scene's, about
    /// `axes`. A new sun also re-ties a clear sky (and a lit ground) that the
    /// scene gave to the new sun's direction. Errors name `scene` and the
    /// flag.
    pub(crate) fn apply(
        &self,
        lights: &mut Lights,
        axes: &SceneAxes,
        scene: &Path,
    ) -> Result<(), SceneError> {
        let err = |flag: &str, message: String| SceneError::at(scene, None, flag, message);
        if let Some(f) = self.sun {
            let position =
                SunPosition::from_azimuth_elevation(f.azimuth_deg, f.elevation_deg, axes)
                    .map_err(|e| err("--sun", e.to_string()))?;
            let sun =
                Sun::from_illuminance(position, f.lux, DVec3::ONE, DEFAULT_ANGULAR_DIAMETER_DEG)
                    .map_err(|e| err("--sun", e.to_string()))?;
            lights.sun = Some(sun);
            if let (Some(sky), None) = (lights.sky.clone(), self.sky) {
                lights.sky = Some(retie_sky(&sky, &sun).map_err(|e| {
                    err(
                        "--sun",
                        format!("the scene's sky cannot follow the new sun: {e}"),
                    )
                })?);
            }
        }
        if let Some(f) = self.sky {
            let model = sky_model(f, lights.sun.as_ref()).map_err(|m| err("--sky", m))?;
            let sky = Sky::new(model, axes.up(), Default::default(), lights.sun.as_ref())
                .map_err(|e| err("--sky", e.to_string()))?;
            lights.sky = Some(sky);
        }
        Ok(())
    }
}

/// The model a `--sky` flag names.
fn sky_model(flag: SkyFlag, sun: Option<&Sun>) -> Result<SkyModel, String> {
    let lux = flag.value.unwrap_or(DEFAULT_SKY_LUX);
    let model = match flag.kind {
        SkyFlagKind::Uniform => {
            if !(lux.is_finite() && lux >= 0.0) {
                return Err(format!(
                    "the sky's illuminance {lux} lux must be finite and ≥ 0"
                ));
            }
            SkyModel::uniform_luminance(lux / std::f64::consts::PI, DVec3::ONE)
        }
        SkyFlagKind::Overcast => SkyModel::cie_overcast_illuminance(lux, DVec3::ONE),
        SkyFlagKind::Clear => {
            let Some(sun) = sun else {
                return Err(
                    "a clear sky is tied to the sun: give --sun AZIMUTH,ELEVATION too \
                            (or a [sun] in the scene config)"
                        .to_owned(),
                );
            };
            let turbidity = flag
                .value
                .unwrap_or(super::config_lights::DEFAULT_TURBIDITY);
            SkyModel::clear(turbidity, sun.direction())
        }
    };
    model.map_err(|e| e.to_string())
}

/// `sky` again about the same up with the same rule below the horizon, a
/// clear sky's sun direction and a ground's sunlight taken from `sun`.
fn retie_sky(sky: &Sky, sun: &Sun) -> Result<Sky, crate::light::sky::SkyError> {
    let model = match sky.model() {
        SkyModel::Clear { turbidity, .. } => SkyModel::clear(turbidity, sun.direction())?,
        other => other,
    };
    Sky::new(model, sky.up(), sky.below_horizon(), Some(sun))
}
