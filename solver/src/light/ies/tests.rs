//! Tests of the LM-63 parser and lookups: every form, the symmetries, the flux
//! quadrature against closed forms, the tilt block, and refusals of bad input.
//! All files here are synthetic, written by the tests.

use super::*;
use std::f64::consts::PI;

/// A synthetic LM-63 file, rendered to text by [`Spec::render`].
#[derive(Clone)]
pub(crate) struct Spec {
    /// The first line (`None` for the 1986 form).
    marker: Option<&'static str>,
    /// Header lines before `TILT=`.
    header: Vec<String>,
    /// The TILT line and, for INCLUDE, its block.
    tilt: String,
    lamps: &'static str,
    lumens: f64,
    multiplier: f64,
    photometric_type: &'static str,
    units: u8,
    ballast: f64,
    twelve: f64,
    vertical: Vec<f64>,
    horizontal: Vec<f64>,
    /// Horizontal-major candela values.
    candela: Vec<f64>,
    /// Line end ("\n" or "\r\n") and value separator (" " or ",").
    eol: &'static str,
    sep: &'static str,
}

impl Spec {
    fn new(vertical: &[f64], horizontal: &[f64], candela: &[f64]) -> Self {
        Spec {
            marker: Some("IESNA:LM-63-2002"),
            header: vec!["[TEST] synthetic 1".into(), "[MANUFAC] nobody".into()],
            tilt: "TILT=NONE".into(),
            lamps: "1",
            lumens: 1000.0,
            multiplier: 1.0,
            photometric_type: "1",
            units: 2,
            ballast: 1.0,
            twelve: 1.0,
            vertical: vertical.to_vec(),
            horizontal: horizontal.to_vec(),
            candela: candela.to_vec(),
            eol: "\n",
            sep: " ",
        }
    }

    /// Writes values four to a line, so that every run wraps across lines.
    fn wrapped(&self, values: &[f64], out: &mut Vec<String>) {
        for chunk in values.chunks(4) {
            let words: Vec<String> = chunk.iter().map(|v| format!("{v}")).collect();
            out.push(words.join(self.sep));
        }
    }

    pub(crate) fn render(&self) -> String {
        let mut lines: Vec<String> = self.marker.iter().map(|m| (*m).to_owned()).collect();
        lines.extend(self.header.iter().cloned());
        lines.push(self.tilt.clone());
        let s = self.sep;
        lines.push(format!(
            "{}{s}{}{s}{}{s}{}{s}{}{s}{}{s}{}{s}0.5{s}1.2{s}0.1",
            self.lamps,
            self.lumens,
            self.multiplier,
            self.vertical.len(),
            self.horizontal.len(),
            self.photometric_type,
            self.units
        ));
        lines.push(format!("{}{s}{}{s}42", self.ballast, self.twelve));
        self.wrapped(&self.vertical, &mut lines);
        self.wrapped(&self.horizontal, &mut lines);
        for row in self.candela.chunks(self.vertical.len().max(1)) {
            self.wrapped(row, &mut lines);
        }
        lines.join(self.eol) + self.eol
    }

    fn parse(&self) -> Result<IesProfile, IesError> {
        IesProfile::parse(&self.render(), "lamp.ies")
    }
}

/// The quadrant file below with its TILT line replaced by `tilt` (a line and its block).
fn with_tilt(tilt: &str) -> Spec {
    Spec {
        tilt: tilt.into(),
        ..Spec::new(&V3, &H3, &QUADRANT)
    }
}

/// A quadrant-symmetric table whose bilinear values are easy to work by hand.
const V3: [f64; 3] = [0.0, 45.0, 90.0];
const H3: [f64; 3] = [0.0, 45.0, 90.0];
const QUADRANT: [f64; 9] = [
    100.0, 80.0, 10.0, // φ = 0
    100.0, 60.0, 20.0, // φ = 45
    100.0, 40.0, 30.0, // φ = 90
];

fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs()).max(1e-300)
}

/// Bilinear interpolation written independently of the module: find the cell by a
/// linear scan, then weight the four corners.
pub(crate) fn bilinear_by_hand(spec: &Spec, theta: f64, phi: f64) -> f64 {
    let (v, h) = (&spec.vertical, &spec.horizontal);
    let cell = |nodes: &[f64], x: f64| {
        let i = (0..nodes.len() - 1)
            .find(|&i| x >= nodes[i] && x <= nodes[i + 1])
            .unwrap();
        (i, (x - nodes[i]) / (nodes[i + 1] - nodes[i]))
    };
    let (i, s) = cell(v, theta);
    let (j, t) = cell(h, phi);
    let c = |j: usize, i: usize| spec.candela[j * v.len() + i];
    (1.0 - s) * (1.0 - t) * c(j, i)
        + s * (1.0 - t) * c(j, i + 1)
        + (1.0 - s) * t * c(j + 1, i)
        + s * t * c(j + 1, i + 1)
}

/// The five forms with their first line, a typical header, and the twelfth field.
pub(crate) fn forms() -> Vec<(IesForm, Spec)> {
    let base = Spec {
        multiplier: 2.0,
        ballast: 0.95,
        ..Spec::new(&V3, &H3, &QUADRANT)
    };
    vec![
        (
            IesForm::Lm1986,
            Spec {
                marker: None,
                header: vec!["SYNTHETIC LUMINAIRE".into(), "TEST 1986".into()],
                twelve: 0.9,
                ..base.clone()
            },
        ),
        (
            IesForm::Lm1991,
            Spec {
                marker: Some("IESNA91"),
                twelve: 0.9,
                eol: "\r\n",
                ..base.clone()
            },
        ),
        (
            IesForm::Lm1995,
            Spec {
                marker: Some("IESNA:LM-63-1995"),
                sep: ",",
                ..base.clone()
            },
        ),
        (IesForm::Lm2002, base.clone()),
        (
            IesForm::Lm2019,
            Spec {
                marker: Some("IES:LM-63-2019"),
                header: vec![
                    "[TEST] 1".into(),
                    "[TESTLAB] none".into(),
                    "[ISSUEDATE] 2026-12-06".into(),
                    "[MANUFAC] nobody".into(),
                    "[MORE] a second line".into(),
                ],
                twelve: 1.1,
                eol: "\r\n",
                ..base
            },
        ),
    ]
}

#[test]
fn every_form_returns_table_values_at_nodes_and_bilinear_between() {
    for (form, spec) in forms() {
        let p = spec.parse().unwrap_or_else(|e| panic!("{form:?}: {e}"));
        assert_eq!(p.form, form);
        // The ballast-lamp photometric factor applies in 1986 and 1991 only.
        let blpf = if form.has_ballast_lamp_factor() {
            0.9
        } else {
            1.0
        };
        let scale = 2.0 * 0.95 * blpf;
        assert!(close(p.scale(), scale, 1e-15), "{form:?}");
        for (j, &phi) in H3.iter().enumerate() {
            for (i, &theta) in V3.iter().enumerate() {
                let want = QUADRANT[j * 3 + i] * scale;
                let got = p.candela(theta, phi);
                assert!(
                    close(got, want, 1e-12),
                    "{form:?} ({theta}, {phi}): {got} vs {want}"
                );
            }
        }
        // Worked by hand: at (22.5°, 22.5°) the φ = 0 and 45 columns give 90 and 80,
        // their mean 85; at (67.5°, 67.5°) 40 and 35 give 37.5; at (30°, 15°),
        // 260/3 and 220/3 weighted 2/3 and 1/3 give 740/9.
        for (theta, phi, table) in [
            (22.5, 22.5, 85.0),
            (67.5, 67.5, 37.5),
            (30.0, 15.0, 740.0 / 9.0),
        ] {
            assert!(
                close(p.candela(theta, phi), table * scale, 1e-12),
                "{form:?}"
            );
        }
        for k in 0..50 {
            let theta = 90.0 * f64::from(k) / 49.0;
            let phi = 90.0 * f64::from((k * 17) % 50) / 49.0;
            let want = bilinear_by_hand(&spec, theta, phi) * scale;
            assert!(
                close(p.candela(theta, phi), want, 1e-12),
                "{form:?} ({theta}, {phi})"
            );
        }
        // Outside the vertical range 0..90 the luminaire sends nothing.
        assert_eq!(p.candela(90.5, 10.0), 0.0);
        assert_eq!(p.candela(f64::NAN, 10.0), 0.0);
    }
}

#[test]
fn header_keywords_are_kept_in_order() {
    let (_, spec) = forms().pop().unwrap();
    let p = spec.parse().unwrap();
    let keywords: Vec<(&str, &str)> = p
        .keywords
        .iter()
        .map(|k| (k.keyword.as_str(), k.value.as_str()))
        .collect();
    assert_eq!(keywords[0], ("TEST", "1"));
    assert_eq!(keywords[4], ("MORE", "a second line"));
    assert_eq!(p.keywords[4].line, 6);
    assert!(close(p.field_twelve, 1.1, 0.0));
    let free = Spec {
        marker: None,
        header: vec!["free text".into()],
        ..Spec::new(&V3, &H3, &QUADRANT)
    };
    assert_eq!(free.parse().unwrap().keywords[0].keyword, "");
}

#[test]
fn axial_symmetry_is_the_same_in_every_plane() {
    let v = [0.0, 30.0, 60.0, 90.0, 120.0, 180.0];
    let c = [500.0, 400.0, 250.0, 90.0, 10.0, 0.0];
    let p = Spec::new(&v, &[0.0], &c).parse().unwrap();
    assert_eq!(p.symmetry(), Symmetry::Axial);
    for theta in [0.0, 15.0, 45.0, 100.0, 179.0] {
        let at0 = p.candela(theta, 0.0);
        assert!(at0 > 0.0);
        for phi in [-720.0, -33.0, 0.0, 47.5, 90.0, 181.0, 359.9, 1e6] {
            assert_eq!(p.candela(theta, phi), at0, "({theta}, {phi})");
        }
    }
}

/// Asserts I(θ, φ) = I(θ, mirror(φ)) to 1e-12 at sampled angles; the mirrored angle's
/// arithmetic (180 − φ, 360 − φ) may round in the last place.
fn assert_mirror(p: &IesProfile, mirror: impl Fn(f64) -> f64, what: &str) {
    for k in 0..40 {
        let theta = 2.25 * f64::from(k);
        let phi = 0.37 + 8.9 * f64::from(k);
        let (a, b) = (p.candela(theta, phi), p.candela(theta, mirror(phi)));
        assert!(close(a, b, 1e-12), "{what} ({theta}, {phi}): {a} vs {b}");
    }
}

#[test]
fn quadrant_symmetry_mirrors_about_both_planes() {
    let p = Spec::new(&V3, &H3, &QUADRANT).parse().unwrap();
    assert_eq!(p.symmetry(), Symmetry::Quadrant);
    assert_mirror(&p, |phi| 180.0 - phi, "180 - phi");
    assert_mirror(&p, |phi| 180.0 + phi, "180 + phi");
    assert_mirror(&p, |phi| 360.0 - phi, "360 - phi");
    assert_mirror(&p, |phi| -phi, "-phi");
}

#[test]
fn bilateral_symmetry_mirrors_about_the_zero_plane_only() {
    let h = [0.0, 60.0, 120.0, 180.0];
    let c = [
        10.0, 20.0, 30.0, 40.0, 50.0, 60.0, 70.0, 80.0, 90.0, 15.0, 25.0, 35.0,
    ];
    let p = Spec::new(&V3, &h, &c).parse().unwrap();
    assert_eq!(p.symmetry(), Symmetry::Bilateral);
    assert_mirror(&p, |phi| 360.0 - phi, "360 - phi");
    assert_mirror(&p, |phi| -phi, "-phi");
    // Not quadrant-symmetric: the 0° and 180° planes differ.
    assert!(p.candela(45.0, 0.0) != p.candela(45.0, 180.0));
    // The 90..270 form (older files) mirrors about the 90°–270° plane instead.
    let h90 = [90.0, 180.0, 270.0];
    let c90 = [10.0, 20.0, 30.0, 40.0, 50.0, 60.0, 70.0, 80.0, 95.0];
    let q = Spec::new(&V3, &h90, &c90).parse().unwrap();
    assert_eq!(q.symmetry(), Symmetry::Bilateral90);
    assert_mirror(&q, |phi| 180.0 - phi, "180 - phi");
    assert!(close(q.candela(90.0, 0.0), 60.0, 1e-12)); // φ = 0 mirrors to 180.
}

#[test]
fn full_range_repeats_every_turn() {
    let h = [0.0, 90.0, 180.0, 270.0, 360.0];
    let c: Vec<f64> = (0..15).map(|k| f64::from(k * k % 11 + 1)).collect();
    let p = Spec::new(&V3, &h, &c).parse().unwrap();
    assert_eq!(p.symmetry(), Symmetry::None);
    // φ = −45 lies halfway between the 270° and 360° planes.
    let want = 0.5 * (c[3 * 3 + 1] + c[4 * 3 + 1]);
    assert!(close(p.candela(45.0, -45.0), want, 1e-12));
    for phi in [12.0, 100.0, 300.0] {
        assert!(close(
            p.candela(30.0, phi),
            p.candela(30.0, phi + 720.0),
            1e-12
        ));
    }
}

#[test]
fn candela_toward_uses_the_type_c_frame() {
    let h = [0.0, 90.0, 180.0, 270.0, 360.0];
    let c: Vec<f64> = (0..15).map(|k| f64::from(k + 1)).collect();
    let p = Spec::new(&V3, &h, &c).parse().unwrap();
    // Straight down is θ = 0; +x is (90°, 0°); +y is (90°, 90°); 45° below −y is (45°, 270°).
    assert!(close(
        p.candela_toward([0.0, 0.0, -2.0]),
        p.candela(0.0, 0.0),
        1e-12
    ));
    assert!(close(
        p.candela_toward([3.0, 0.0, 0.0]),
        p.candela(90.0, 0.0),
        1e-12
    ));
    assert!(close(
        p.candela_toward([0.0, 1.0, 0.0]),
        p.candela(90.0, 90.0),
        1e-12
    ));
    assert!(close(
        p.candela_toward([0.0, -1.0, -1.0]),
        p.candela(45.0, 270.0),
        1e-12
    ));
    assert_eq!(p.candela_toward([0.0, 0.0, 1.0]), 0.0); // Above the 0..90 range.
    assert_eq!(p.candela_toward([0.0; 3]), 0.0);
}

#[test]
fn isotropic_flux_is_four_pi_i() {
    let v: Vec<f64> = (0..=18).map(|k| f64::from(k) * 10.0).collect();
    let i = 250.0;
    // The integral of the interpolant is exact in closed form; only rounding remains.
    let want = 4.0 * PI * i;
    for h in [
        vec![0.0],
        vec![0.0, 45.0, 90.0],
        vec![0.0, 90.0, 180.0, 270.0, 360.0],
    ] {
        let c = vec![i; v.len() * h.len()];
        let flux = Spec::new(&v, &h, &c).parse().unwrap().total_flux_lm();
        assert!(close(flux, want, 1e-12), "{h:?}: {flux} vs {want}");
    }
}

#[test]
fn flux_stays_exact_at_the_angle_cap() {
    // 10,000 vertical angles over 0..180 (steps of 0.018°), the finest a file may
    // declare, holding I = θ in degrees: linear, so the interpolant is exact and the
    // flux is 2π ∫₀^π (180/π) θ sin θ dθ = 2π · (180/π) · π = 360π. Only rounding
    // remains, which the closed-form weights must keep below 1e-12.
    let n = MAX_ANGLES;
    let v: Vec<f64> = (0..n).map(|k| 180.0 * k as f64 / (n - 1) as f64).collect();
    let p = IesProfile::parse(&Spec::new(&v, &[0.0], &v).render(), "fine.ies").unwrap();
    let flux = p.total_flux_lm();
    assert!(close(flux, 360.0 * PI, 1e-12), "{flux}");
}

#[test]
fn cosine_lobe_flux_is_pi_i0_within_the_interpolation_bound() {
    let step = 5.0_f64;
    let v: Vec<f64> = (0..=36).map(|k| f64::from(k) * step).collect();
    let i0 = 1000.0;
    let c: Vec<f64> = v
        .iter()
        .map(|t| (i0 * t.to_radians().cos()).max(0.0))
        .collect();
    let flux = Spec::new(&v, &[0.0], &c).parse().unwrap().total_flux_lm();
    // Linear interpolation of I₀ cos θ errs by at most I₀ h²/8 per direction (|cos''| ≤ 1),
    // so over the lower hemisphere (∫ sin θ dθ dφ = 2π) the flux errs by at most
    // π I₀ h²/4: relative h²/4 ≈ 1.9e-3 at h = 5°. cos is concave there, so the
    // interpolant lies below it.
    let h = step.to_radians();
    let want = PI * i0;
    assert!(
        (flux - want).abs() <= want * h * h / 4.0,
        "{flux} vs {want}"
    );
    assert!(flux < want);
}

#[test]
fn flux_of_a_quadrant_file_equals_its_full_turn_twin() {
    // The quadrant table mirrored out to 0..360 by hand: 0, 45, 90, 135, 180, ... 360.
    let h: Vec<f64> = (0..=8).map(|k| f64::from(k) * 45.0).collect();
    let column = |k: usize| {
        let folded = [0, 1, 2, 1, 0, 1, 2, 1, 0][k];
        QUADRANT[folded * 3..folded * 3 + 3].to_vec()
    };
    let c: Vec<f64> = (0..9).flat_map(column).collect();
    let full = Spec::new(&V3, &h, &c).parse().unwrap();
    let quadrant = Spec::new(&V3, &H3, &QUADRANT).parse().unwrap();
    assert!(close(full.total_flux_lm(), quadrant.total_flux_lm(), 1e-12));
    for phi in [10.0, 100.0, 200.0, 300.0] {
        assert!(close(
            full.candela(30.0, phi),
            quadrant.candela(30.0, phi),
            1e-12
        ));
    }
}

#[test]
fn multiplier_and_absolute_photometry_are_applied() {
    let relative = Spec::new(&V3, &H3, &QUADRANT).parse().unwrap();
    assert_eq!(relative.lumens_per_lamp, Some(1000.0));
    assert_eq!(relative.rated_lumens(), Some(1000.0));
    let absolute = Spec {
        lumens: -1.0,
        multiplier: 3.0,
        lamps: "2",
        ..Spec::new(&V3, &H3, &QUADRANT)
    }
    .parse()
    .unwrap();
    assert_eq!(absolute.lumens_per_lamp, None);
    assert_eq!(absolute.rated_lumens(), None);
    assert_eq!(absolute.lamp_count, 2);
    for (theta, phi) in [(0.0, 0.0), (30.0, 15.0), (80.0, 60.0)] {
        let ratio = absolute.candela(theta, phi) / relative.candela(theta, phi);
        assert!(close(ratio, 3.0, 1e-15));
    }
    assert!(close(
        absolute.total_flux_lm(),
        3.0 * relative.total_flux_lm(),
        1e-14
    ));
}

#[test]
fn feet_are_converted_to_metres() {
    let p = Spec {
        units: 1,
        ..Spec::new(&V3, &H3, &QUADRANT)
    }
    .parse()
    .unwrap();
    let want = [0.5 * 0.3048, 1.2 * 0.3048, 0.1 * 0.3048];
    for (got, want) in p.opening_m.iter().zip(want) {
        assert!(close(*got, want, 1e-15));
    }
}

#[test]
fn tilt_include_is_parsed_and_its_factor_interpolated() {
    let spec = with_tilt("TILT=INCLUDE\n1\n5\n0 15 30 45\n90\n1.0 0.95 0.9 0.8 0.5");
    let p = spec.parse().unwrap();
    let tilt = p.tilt.as_ref().unwrap();
    assert_eq!(tilt.geometry, LampGeometry::Vertical);
    assert_eq!(tilt.angles, vec![0.0, 15.0, 30.0, 45.0, 90.0]);
    assert_eq!(tilt.factors, vec![1.0, 0.95, 0.9, 0.8, 0.5]);
    // Linear between pairs, exact at them, held beyond the ends.
    assert!(close(p.tilt_factor(15.0), 0.95, 1e-15));
    assert!(close(p.tilt_factor(22.5), 0.925, 1e-12));
    assert!(close(p.tilt_factor(60.0), 0.8 - 0.3 / 3.0, 1e-12));
    assert_eq!(p.tilt_factor(120.0), 0.5);
    assert_eq!(p.tilt_factor(-5.0), 1.0);
    // The caller applies it: candela() is the distribution as photometered.
    let untilted = Spec::new(&V3, &H3, &QUADRANT).parse().unwrap();
    assert_eq!(p.candela(30.0, 15.0), untilted.candela(30.0, 15.0));
    assert_eq!(untilted.tilt_factor(45.0), 1.0);
}

#[test]
fn tilt_file_is_refused_naming_its_line() {
    let spec = with_tilt("TILT=lamp.tlt");
    let e = spec.parse().unwrap_err();
    assert_eq!(e.line, 4);
    let text = e.to_string();
    assert!(text.starts_with("lamp.ies:4: 'TILT=lamp.tlt'"), "{text}");
    assert!(text.contains("TILT=INCLUDE"), "{text}");
}

/// Every prefix of each valid form: never a panic; a prefix that ends before the last
/// value starts is always an error naming the file and a line within it. (A prefix
/// that cuts the last value short, "30" to "3", is a valid file with another value.)
#[test]
fn every_truncation_is_an_error_and_never_panics() {
    let tilted = with_tilt("TILT=INCLUDE\n2\n2\n0 90\n1 0.5");
    let specs = forms().into_iter().map(|(_, s)| s).chain([tilted]);
    for spec in specs {
        let text = spec.render();
        let last_value_start = text.trim_end().rfind(|c: char| c.is_whitespace()).unwrap() + 1;
        for end in 0..text.len() {
            let prefix = &text[..end];
            let result = IesProfile::parse(prefix, "cut.ies");
            if end < last_value_start {
                let e = result.expect_err(&format!("prefix of {end} bytes parsed"));
                assert_eq!(e.origin, "cut.ies");
                // An upper bound on the line count: a prefix cut between CR and LF
                // reads as a lone-CR file.
                let lines = prefix.matches(['\n', '\r']).count() + 1;
                assert!(e.line >= 1 && e.line <= lines, "{e} ({lines} lines)");
                assert!(e.to_string().starts_with(&format!("cut.ies:{}: ", e.line)));
            }
        }
    }
}

/// Every value of the numeric block replaced by each hostile token: never a panic.
#[test]
fn hostile_tokens_never_panic() {
    let tilted = with_tilt("TILT=INCLUDE\n1\n2\n0 90\n1 0.5");
    let text = tilted.render();
    let lines: Vec<&str> = text.lines().collect();
    let hostile = [
        "abc", "-1", "0", "-0.5", "1e9", "4e9", "nan", "inf", "1e308", "2.5", "10000",
    ];
    for (l, line) in lines.iter().enumerate().skip(3) {
        let words: Vec<&str> = line.split_whitespace().collect();
        for w in 0..words.len() {
            for bad in hostile {
                let mut changed = words.clone();
                changed[w] = bad;
                let mut all = lines.clone();
                let new_line = changed.join(" ");
                all[l] = &new_line;
                let _ = IesProfile::parse(&all.join("\n"), "x.ies");
            }
        }
    }
}

/// Parses `spec` with one edit to its rendered text and returns the error.
fn refused(spec: &Spec, from: &str, to: &str) -> IesError {
    let text = spec.render();
    assert!(text.contains(from), "{from}");
    IesProfile::parse(&text.replacen(from, to, 1), "lamp.ies").unwrap_err()
}

#[test]
fn malformed_values_are_refused_naming_file_line_and_token() {
    let spec = Spec::new(&V3, &H3, &QUADRANT);
    // Lines: 1 marker, 2–3 keywords, 4 TILT, 5–6 numbers, 7 vertical, 8 horizontal,
    // 9–11 candela rows. Each case: the edit, the line named, and the message's tail.
    let cases = [
        (
            "\n0 45 90\n0",
            "\n0 abc 90\n0",
            7,
            "vertical angle 'abc' is not a finite number",
        ),
        (
            "\n0 45 90\n0",
            "\n0 60 45\n0",
            7,
            "vertical angle '45' must be greater",
        ),
        (
            "0 45 90\n100",
            "0 45 270\n100",
            8,
            "horizontal angle '270' must end",
        ),
        (
            "100 80 10",
            "100 -80 10",
            9,
            "candela value '-80' must be ≥ 0",
        ),
        (
            "100 80 10",
            "100 NaN 10",
            9,
            "candela value 'NaN' is not a finite number",
        ),
        (
            "1000 1 3 3 1 2",
            "1000 1 -3 3 1 2",
            5,
            "number of vertical angles '-3' must",
        ),
        (
            "1000 1 3 3 1 2",
            "1000 0 3 3 1 2",
            5,
            "candela multiplier '0' must",
        ),
        ("1 1000 1", "1 -2 1", 5, "lumens per lamp '-2' must"),
        ("30\n", "30 7\n", 11, "'7' follows the candela table"),
        (
            "IESNA:LM-63-2002",
            "IESNA:LM-63-2099",
            1,
            "unknown LM-63 edition",
        ),
        ("TILT=NONE", "TILT NONE", 12, "no 'TILT=' line"),
    ];
    for (from, to, line, tail) in cases {
        let e = refused(&spec, from, to);
        let text = e.to_string();
        assert!(text.starts_with(&format!("lamp.ies:{line}: ")), "{text}");
        assert!(text.contains(tail), "{text}");
    }
    // The exact message the issue asks for.
    let e = refused(&spec, "\n0 45 90\n0", "\n0 abc 90\n0");
    assert_eq!(
        e.to_string(),
        "lamp.ies:7: vertical angle 'abc' is not a finite number"
    );
}

#[test]
fn photometric_types_a_and_b_are_refused() {
    for (code, letter) in [("3", "A"), ("2", "B")] {
        let spec = Spec {
            photometric_type: code,
            ..Spec::new(&V3, &H3, &QUADRANT)
        };
        let e = spec.parse().unwrap_err();
        assert_eq!(e.line, 5);
        let want = format!("photometric type {letter} ({code}) is not supported");
        assert!(e.to_string().contains(&want), "{e}");
    }
}

#[test]
fn huge_counts_are_refused_before_allocating() {
    let spec = Spec::new(&V3, &H3, &QUADRANT);
    // 10⁹ vertical angles: over the per-axis cap, refused when the count is read.
    let e = refused(&spec, "1000 1 3 3 1 2", "1000 1 1000000000 3 1 2");
    assert_eq!(e.line, 5);
    assert!(
        matches!(
            e.problem,
            IesProblem::TooMany {
                count: 1_000_000_000,
                ..
            }
        ),
        "{e}"
    );
    // Each count under its cap, the product (25 million) over the table cap.
    let e = refused(&spec, "1000 1 3 3 1 2", "1000 1 5000 5000 1 2");
    assert!(
        matches!(
            e.problem,
            IesProblem::TooMany {
                count: 25_000_000,
                ..
            }
        ),
        "{e}"
    );
    // Within the caps but more than the file holds: refused from the token count.
    let e = refused(&spec, "1000 1 3 3 1 2", "1000 1 100 100 1 2");
    let want = IesProblem::TooFewValues {
        what: "angles and candela values",
        needed: 100 + 100 + 10_000,
        present: 15,
    };
    assert_eq!(e.problem, want);
    let tilted = with_tilt("TILT=INCLUDE\n1\n4000000000\n0 90\n1 0.5");
    let e = tilted.parse().unwrap_err();
    assert_eq!(e.line, 6);
    assert!(matches!(e.problem, IesProblem::TooMany { .. }), "{e}");
}

#[test]
fn crlf_commas_and_lone_cr_parse_as_plain_text() {
    let plain = Spec::new(&V3, &H3, &QUADRANT).parse().unwrap();
    let crlf = Spec {
        eol: "\r\n",
        sep: ",",
        ..Spec::new(&V3, &H3, &QUADRANT)
    }
    .parse()
    .unwrap();
    assert_eq!(plain, crlf);
    let cr = Spec::new(&V3, &H3, &QUADRANT).render().replace('\n', "\r");
    assert_eq!(IesProfile::parse(&cr, "lamp.ies").unwrap(), plain);
}
