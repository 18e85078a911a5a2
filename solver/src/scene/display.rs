//! The legacy display parameter file of Remington 1992, appendix A.
//!
//! ```text
//! line 1  comment
//! line 2  eye x y z lookat x y z
//! line 3  up x y z
//! line 4  fovx a fovy b          (degrees)
//! line 5  near a far b
//! line 6  xres a yres b
//! line 7  diameter a
//! line 8  ambient 0|1
//! line 9  threshold a            (shooting patch's energy / total energy × 1000)
//! ```
//!
//! It gives the initial [`Camera`] (eye, reference point = target, up, vertical
//! field of view, resolution) and a [`SettingsPatch`] with `ambient` (line 8) and
//! `threshold` (line 9). Lines may not be left out or reordered; blank lines
//! after line 9 are allowed.
//!
//! **Threshold conversion.** Remington 1992 stops when the shooting patch's unshot energy,
//! as a fraction of the total, times 1000 falls below `a`. This solver stops
//! when the *total* unshot power falls below `threshold` × total emitted power
//! (design notes, "Progressive refinement"). The shooting patch holds the most
//! unshot power, so its share never exceeds the total's: taking
//! `threshold = a / 1000` stops no earlier than Remington 1992 would (the total fraction
//! below a/1000 implies the shooting patch's is too), i.e. it is the conservative
//! reading. `a` must lie in (0, 1000).

use super::text::{numbered_lines, parse_real, read_text};
use super::{SceneError, SourceRef, Warning};
use crate::settings::SettingsPatch;
use solution::camera::Camera;
use std::path::{Path, PathBuf};

/// The largest image side a display file may ask for.
const MAX_RESOLUTION: u64 = 16384;

/// Everything a display parameter file says.
#[derive(Clone, Debug, PartialEq)]
pub struct DisplayParams {
    /// Eye, reference point (target), up, vertical FOV (line 4's `fovy`), resolution.
    pub camera: Camera,
    /// Line 4's `fovx`, degrees. The camera uses `fovy` and the image aspect; a
    /// `fovx` that disagrees with them by more than 1% gives a warning.
    pub fov_x_deg: f64,
    /// Near and far clipping planes (line 5), scene units.
    pub near: f64,
    pub far: f64,
    /// Approximate image diameter (line 7), scene units.
    pub diameter: f64,
    /// `ambient` (line 8) and `threshold` = a / 1000 (line 9; see the module notes).
    pub settings: SettingsPatch,
    pub file: PathBuf,
    pub warnings: Vec<Warning>,
}

/// Reads a display parameter file (Remington 1992, appendix A).
pub fn load_display_file(path: &Path) -> Result<DisplayParams, SceneError> {
    let text = read_text(path)?;
    parse_display(path, &text)
}

/// The numbers of lines 2 to 9, each line checked against its layout, and
/// nothing but blank lines after line 9.
fn read_values(path: &Path, text: &str) -> Result<Vec<Vec<f64>>, SceneError> {
    const LAYOUT: [&str; 8] = [
        "eye x y z lookat x y z",
        "up x y z",
        "fovx a fovy b",
        "near a far b",
        "xres a yres b",
        "diameter a",
        "ambient 0|1",
        "threshold a",
    ];
    let mut lines = numbered_lines(text);
    lines.next(); // line 1: comment
    let mut values: Vec<Vec<f64>> = Vec::with_capacity(LAYOUT.len());
    for (k, layout) in LAYOUT.iter().enumerate() {
        let line_no = k + 2;
        let err = |m: String| SceneError::at(path, Some(line_no), String::new(), m);
        let Some((_, line)) = lines.next() else {
            return Err(SceneError::at(
                path,
                Some(line_no),
                String::new(),
                format!("the file ends before line {line_no}, which must be `{layout}`"),
            ));
        };
        let tokens: Vec<&str> = line.split_whitespace().collect();
        let expected: Vec<&str> = layout.split_whitespace().collect();
        if tokens.len() != expected.len() {
            return Err(err(format!(
                "expected `{layout}`, found `{}`",
                tokens.join(" ")
            )));
        }
        let mut numbers = Vec::new();
        let mut keyword = "";
        for (t, e) in tokens.iter().zip(&expected) {
            let is_keyword = e.chars().all(|c| c.is_ascii_lowercase()) && e.len() > 1;
            if is_keyword {
                if !t.eq_ignore_ascii_case(e) {
                    return Err(err(format!(
                        "expected the word `{e}` (line {line_no} is `{layout}`), found `{t}`"
                    )));
                }
                keyword = e;
            } else {
                numbers.push(parse_real(t, keyword).map_err(err)?);
            }
        }
        values.push(numbers);
    }
    for (no, line) in lines {
        if !line.trim().is_empty() {
            return Err(SceneError::at(
                path,
                Some(no),
                String::new(),
                format!("unexpected `{}` after line 9 (threshold)", line.trim()),
            ));
        }
    }
    Ok(values)
}

pub(crate) fn parse_display(path: &Path, text: &str) -> Result<DisplayParams, SceneError> {
    let values = read_values(path, text)?;
    let check = |ok: bool, line: usize, m: String| {
        if ok {
            Ok(())
        } else {
            Err(SceneError::at(path, Some(line), String::new(), m))
        }
    };
    let (eye, target) = (
        [values[0][0], values[0][1], values[0][2]],
        [values[0][3], values[0][4], values[0][5]],
    );
    check(
        eye != target,
        2,
        format!("eye and lookat are the same point {eye:?}"),
    )?;
    let up = [values[1][0], values[1][1], values[1][2]];
    let view = glam::DVec3::from(target) - glam::DVec3::from(eye);
    let up_v = glam::DVec3::from(up);
    check(
        up_v.length() > 0.0 && view.normalize().cross(up_v.normalize()).length() > 1e-6,
        3,
        format!("up {up:?} is zero or parallel to the view direction"),
    )?;
    let (fov_x, fov_y) = (values[2][0], values[2][1]);
    for (v, name) in [(fov_x, "fovx"), (fov_y, "fovy")] {
        check(
            v > 0.0 && v < 180.0,
            4,
            format!("{name} = {v} degrees is out of range (0 < fov < 180)"),
        )?;
    }
    let (near, far) = (values[3][0], values[3][1]);
    check(
        near > 0.0 && far > near,
        5,
        format!("near = {near}, far = {far}: need 0 < near < far"),
    )?;
    let mut resolution = [0u32; 2];
    for (k, name) in ["xres", "yres"].iter().enumerate() {
        let v = values[4][k];
        check(
            v.fract() == 0.0 && v >= 1.0 && v <= MAX_RESOLUTION as f64,
            6,
            format!("{name} = {v} must be a whole number of pixels from 1 to {MAX_RESOLUTION}"),
        )?;
        resolution[k] = v as u32;
    }
    let diameter = values[5][0];
    check(
        diameter > 0.0,
        7,
        format!("diameter = {diameter} must be > 0"),
    )?;
    let ambient = values[6][0];
    check(
        ambient == 0.0 || ambient == 1.0,
        8,
        format!("ambient = {ambient} must be 0 or 1"),
    )?;
    let threshold = values[7][0];
    check(
        threshold > 0.0 && threshold < 1000.0,
        9,
        format!(
            "threshold = {threshold} is out of range: 0 < threshold < 1000 (it is a share × 1000)"
        ),
    )?;

    let warnings = fov_warning(path, fov_x, fov_y, resolution)
        .into_iter()
        .collect();
    Ok(DisplayParams {
        camera: Camera {
            eye,
            target,
            up,
            fov_y_deg: fov_y,
            width: resolution[0],
            height: resolution[1],
        },
        fov_x_deg: fov_x,
        near,
        far,
        diameter,
        settings: SettingsPatch {
            ambient: Some(ambient == 1.0),
            threshold: Some(threshold / 1000.0),
            ..Default::default()
        },
        file: path.to_path_buf(),
        warnings,
    })
}

/// A warning when line 4's `fovx` disagrees by more than 1% with the `fovx`
/// that `fovy` and the image's aspect imply (square pixels).
fn fov_warning(path: &Path, fov_x: f64, fov_y: f64, resolution: [u32; 2]) -> Option<Warning> {
    // tan(fovx / 2) = aspect · tan(fovy / 2) for square pixels.
    let aspect = f64::from(resolution[0]) / f64::from(resolution[1]);
    let implied_x = 2.0
        * (aspect * (fov_y.to_radians() / 2.0).tan())
            .atan()
            .to_degrees();
    ((implied_x - fov_x).abs() > 0.01 * fov_x).then(|| Warning {
        source: SourceRef {
            file: path.to_path_buf(),
            line: Some(4),
            item: String::new(),
        },
        message: format!(
            "fovx {fov_x} disagrees with fovy {fov_y} and the {}×{} image (which imply fovx {:.3}); the camera uses fovy and the image aspect",
            resolution[0], resolution[1], implied_x
        ),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const GOOD: [&str; 9] = [
        "standard camera",
        "eye 278 273 -800 lookat 278 273 0",
        "up 0 1 0",
        "fovx 39.3077 fovy 39.3077",
        "near 10 far 3000",
        "xres 512 yres 512",
        "diameter 1000",
        "ambient 1",
        "threshold 5",
    ];

    fn parse(lines: &[&str]) -> Result<DisplayParams, SceneError> {
        parse_display(Path::new("view.display"), &lines.join("\n"))
    }

    #[test]
    fn reads_camera_and_converts_threshold() {
        let d = parse(&GOOD).unwrap();
        assert_eq!(d.camera.eye, [278.0, 273.0, -800.0]);
        assert_eq!(d.camera.target, [278.0, 273.0, 0.0]);
        assert_eq!(d.camera.up, [0.0, 1.0, 0.0]);
        assert_eq!(d.camera.fov_y_deg, 39.3077);
        assert_eq!((d.camera.width, d.camera.height), (512, 512));
        assert_eq!((d.near, d.far, d.diameter), (10.0, 3000.0, 1000.0));
        assert_eq!(d.settings.ambient, Some(true));
        // Remington's (1992) "share × 1000" of 5 is a total unshot fraction of 5 / 1000.
        assert_eq!(d.settings.threshold, Some(0.005));
        assert!(d.warnings.is_empty());
    }

    #[test]
    fn inconsistent_fovx_warns() {
        let mut lines = GOOD;
        lines[4 - 1] = "fovx 60 fovy 39.3077";
        let d = parse(&lines).unwrap();
        assert_eq!(d.warnings.len(), 1);
        assert!(d.warnings[0].message.contains("fovx 60 disagrees"));
        assert_eq!(d.warnings[0].source.line, Some(4));
        // A 2:1 image with fovy 40° implies fovx = 2·atan(2·tan 20°) = 72.1°: no warning.
        lines[3] = "fovx 72.1 fovy 40";
        lines[5] = "xres 1024 yres 512";
        assert!(parse(&lines).unwrap().warnings.is_empty());
    }

    #[test]
    fn every_malformed_line_names_file_line_and_what() {
        let cases: [(usize, &str, &str); 16] = [
            (
                2,
                "eye 1 2 3 lookat 4 5",
                "expected `eye x y z lookat x y z`",
            ),
            (2, "eye 1 2 3 look 4 5 6", "expected the word `lookat`"),
            (2, "eye 1 2 3 lookat 1 2 3", "same point"),
            (
                2,
                "eye 1 2 x lookat 4 5 6",
                "eye: expected a number, found `x`",
            ),
            (3, "up 0 0 1e400", "not a finite number"),
            (3, "up 0 0 5", "parallel to the view direction"),
            (4, "fovx 40 fovy 180", "fovy = 180 degrees is out of range"),
            (5, "near 10 far 5", "need 0 < near < far"),
            (5, "near 0 far 5", "need 0 < near < far"),
            (6, "xres 512.5 yres 512", "whole number of pixels"),
            (6, "xres 512 yres 100000", "whole number of pixels"),
            (7, "diameter -1", "must be > 0"),
            (8, "ambient 2", "must be 0 or 1"),
            (8, "ambiance 1", "expected the word `ambient`"),
            (9, "threshold 1000", "out of range"),
            (9, "threshold 0", "out of range"),
        ];
        for (line, text, fragment) in cases {
            let mut lines = GOOD;
            lines[line - 1] = text;
            let message = parse(&lines).unwrap_err().to_string();
            assert!(
                message.starts_with(&format!("view.display:{line}:")),
                "{message:?} should name line {line}"
            );
            assert!(
                message.contains(fragment),
                "{message:?} should say {fragment:?}"
            );
        }
        let message = parse(&GOOD[..6]).unwrap_err().to_string();
        assert!(
            message.starts_with("view.display:7:") && message.contains("ends before line 7"),
            "{message}"
        );
        let mut extra = GOOD.to_vec();
        extra.extend(["", "junk"]);
        let message = parse(&extra).unwrap_err().to_string();
        assert!(
            message.starts_with("view.display:11:") && message.contains("junk"),
            "{message}"
        );
    }
}
