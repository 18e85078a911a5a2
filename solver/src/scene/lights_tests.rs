//! Lights from a TOML scene config and from the command-line flags, into
//! [`Scene::lights`] (issue 41): every form of `[sun]`, `[sky]` and
//! `[[lights]]` against the values the light types compute, the errors each
//! bad value gives (file, line, value), and the no-emitter check.

use super::*;
use crate::light::lamp::Beam;
use crate::light::sky::{BelowHorizon, SkyModel, CIE_OVERCAST_HORIZONTAL_FACTOR};
use crate::light::sun::{LocalTime, SceneAxes, Site, SunPosition};
use crate::light::Lights;
use std::f64::consts::PI;
use std::fs;
use std::sync::Arc;

/// A dark 2 × 2 floor at y = 0 (no emitter), 1 unit above the origin's
/// corner so that the re-centring offset is not zero.
const ROOM_OBJ: &str = "v 1 1 1\nv 3 1 1\nv 3 1 -1\nv 1 1 -1\nf 1 2 3 4\n";

/// Writes the room and `config.toml` = the geometry line and `body`.
fn config(dir: &Path, body: &str) -> PathBuf {
    fs::write(dir.join("room.obj"), ROOM_OBJ).unwrap();
    let path = dir.join("config.toml");
    fs::write(&path, format!("geometry = [\"room.obj\"]\n{body}")).unwrap();
    path
}

/// The scene's lights, moved back to the original coordinates.
fn lights_of(dir: &Path, body: &str, options: &ImportOptions) -> Lights {
    let path = config(dir, body);
    let scene = load_scene(&path, options)
        .unwrap_or_else(|e| panic!("{e}"))
        .scene;
    scene.lights.recentred(-scene.recentre_offset)
}

fn lights(body: &str) -> Lights {
    let dir = tempfile::tempdir().unwrap();
    lights_of(dir.path(), body, &ImportOptions::default())
}

/// The 1-based line of the config holding `needle` (after the geometry line).
fn line_of(body: &str, needle: &str) -> usize {
    let text = format!("geometry = [\"room.obj\"]\n{body}");
    text.lines()
        .position(|l| l.contains(needle))
        .map(|i| i + 1)
        .unwrap_or_else(|| panic!("{needle:?} not in the config"))
}

/// The error of `body`, checked to name the config file, the line holding
/// `line_needle`, and `value`.
fn refused(body: &str, line_needle: &str, value: &str) -> String {
    let dir = tempfile::tempdir().unwrap();
    refused_in(dir.path(), body, line_needle, value)
}

/// [`refused`] with the config written in `dir`, beside files a test put there.
fn refused_in(dir: &Path, body: &str, line_needle: &str, value: &str) -> String {
    let path = config(dir, body);
    let message = match load_scene(&path, &ImportOptions::default()) {
        Ok(_) => panic!("accepted: {body}"),
        Err(e) => e.to_string(),
    };
    let at = format!("{}:{}", path.display(), line_of(body, line_needle));
    assert!(message.contains(&at), "{at} not in {message}");
    assert!(message.contains(value), "{value:?} not in {message}");
    message
}

fn close(a: DVec3, b: DVec3, tolerance: f64) -> bool {
    (a - b).abs().max_element() <= tolerance
}

/// 100 klux of white light is 100,000 / 683 W·m⁻² per channel (`units.rs`).
const SUN_146: f64 = 100_000.0 / 683.0;

#[test]
fn sun_forms_give_the_direction_and_irradiance_the_light_types_compute() {
    // A direction need not be unit length; 100 klux white is 146.41 W·m⁻².
    let sun = lights("[sun]\ndirection = [0, 2, 0]\nilluminance = 100000\n")
        .sun
        .unwrap();
    assert_eq!(sun.direction(), DVec3::Y);
    assert!(close(sun.irradiance(), DVec3::splat(SUN_146), 1e-9));
    assert!((sun.irradiance().x - 146.4).abs() < 0.05);
    assert_eq!(sun.angular_diameter_deg(), 0.53);
    // Radiometric irradiance as given; a colour filters lux.
    let sun =
        lights("[sun]\ndirection = [1, 1, 0]\nirradiance = [1, 2, 3]\nangular_diameter_deg = 1\n")
            .sun
            .unwrap();
    assert_eq!(sun.irradiance(), DVec3::new(1.0, 2.0, 3.0));
    assert_eq!(sun.angular_diameter_deg(), 1.0);
    let sun = lights("[sun]\ndirection = [0, 1, 0]\nilluminance = 683\ncolor = [1, 0.5, 0.25]\n")
        .sun
        .unwrap();
    assert!(close(sun.irradiance(), DVec3::new(1.0, 0.5, 0.25), 1e-15));
    // Azimuth 90° (east, +x for y-up and north −z) at 30° elevation:
    // (cos 30°, sin 30°, 0), exact to rounding.
    let sun = lights("[sun]\nazimuth_deg = 90\nelevation_deg = 30\nirradiance = 1\n")
        .sun
        .unwrap();
    let expected = DVec3::new(30f64.to_radians().cos(), 0.5, 0.0);
    assert!(
        close(sun.direction(), expected, 1e-15),
        "{}",
        sun.direction()
    );
    // A z-up scene's default north is +y; a north given at the top level or
    // in [sun] replaces it.
    let sun = lights("up = \"z\"\n[sun]\nazimuth_deg = 0\nelevation_deg = 0\nirradiance = 1\n")
        .sun
        .unwrap();
    assert!(close(sun.direction(), DVec3::Y, 1e-15));
    let sun =
        lights("north = [1, 0, 0]\n[sun]\nazimuth_deg = 0\nelevation_deg = 0\nirradiance = 1\n")
            .sun
            .unwrap();
    assert!(close(sun.direction(), DVec3::X, 1e-15));
    let sun =
        lights("[sun]\nnorth = [1, 0, 0]\nazimuth_deg = 90\nelevation_deg = 0\nirradiance = 1\n")
            .sun
            .unwrap();
    // East = north × up = x × y = +z.
    assert!(close(sun.direction(), DVec3::Z, 1e-15));
}

#[test]
fn a_sun_from_place_and_time_is_the_noaa_position() {
    // The NREL SPA example's place and time (Golden, 2003-10-17 12:30:30,
    // UTC−7): the same call the config makes, so equal to rounding.
    let body = "[sun]\nlatitude = 39.742476\nlongitude = -105.1786\ndate = \"2003-10-17\"\n\
                time = \"12:30:30\"\nutc_offset_hours = -7\nilluminance = 100000\n";
    let sun = lights(body).sun.unwrap();
    let site = Site {
        latitude_deg: 39.742476,
        longitude_deg: -105.1786,
    };
    let time = LocalTime {
        year: 2003,
        month: 10,
        day: 17,
        hours: 12.5 + 30.0 / 3600.0,
        utc_offset_hours: -7.0,
    };
    let (expected, eph) =
        SunPosition::from_place_and_time(&site, &time, &SceneAxes::default()).unwrap();
    assert!(close(sun.direction(), expected.direction(), 1e-12));
    // And it is where the SPA puts it, within NOAA's accuracy (0.02°).
    let (az, el) = SceneAxes::default().azimuth_elevation(sun.direction());
    assert!((az - 194.340241).abs() < 0.02, "{az}");
    assert!(
        (el - 39.872046).abs() < 0.02,
        "{el} ({})",
        eph.elevation_deg
    );
}

#[test]
fn a_sun_below_the_horizon_is_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    let path = config(
        dir.path(),
        "[sun]\nlatitude = 48.85\nlongitude = 2.35\ndate = \"2024-12-21\"\ntime = \"02:00\"\n\
         utc_offset_hours = 1\nilluminance = 100000\n",
    );
    let scene = load_scene(&path, &ImportOptions::default()).unwrap().scene;
    assert!(scene
        .warnings
        .iter()
        .any(|w| w.message.contains("below the horizon")));
    // The same for any form of position; a sun above the horizon is quiet.
    for (elevation, warned) in [(-5, true), (5, false)] {
        let path = config(
            dir.path(),
            &format!("[sun]\nazimuth_deg = 0\nelevation_deg = {elevation}\nirradiance = 1\n"),
        );
        let scene = load_scene(&path, &ImportOptions::default()).unwrap().scene;
        let found = scene
            .warnings
            .iter()
            .any(|w| w.message.contains("below the horizon") && w.source.line == Some(2));
        assert_eq!(found, warned, "{elevation}: {:?}", scene.warnings);
    }
}

#[test]
fn sky_forms_give_the_models_radiance() {
    let sky = lights("[sky]\nkind = \"uniform\"\nradiance = [1, 2, 3]\n")
        .sky
        .unwrap();
    assert_eq!(
        sky.model(),
        SkyModel::Uniform {
            radiance: DVec3::new(1.0, 2.0, 3.0)
        }
    );
    assert_eq!(sky.up(), DVec3::Y);
    assert_eq!(sky.below_horizon(), BelowHorizon::Black);
    let sky = lights("[sky]\nkind = \"uniform\"\nluminance = 1366\ncolor = [1, 0.5, 0]\n")
        .sky
        .unwrap();
    assert!(close(
        sky.radiance(DVec3::Y),
        DVec3::new(2.0, 1.0, 0.0),
        1e-15
    ));
    // A horizontal illuminance E gives L = E/π, so back E/683 W·m⁻².
    let sky = lights("[sky]\nkind = \"uniform\"\nilluminance = 10000\n")
        .sky
        .unwrap();
    assert!(close(
        sky.horizontal_irradiance(),
        DVec3::splat(10_000.0 / 683.0),
        1e-9
    ));
    // CIE overcast from horizontal illuminance: L_z = 9E/(7π), over 683.
    let sky = lights("[sky]\nkind = \"cie-overcast\"\nilluminance = 10000\n")
        .sky
        .unwrap();
    let SkyModel::CieOvercast { zenith_radiance } = sky.model() else {
        panic!("{:?}", sky.model())
    };
    let lz = 9.0 * 10_000.0 / (7.0 * PI) / 683.0;
    assert!(
        close(zenith_radiance, DVec3::splat(lz), 1e-12),
        "{zenith_radiance}"
    );
    assert!((CIE_OVERCAST_HORIZONTAL_FACTOR * lz - 10_000.0 / 683.0).abs() < 1e-9);
    let sky = lights("[sky]\nkind = \"overcast\"\nzenith_luminance = 683\n")
        .sky
        .unwrap();
    assert!(close(sky.radiance(DVec3::Y), DVec3::ONE, 1e-15));
    let sky = lights("[sky]\nkind = \"cie-overcast\"\nzenith_radiance = 3\n")
        .sky
        .unwrap();
    // (1 + 2 cos θ)/3 at the horizon is a third of the zenith.
    assert!(close(sky.radiance(DVec3::X), DVec3::ONE, 1e-15));
    // The sky's up is the scene's.
    let sky = lights("up = \"z\"\n[sky]\nkind = \"uniform\"\nradiance = 1\n")
        .sky
        .unwrap();
    assert_eq!(sky.up(), DVec3::Z);
}

#[test]
fn a_clear_sky_follows_the_sun_and_the_ground_is_lit() {
    let body = "[sun]\ndirection = [1, 1, 0]\nilluminance = 100000\n\
                [sky]\nkind = \"clear\"\nbelow_horizon = \"ground\"\nground_albedo = 0.2\n";
    let lights = lights(body);
    let (sun, sky) = (lights.sun.unwrap(), lights.sky.unwrap());
    let SkyModel::Clear {
        turbidity,
        sun_direction,
    } = sky.model()
    else {
        panic!("{:?}", sky.model())
    };
    assert_eq!(turbidity, 3.0);
    assert!(close(sun_direction, sun.direction(), 1e-15));
    // The ground: ρ (E_sky + E⊥ sin h) / π.
    let e = sky.horizontal_irradiance() + sun.irradiance() * sun.direction().y;
    assert!(close(sky.ground_radiance(), 0.2 * e / PI, 1e-12));
    let sky = self::lights(&format!("{body}turbidity = 6\n")).sky.unwrap();
    assert!(matches!(sky.model(), SkyModel::Clear { turbidity, .. } if turbidity == 6.0));
    let same = self::lights("[sky]\nkind = \"uniform\"\nradiance = 1\nbelow_horizon = \"same\"\n");
    assert_eq!(same.sky.unwrap().radiance(-DVec3::Y), DVec3::ONE);
}

#[test]
fn lamp_forms_give_their_intensity_beam_and_radius() {
    let body = "units_per_metre = 100\n\
                [[lights]]\nposition = [2, 3, 0]\ncandela = 683\ncolor = [1, 0.5, 0.25]\n\
                [[lights]]\nname = \"bulb\"\nposition = [0, 1, 0]\npower = 12.566370614359172\nradius = \"5 cm\"\n\
                [[lights]]\nkind = \"spot\"\nposition = [0, 2, 0]\ndirection = [0, -2, 0]\n\
                inner_cone_deg = 20\nouter_cone_deg = 30\npower = 1\nradius = 0.5\n\
                [[lights]]\nkind = \"point\"\nposition = [0, 0, 1]\nintensity = [1, 2, 3]\n";
    let lamps = lights(body).lamps;
    assert_eq!(lamps.len(), 4);
    assert_eq!(lamps[0].position, DVec3::new(2.0, 3.0, 0.0));
    assert!(close(lamps[0].intensity, DVec3::new(1.0, 0.5, 0.25), 1e-15));
    assert_eq!(lamps[0].name, "lights[0]");
    assert_eq!(lamps[0].beam, Beam::Point);
    // power / 4π for a point; 5 cm at 100 units per metre is 5 units.
    assert_eq!(lamps[1].name, "bulb");
    assert!(close(lamps[1].intensity, DVec3::ONE, 1e-15));
    assert!((lamps[1].radius - 5.0).abs() < 1e-12);
    // A spot's power over its cone's solid angle 2π[(1 − cos i) + (cos i − cos o)/3].
    let (ci, co) = (20f64.to_radians().cos(), 30f64.to_radians().cos());
    let solid = 2.0 * PI * ((1.0 - ci) + (ci - co) / 3.0);
    assert!((lamps[2].intensity.x * solid - 1.0).abs() < 1e-6);
    assert!((lamps[2].power().y - 1.0).abs() < 1e-12);
    assert_eq!(
        lamps[2].beam,
        Beam::Spot {
            axis: -DVec3::Y,
            cos_inner: ci,
            cos_outer: co
        }
    );
    assert_eq!(lamps[2].radius, 0.5);
    assert_eq!(lamps[3].intensity, DVec3::new(1.0, 2.0, 3.0));
}

/// An axially symmetric IES LM-63-1995 file: 100 cd straight down, 80 at
/// 45°, 0 at 90°, absolute photometry.
const IES: &str = "IESNA:LM-63-1995\n[TEST] lights_tests\nTILT=NONE\n\
                   1 -1 1 3 1 1 2 0 0 0\n1 1 100\n0 45 90\n0\n100 80 0\n";

#[test]
fn an_ies_lamp_takes_its_candela_or_is_scaled_to_a_strength() {
    let dir = tempfile::tempdir().unwrap();
    fs::write(dir.path().join("down.ies"), IES).unwrap();
    let body = "[[lights]]\nposition = [0, 2, 0]\nies = \"down.ies\"\ncolor = [1, 1, 0.5]\n\
                [[lights]]\nposition = [0, 2, 0]\nies = \"down.ies\"\ncandela = 683\n\
                [[lights]]\nposition = [0, 2, 0]\nies = \"down.ies\"\npower = 1\n";
    let lamps = lights_of(dir.path(), body, &ImportOptions::default()).lamps;
    // The profile's own peak, 100 cd, through the colour.
    assert!(close(
        lamps[0].intensity,
        DVec3::new(100.0, 100.0, 50.0) / 683.0,
        1e-15
    ));
    let p = lamps[0].profile.as_ref().unwrap();
    assert_eq!(p.peak_candela, 100.0);
    assert_eq!(p.down, -DVec3::Y);
    // Straight down is the peak; at 45° the file's 80 cd.
    let down = lamps[0].intensity_toward(-DVec3::Y);
    assert!(close(down, lamps[0].intensity, 1e-15));
    let slant = lamps[0].intensity_toward(DVec3::new(1.0, -1.0, 0.0).normalize());
    assert!((slant.x / down.x - 0.8).abs() < 1e-12, "{slant}");
    // `candela` sets the peak; the profile is read once for both lamps.
    assert!(close(lamps[1].intensity, DVec3::ONE, 1e-15));
    assert!(Arc::ptr_eq(
        &lamps[0].profile.as_ref().unwrap().ies,
        &lamps[1].profile.as_ref().unwrap().ies
    ));
    // `power`: the profile's flux scaled to 1 W per channel.
    assert!((lamps[2].power().x - 1.0).abs() < 1e-12);
}

#[test]
fn lamps_are_recentred_with_the_polygons() {
    let dir = tempfile::tempdir().unwrap();
    let path = config(
        dir.path(),
        "[[lights]]\nposition = [2, 3, 0]\nintensity = 1\n",
    );
    let scene = load_scene(&path, &ImportOptions::default()).unwrap().scene;
    // The floor's box is centred at (2, 1, 0).
    assert_eq!(scene.recentre_offset, DVec3::new(2.0, 1.0, 0.0));
    assert_eq!(scene.lights.lamps[0].position, DVec3::new(0.0, 2.0, 0.0));
}

#[test]
fn bad_sun_values_name_the_file_line_and_value() {
    refused(
        "[sun]\ndirection = [0, 0, 0]\nilluminance = 1\n",
        "direction",
        "[0, 0, 0]",
    );
    refused(
        "[sun]\nazimuth_deg = 10\nelevation_deg = 100\nilluminance = 1\n",
        "elevation_deg",
        "100",
    );
    refused(
        "[sun]\ndirection = [0, 1, 0]\nilluminance = nan\n",
        "illuminance",
        "NaN",
    );
    refused(
        "[sun]\ndirection = [0, 1, 0]\nirradiance = [1, -2, 1]\n",
        "irradiance",
        "-2",
    );
    refused(
        "\n[sun]\ndirection = [0, 1, 0]\n",
        "[sun]",
        "needs a strength",
    );
    refused("[sun]\nilluminance = 5\n", "[sun]", "needs a position");
    refused(
        "[sun]\ndirection = [0, 1, 0]\nazimuth_deg = 3\nelevation_deg = 4\nirradiance = 1\n",
        "azimuth_deg",
        "`direction` and `azimuth_deg/elevation_deg` are both given",
    );
    refused(
        "[sun]\nlatitude = 45\nlongitude = 0\ndate = \"2024-13-01\"\ntime = \"12:00\"\nirradiance = 1\n",
        "date",
        "2024-13-01",
    );
    refused(
        "[sun]\nlatitude = 45\nlongitude = 0\ndate = \"2024-06-01\"\ntime = \"25:00\"\nirradiance = 1\n",
        "time",
        "25:00",
    );
    refused(
        "[sun]\nlatitude = 95\nlongitude = 0\ndate = \"2024-06-01\"\ntime = \"12:00\"\nirradiance = 1\n",
        "latitude",
        "95",
    );
    refused(
        "north = [0, 1, 0]\n[sun]\nazimuth_deg = 0\nelevation_deg = 0\nirradiance = 1\n",
        "north",
        "[0, 1, 0]",
    );
    refused(
        "[sun]\ndirection = [0, 1, 0]\nirradiance = 1\ncolor = [1, 0, 0]\n",
        "color",
        "leave `color` out",
    );
}

#[test]
fn bad_sky_values_name_the_file_line_and_value() {
    refused(
        "[sky]\nkind = \"stormy\"\nradiance = 1\n",
        "kind",
        "\"stormy\"",
    );
    refused("[sky]\nkind = \"map\"\n", "kind", "needs `file");
    refused(
        "[sky]\nkind = \"map\"\nfile = \"gone.hdr\"\n",
        "file",
        "cannot be read",
    );
    refused(
        "[sky]\nkind = \"map\"\nfile = \"gone.hdr\"\nradiance = 1\n",
        "radiance",
        "does not apply",
    );
    refused(
        "[sky]\nkind = \"uniform\"\nradiance = 1\nscale = 2\n",
        "scale",
        "\"map\" only",
    );
    refused(
        "[sky]\nkind = \"uniform\"\nradiance = -1\n",
        "radiance",
        "-1",
    );
    refused(
        "[sky]\nkind = \"uniform\"\nluminance = nan\n",
        "luminance",
        "NaN",
    );
    refused(
        "[sky]\nkind = \"cie-overcast\"\nilluminance = -5\n",
        "illuminance",
        "-5",
    );
    refused("\n[sky]\nkind = \"uniform\"\n", "[sky]", "needs a strength");
    refused(
        "[sky]\nkind = \"cie-overcast\"\nradiance = 1\n",
        "radiance",
        "`radiance` does not apply",
    );
    refused("[sky]\nkind = \"clear\"\n", "kind", "give a [sun] table");
    refused(
        "[sun]\ndirection = [1, 1, 0]\nirradiance = 1\n[sky]\nkind = \"clear\"\nturbidity = 12\n",
        "turbidity",
        "12",
    );
    refused(
        "[sky]\nkind = \"uniform\"\nradiance = 1\nbelow_horizon = \"ground\"\nground_albedo = 1.5\n",
        "ground_albedo",
        "1.5",
    );
    refused(
        "[sky]\nkind = \"uniform\"\nradiance = 1\nbelow_horizon = \"sideways\"\n",
        "below_horizon",
        "\"sideways\"",
    );
}

#[test]
fn bad_lamp_values_name_the_file_line_and_value() {
    let lamp = "[[lights]]\nposition = [0, 1, 0]\n";
    refused(&format!("{lamp}candela = nan\n"), "candela", "NaN");
    refused(
        &format!("{lamp}intensity = [1, -3, 0]\n"),
        "intensity",
        "-3",
    );
    refused(&format!("{lamp}power = -1\n"), "power", "-1");
    refused(
        &format!("{lamp}kind = \"area\"\nintensity = 1\n"),
        "kind",
        "\"area\"",
    );
    refused(lamp, "[[lights]]", "needs a strength");
    refused(
        "[[lights]]\nposition = [0, nan, 0]\nintensity = 1\n",
        "position",
        "[0, NaN, 0]",
    );
    refused(
        &format!("{lamp}intensity = 1\ncandela = 2\n"),
        "candela",
        "give one",
    );
    refused(
        &format!("{lamp}intensity = 1\nradius = \"3 parsecs\"\n"),
        "radius",
        "3 parsecs",
    );
    let spot = format!("{lamp}kind = \"spot\"\nintensity = 1\ndirection = [0, -1, 0]\n");
    refused(
        &format!("{spot}inner_cone_deg = 30\nouter_cone_deg = 20\n"),
        "inner_cone_deg",
        "inner 30",
    );
    refused(
        &format!("{spot}outer_cone_deg = 95\n"),
        "outer_cone_deg",
        "outer 95",
    );
    refused(
        &format!("{spot}outer_cone_deg = -5\n"),
        "outer_cone_deg",
        "-5",
    );
    refused(
        &format!(
            "{lamp}kind = \"spot\"\nintensity = 1\ndirection = [0, 0, 0]\nouter_cone_deg = 20\n"
        ),
        "direction",
        "[0, 0, 0]",
    );
    refused(
        &format!("{lamp}intensity = 1\nouter_cone_deg = 20\n"),
        "outer_cone_deg",
        "kind = \"spot\" only",
    );
}

#[test]
fn a_bad_ies_file_names_itself_its_line_and_the_config_line() {
    let dir = tempfile::tempdir().unwrap();
    // Truncated after the vertical angles.
    let truncated = IES.rsplit_once("0\n100").unwrap().0;
    fs::write(dir.path().join("cut.ies"), truncated).unwrap();
    let body = "[[lights]]\nposition = [0, 2, 0]\nies = \"cut.ies\"\n";
    let path = config(dir.path(), body);
    let message = load_scene(&path, &ImportOptions::default())
        .unwrap_err()
        .to_string();
    let ies = dir.path().join("cut.ies");
    // The candela values were cut: the error is at the file's last line, 7.
    assert!(
        message.contains(&format!("{}:7", ies.display())),
        "{message}"
    );
    assert!(message.contains("only 3 values follow"), "{message}");
    assert!(
        message.contains(&format!("{}:{}", path.display(), line_of(body, "ies ="))),
        "{message}"
    );
    let missing = config(
        dir.path(),
        "[[lights]]\nposition = [0, 2, 0]\nies = \"none.ies\"\n",
    );
    let message = load_scene(&missing, &ImportOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        message.contains("none.ies") && message.contains(":4"),
        "{message}"
    );
}

#[test]
fn a_scene_lit_only_by_lights_is_not_refused_and_the_error_names_the_lights() {
    let dir = tempfile::tempdir().unwrap();
    // Only a sun, and no emissive material: imported.
    let path = config(
        dir.path(),
        "[sun]\nazimuth_deg = 180\nelevation_deg = 45\nilluminance = 100000\n",
    );
    let scene = load_scene(&path, &ImportOptions::default()).unwrap().scene;
    assert!(scene.lights.sun.is_some());
    // No light at all: refused, naming every way to light it.
    let dark = config(dir.path(), "");
    let message = load_scene(&dark, &ImportOptions::default())
        .unwrap_err()
        .to_string();
    for phrase in [
        "no emitter",
        "[materials.NAME]",
        "`[sun]`, `[sky]` or `[[lights]]`",
        "--sun AZIMUTH,ELEVATION",
        "--sky KIND",
    ] {
        assert!(message.contains(phrase), "{phrase:?} not in {message}");
    }
    // An OBJ: the flags light it.
    let obj = dir.path().join("room.obj");
    let message = load_scene(&obj, &ImportOptions::default())
        .unwrap_err()
        .to_string();
    assert!(message.contains("--sun AZIMUTH,ELEVATION") && message.contains("[sun]"));
    let flags = ImportOptions {
        lights: LightFlags {
            sun: None,
            sky: Some(SkyFlag {
                kind: SkyFlagKind::Uniform,
                value: None,
            }),
        },
        ..Default::default()
    };
    let scene = load_scene(&obj, &flags).unwrap().scene;
    // The default 10 klux on a horizontal plane.
    let e = scene.lights.sky.unwrap().horizontal_irradiance();
    assert!(close(e, DVec3::splat(DEFAULT_SKY_LUX / 683.0), 1e-9));
}

fn sun_flag(azimuth_deg: f64, elevation_deg: f64) -> SunFlag {
    SunFlag {
        azimuth_deg,
        elevation_deg,
        lux: DEFAULT_SUN_LUX,
    }
}

#[test]
fn flags_replace_the_scenes_sun_and_sky() {
    let dir = tempfile::tempdir().unwrap();
    let body = "up = \"z\"\n[sun]\ndirection = [0, 0, 1]\nirradiance = 5\n\
                [sky]\nkind = \"clear\"\nturbidity = 4\n";
    let flags = ImportOptions {
        lights: LightFlags {
            sun: Some(sun_flag(90.0, 30.0)),
            sky: None,
        },
        ..Default::default()
    };
    let lights = lights_of(dir.path(), body, &flags);
    let sun = lights.sun.unwrap();
    // z up, north +y, east = y × z = +x: azimuth 90° at 30° is (cos 30°, 0, ½).
    let expected = DVec3::new(30f64.to_radians().cos(), 0.0, 0.5);
    assert!(
        close(sun.direction(), expected, 1e-15),
        "{}",
        sun.direction()
    );
    assert!(close(sun.irradiance(), DVec3::splat(SUN_146), 1e-9));
    // The config's clear sky follows the new sun and keeps its turbidity.
    assert_eq!(
        lights.sky.unwrap().model(),
        SkyModel::Clear {
            turbidity: 4.0,
            sun_direction: sun.direction()
        }
    );
    // `--sky overcast,20000` replaces the sky: L_z = 9E/(7π) / 683.
    let flags = ImportOptions {
        lights: LightFlags {
            sun: None,
            sky: Some(SkyFlag {
                kind: SkyFlagKind::Overcast,
                value: Some(20_000.0),
            }),
        },
        ..Default::default()
    };
    let sky = lights_of(dir.path(), body, &flags).sky.unwrap();
    let lz = 9.0 * 20_000.0 / (7.0 * PI) / 683.0;
    assert_eq!(sky.up(), DVec3::Z);
    assert!(
        matches!(sky.model(), SkyModel::CieOvercast { zenith_radiance } if close(zenith_radiance, DVec3::splat(lz), 1e-12))
    );
}

#[test]
fn a_clear_sky_flag_needs_a_sun() {
    let dir = tempfile::tempdir().unwrap();
    let obj = dir.path().join("room.obj");
    fs::write(&obj, ROOM_OBJ).unwrap();
    let clear = |sun| ImportOptions {
        lights: LightFlags {
            sun,
            sky: Some(SkyFlag {
                kind: SkyFlagKind::Clear,
                value: None,
            }),
        },
        ..Default::default()
    };
    let message = load_scene(&obj, &clear(None)).unwrap_err().to_string();
    assert!(
        message.contains("--sky") && message.contains("--sun"),
        "{message}"
    );
    let scene = load_scene(&obj, &clear(Some(sun_flag(180.0, 40.0))))
        .unwrap()
        .scene;
    let lights = scene.lights;
    assert!(matches!(
        lights.sky.unwrap().model(),
        SkyModel::Clear { turbidity, sun_direction }
            if turbidity == 3.0 && sun_direction == lights.sun.unwrap().direction()
    ));
    // A sun below the horizon cannot drive the clear sky.
    let message = load_scene(&obj, &clear(Some(sun_flag(180.0, -5.0))))
        .unwrap_err()
        .to_string();
    assert!(
        message.contains("--sky") && message.contains("-5"),
        "{message}"
    );
}

#[test]
fn map_skies_load_from_hdr_files_and_absurd_sizes_are_refused() {
    // A 2 × 1 map: its texels come back through the sky (the upper row is
    // the whole sphere here, so every direction above the horizon sees one
    // of the two texels); a file claiming 100,000² texels is refused before
    // anything is allocated, naming the config's line and the size.
    let dir = tempfile::tempdir().unwrap();
    let mut hdr = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 1 +X 2\n".to_vec();
    hdr.extend(crate::light::envmap::radiance_to_rgbe([1.0, 1.0, 1.0]));
    hdr.extend(crate::light::envmap::radiance_to_rgbe([4.0, 4.0, 4.0]));
    std::fs::write(dir.path().join("sky.hdr"), &hdr).unwrap();
    let path = config(
        dir.path(),
        "[sky]\nkind = \"map\"\nfile = \"sky.hdr\"\nscale = 0.5\n",
    );
    let loaded = load_scene(&path, &ImportOptions::default()).unwrap();
    let sky = loaded.scene.lights.sky.unwrap();
    let up = sky.up();
    let values: Vec<f64> = [DVec3::X, DVec3::NEG_X, DVec3::Z, DVec3::NEG_Z]
        .iter()
        .map(|d| sky.radiance((*d + up).normalize()).x)
        .collect();
    assert!(
        values
            .iter()
            .all(|v| (*v - 0.5).abs() < 0.01 || (*v - 2.0).abs() < 0.02),
        "{values:?}"
    );
    std::fs::write(
        dir.path().join("huge.hdr"),
        b"#?RADIANCE\n\n-Y 100000 +X 100000\n",
    )
    .unwrap();
    refused_in(
        dir.path(),
        "[sky]\nkind = \"map\"\nfile = \"huge.hdr\"\n",
        "file",
        "100000×100000",
    );
}
