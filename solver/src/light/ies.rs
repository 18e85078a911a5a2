//! IES LM-63 photometric files: a luminaire's intensity distribution in candela,
//! parsed from text and looked up by direction (issue 41's photometric lamps).
//!
//! The format is the Illuminating Engineering Society's "Standard File Format for the
//! Electronic Transfer of Photometric Data": ANSI/IES LM-63-2019 and its earlier
//! editions IESNA LM-63-1986, -1991, ANSI/IESNA LM-63-1995 and -2002. All editions share
//! one layout: an identifying first line (absent in 1986; `IESNA91` in 1991;
//! `IESNA:LM-63-1995`, `IESNA:LM-63-2002`; `IES:LM-63-2019`), free text or `[KEYWORD]`
//! lines, a `TILT=` line with its optional inline tilt block, then the numeric block:
//! thirteen numbers (lamps, lumens per lamp, candela multiplier, the two angle counts,
//! photometric type, units type, width, length, height, ballast factor, a field whose
//! meaning changed by edition, input watts), the vertical angles, the horizontal
//! angles and the candela table, one run of vertical values per horizontal angle.
//! Section numbers are not cited here: this module follows the field order and the
//! rules that every edition states, not a copy of one edition's text.
//!
//! **Why the parser is pure:** the solver core opens no files (ARCHITECTURE.md's
//! Architecture Invariant, enforced by `solver/clippy.toml`). The importer reads the
//! file and hands [`IesProfile::parse`] its text and its path (`origin`), which every
//! error names with the line and the offending token. That is also why `TILT=<file>`
//! is refused: the tilt data must be inlined (`TILT=INCLUDE`).
//!
//! **Frame (photometric type C, the only type accepted):** in the luminaire's frame, z
//! points up, so the nadir is −z. The vertical angle θ runs from 0° at the nadir to
//! 180° at the zenith; the horizontal angle φ turns counterclockwise seen from above,
//! from the 0° photometric plane along +x to 90° along +y. The direction (θ, φ) is
//! (sin θ cos φ, sin θ sin φ, −cos θ); [`IesProfile::candela_toward`] takes such a
//! direction.
//!
//! **Precision:** f64 throughout. Lookups are bilinear in (θ, φ) in degrees and exact
//! at the table's nodes (the weights there are exactly 0 and 1). The flux is the
//! closed-form integral of that same bilinear interpolant, so it differs from the
//! interpolant's true integral only by rounding.
//!
//! **Untrusted sizes:** every count is checked against a cap ([`MAX_ANGLES`],
//! [`MAX_CANDELA_VALUES`], [`MAX_TILT_PAIRS`]) and against the number of values the text
//! actually holds before anything is allocated from it.

mod parse;
#[cfg(test)]
pub(crate) mod tests;

/// The most vertical or horizontal angles a file may declare. Real files hold up to a
/// few hundred of each; 10,000 is a tenth of a degree over half a turn many times over.
pub const MAX_ANGLES: usize = 10_000;
/// The most candela values (vertical × horizontal angles) a file may declare: 32 MiB of
/// f64, far above any goniophotometer's output at 0.1°×1° resolution.
pub const MAX_CANDELA_VALUES: usize = 4_000_000;
/// The most (angle, factor) pairs a `TILT=INCLUDE` block may declare.
pub const MAX_TILT_PAIRS: usize = 10_000;

/// Which edition of LM-63 the file's first line names.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum IesForm {
    /// No identifying first line: LM-63-1986, and 1991 files written without
    /// their `IESNA91` line. The header is free text.
    Lm1986,
    /// First line `IESNA91`.
    Lm1991,
    /// First line `IESNA:LM-63-1995`.
    Lm1995,
    /// First line `IESNA:LM-63-2002`.
    Lm2002,
    /// First line `IES:LM-63-2019`.
    Lm2019,
}

impl IesForm {
    /// Whether the twelfth number is the ballast-lamp photometric factor (1986 and
    /// 1991). Later editions call it "future use" (1995, 2002) or the file generation
    /// type (2019), and it scales nothing there.
    #[must_use]
    pub fn has_ballast_lamp_factor(self) -> bool {
        matches!(self, Self::Lm1986 | Self::Lm1991)
    }
}

/// One header line before `TILT=`: `[KEYWORD] value`, or free text (1986 form, or a
/// non-keyword line anywhere) with an empty keyword. Kept for display, otherwise unused.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct IesKeyword {
    /// The keyword without its brackets, e.g. `TEST`, `MANUFAC`, `MORE`; empty for free text.
    pub keyword: String,
    /// The rest of the line, trimmed.
    pub value: String,
    /// The 1-based line number in the file.
    pub line: usize,
}

/// How the lamp sits in the luminaire, from a `TILT=INCLUDE` block.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LampGeometry {
    /// 1: the lamp is vertical, base up or base down.
    Vertical,
    /// 2: the lamp is horizontal and stays horizontal when the luminaire is tilted
    /// in the 0°–180° plane.
    HorizontalAlong0To180,
    /// 3: the lamp is horizontal and stays horizontal when the luminaire is tilted
    /// in the 90°–270° plane.
    HorizontalAlong90To270,
}

/// A `TILT=INCLUDE` block: how a lamp's output changes when the luminaire is tilted
/// from the position it was photometered in (high-intensity discharge lamps lose
/// output when tilted).
#[derive(Debug, Clone, PartialEq)]
pub struct IesTilt {
    /// The lamp-to-luminaire geometry.
    pub geometry: LampGeometry,
    /// Tilt angles in degrees, strictly ascending.
    pub angles: Vec<f64>,
    /// The multiplying factor at each angle, ≥ 0.
    pub factors: Vec<f64>,
}

impl IesTilt {
    /// The factor that multiplies every candela value when the luminaire is installed
    /// tilted by `tilt_deg` from its photometered position: linear in the angle between
    /// the table's pairs, the end value beyond either end (LM-63 gives no rule there,
    /// and holding the measured end value is the cautious choice).
    #[must_use]
    pub fn factor(&self, tilt_deg: f64) -> f64 {
        interpolate_clamped(&self.angles, &self.factors, tilt_deg)
    }
}

/// How the horizontal angles cover the full turn (type C, from the last angle).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Symmetry {
    /// One horizontal angle, 0°: the same in every plane.
    Axial,
    /// 0°..90°: mirrored about the 0°–180° and the 90°–270° planes.
    Quadrant,
    /// 0°..180°: mirrored about the 0°–180° plane.
    Bilateral,
    /// 90°..270° (a form older files use): mirrored about the 90°–270° plane.
    Bilateral90,
    /// 0°..360°: no symmetry.
    None,
}

/// A parsed photometric type C distribution. Construct with [`IesProfile::parse`].
#[derive(Debug, Clone, PartialEq)]
pub struct IesProfile {
    /// The edition the first line names.
    pub form: IesForm,
    /// The header lines before `TILT=`, in file order.
    pub keywords: Vec<IesKeyword>,
    /// The inline tilt block, or `None` for `TILT=NONE`. Not applied by
    /// [`IesProfile::candela`]: see [`IesProfile::tilt_factor`].
    pub tilt: Option<IesTilt>,
    /// The number of lamps.
    pub lamp_count: u32,
    /// Rated lumens per lamp, or `None` for absolute photometry (−1 in the file).
    pub lumens_per_lamp: Option<f64>,
    /// The candela multiplier.
    pub candela_multiplier: f64,
    /// The luminous opening's width, length and height in metres (converted from
    /// feet where the units type is 1); negative values keep LM-63's meaning of
    /// round or spherical openings.
    pub opening_m: [f64; 3],
    /// The ballast factor.
    pub ballast_factor: f64,
    /// The ballast-lamp photometric factor (1986 and 1991 forms); 1 for later forms.
    pub ballast_lamp_factor: f64,
    /// The twelfth number as written: the ballast-lamp photometric factor (1986,
    /// 1991), "future use" (1995, 2002) or the file generation type (2019).
    pub field_twelve: f64,
    /// Input watts.
    pub input_watts: f64,
    vertical: Vec<f64>,
    horizontal: Vec<f64>,
    /// Raw candela values as written, horizontal-major: `candela[h * nv + v]`.
    raw: Vec<f64>,
    symmetry: Symmetry,
}

impl IesProfile {
    /// Parses an LM-63 file's text; `origin` (the path) names the file in errors.
    ///
    /// # Errors
    /// An [`IesError`] naming `origin`, the line and the offending token for any
    /// malformed, truncated, oversized or unsupported file (types A and B,
    /// `TILT=<file>`).
    pub fn parse(text: &str, origin: &str) -> Result<Self, IesError> {
        parse::parse(text, origin)
    }

    /// The vertical angles in degrees, ascending within [0, 180].
    #[must_use]
    pub fn vertical_angles(&self) -> &[f64] {
        &self.vertical
    }

    /// The horizontal angles in degrees, ascending, as the file states them.
    #[must_use]
    pub fn horizontal_angles(&self) -> &[f64] {
        &self.horizontal
    }

    /// The symmetry the horizontal angles imply.
    #[must_use]
    pub fn symmetry(&self) -> Symmetry {
        self.symmetry
    }

    /// The raw candela value as written at horizontal index `h` and vertical index `v`,
    /// before any factor; `None` outside the table.
    #[must_use]
    pub fn raw_candela(&self, h: usize, v: usize) -> Option<f64> {
        let nv = self.vertical.len();
        (h < self.horizontal.len() && v < nv).then(|| self.raw[h * nv + v])
    }

    /// The factor every table value is multiplied by: the candela multiplier, the
    /// ballast factor, and, in the 1986 and 1991 forms, the ballast-lamp photometric
    /// factor. Later editions' twelfth field is not a factor and is not applied.
    #[must_use]
    pub fn scale(&self) -> f64 {
        self.candela_multiplier * self.ballast_factor * self.ballast_lamp_factor
    }

    /// Rated lumens of the luminaire's lamps (lamps × lumens per lamp), or `None` for
    /// absolute photometry. For relative photometry the candela values are those of
    /// the luminaire with lamps of these rated lumens; a caller that wants another
    /// lamp output scales intensities by its lumens over these.
    #[must_use]
    pub fn rated_lumens(&self) -> Option<f64> {
        self.lumens_per_lamp.map(|l| l * f64::from(self.lamp_count))
    }

    /// The tilt factor for a luminaire installed tilted by `tilt_deg` from its
    /// photometered position (1 for `TILT=NONE`). [`IesProfile::candela`] returns
    /// the distribution as photometered; the caller, who knows the installed
    /// orientation and the [`LampGeometry`], multiplies by this factor.
    #[must_use]
    pub fn tilt_factor(&self, tilt_deg: f64) -> f64 {
        self.tilt.as_ref().map_or(1.0, |t| t.factor(tilt_deg))
    }

    /// Intensity in candela at vertical angle `theta_deg` from the nadir and
    /// horizontal angle `phi_deg` (type C frame, module docs): bilinear in the table
    /// after folding φ by the symmetry, zero outside the vertical range (and for a
    /// non-finite angle), times [`IesProfile::scale`]. φ may be any finite angle.
    #[must_use]
    pub fn candela(&self, theta_deg: f64, phi_deg: f64) -> f64 {
        let (vf, vl) = (self.vertical[0], self.vertical[self.vertical.len() - 1]);
        // Written so that a NaN θ fails the range test and returns zero.
        if !((vf..=vl).contains(&theta_deg) && phi_deg.is_finite()) {
            return 0.0;
        }
        let nv = self.vertical.len();
        let (v0, tv) = bracket(&self.vertical, theta_deg);
        let at = |h: usize| {
            let row = &self.raw[h * nv..(h + 1) * nv];
            lerp(row[v0], row.get(v0 + 1).copied().unwrap_or(0.0), tv)
        };
        let value = if self.horizontal.len() == 1 {
            at(0)
        } else {
            let (h0, th) = bracket(&self.horizontal, self.fold(phi_deg));
            let next = (h0 + 1).min(self.horizontal.len() - 1);
            lerp(at(h0), at(next), th)
        };
        value * self.scale()
    }

    /// Intensity in candela toward `dir` in the luminaire's frame (z up, nadir −z,
    /// φ = 0 along +x); `dir` need not be unit length. Zero for a zero or non-finite
    /// direction.
    #[must_use]
    pub fn candela_toward(&self, dir: [f64; 3]) -> f64 {
        let horizontal = dir[0].hypot(dir[1]);
        // The zero vector has no direction; NaN falls through to candela's zero.
        if horizontal == 0.0 && dir[2] == 0.0 {
            return 0.0;
        }
        let theta = horizontal.atan2(-dir[2]).to_degrees();
        let phi = dir[1].atan2(dir[0]).to_degrees();
        self.candela(theta, phi)
    }

    /// Maps any finite φ into the stored horizontal range by the symmetry.
    fn fold(&self, phi_deg: f64) -> f64 {
        let phi = phi_deg.rem_euclid(360.0);
        let half = if phi > 180.0 { 360.0 - phi } else { phi };
        match self.symmetry {
            Symmetry::Axial => 0.0,
            Symmetry::None => phi,
            Symmetry::Bilateral => half,
            Symmetry::Quadrant => {
                if half > 90.0 {
                    180.0 - half
                } else {
                    half
                }
            }
            Symmetry::Bilateral90 => {
                if phi < 90.0 {
                    180.0 - phi
                } else if phi > 270.0 {
                    540.0 - phi
                } else {
                    phi
                }
            }
        }
    }

    /// The luminous flux in lumens, ∫ I(θ, φ) dω over the sphere, of exactly the
    /// distribution [`IesProfile::candela`] returns (tilt not applied).
    ///
    /// Quadrature: the interpolant is linear in φ between horizontal angles, so the
    /// φ integral is the trapezoid rule, exact; for each linear piece in θ on [a, b],
    /// ∫ I sin θ dθ = I(a)·w_a + I(b)·w_b with closed-form weights
    /// ([`linear_sine_weights`]). The result is the interpolant's exact integral up to
    /// rounding (relative error below 1e-12 for tables within the caps, which a test
    /// checks at the cap). Against the luminaire's true distribution the
    /// error is the interpolation's: for a smooth I, at most max|∂²I/∂θ²|·Δ²/8 per
    /// direction. The stored horizontal range is multiplied out by the symmetry.
    #[must_use]
    pub fn total_flux_lm(&self) -> f64 {
        let nv = self.vertical.len();
        let vertical_integral = |h: usize| -> f64 {
            let row = &self.raw[h * nv..(h + 1) * nv];
            self.vertical
                .windows(2)
                .zip(row.windows(2))
                .map(|(angles, values)| {
                    let (wa, wb) = linear_sine_weights(angles[0], angles[1]);
                    values[0] * wa + values[1] * wb
                })
                .sum()
        };
        let around: f64 = if self.horizontal.len() == 1 {
            std::f64::consts::TAU * vertical_integral(0)
        } else {
            let span = self.horizontal[self.horizontal.len() - 1] - self.horizontal[0];
            let stored: f64 = self
                .horizontal
                .windows(2)
                .enumerate()
                .map(|(h, w)| {
                    let width = (w[1] - w[0]).to_radians();
                    0.5 * width * (vertical_integral(h) + vertical_integral(h + 1))
                })
                .sum();
            stored * 360.0 / span
        };
        around * self.scale()
    }
}

/// The weights (w_a, w_b) with ∫_a^b I(θ) sin θ dθ = I(a)·w_a + I(b)·w_b for I linear
/// on [a, b] (degrees in, radians inside). With m = (a + b)/2 and h = (b − a)/2:
/// ∫ sin θ = 2 sin m sin h, and the odd part gives ±cos m · (sin h − h cos h)/h, so
/// w_a,b = sin m sin h ∓ cos m · (sin h − h cos h)/h. The difference sin h − h cos h
/// is summed as its Taylor series, h³/3 − h⁵/30 + …, because subtracting the two
/// products (or the textbook form w_b = (sin b − sin a)/Δ − cos b) cancels about
/// four of sixteen digits per weight at the fine steps (h ≈ 1.6e-4) of a table at
/// the cap; the series keeps each weight to a few ulps.
fn linear_sine_weights(a_deg: f64, b_deg: f64) -> (f64, f64) {
    let (a, b) = (a_deg.to_radians(), b_deg.to_radians());
    let (m, h) = (0.5 * (a + b), 0.5 * (b - a));
    // Σ_{k≥1} (−1)^(k+1) · 2k · h^(2k+1)/(2k+1)!; h ≤ π/2, so 15 terms leave < 1e-26.
    let mut term = h * h * h / 6.0;
    let mut odd = 0.0;
    for k in 1..=15_u32 {
        let sign = if k % 2 == 1 { 1.0 } else { -1.0 };
        odd += sign * f64::from(2 * k) * term;
        term *= h * h / f64::from((2 * k + 2) * (2 * k + 3));
    }
    let even = m.sin() * h.sin();
    let odd = if h > 0.0 { m.cos() * odd / h } else { 0.0 };
    (even - odd, even + odd)
}

/// `a + (b − a)·t` written as `a(1 − t) + b·t`, exact at t = 0 and t = 1.
fn lerp(a: f64, b: f64, t: f64) -> f64 {
    a * (1.0 - t) + b * t
}

/// The index `i` and weight `t` with `x` between `nodes[i]` and `nodes[i + 1]` and
/// `x = nodes[i] + t·(nodes[i + 1] − nodes[i])`; `x` at or past the last node gives the
/// last index and t = 0. `nodes` is strictly ascending and non-empty; `x` is clamped.
fn bracket(nodes: &[f64], x: f64) -> (usize, f64) {
    let last = nodes.len() - 1;
    // The count of nodes ≤ x, less one: the interval's left node.
    let i = nodes.partition_point(|&n| n <= x).saturating_sub(1);
    if i >= last {
        return (last, 0.0);
    }
    let t = ((x - nodes[i]) / (nodes[i + 1] - nodes[i])).clamp(0.0, 1.0);
    (i, t)
}

/// Piecewise-linear interpolation of `values` over ascending `nodes`, holding the end
/// values beyond either end; NaN gives the first value.
fn interpolate_clamped(nodes: &[f64], values: &[f64], x: f64) -> f64 {
    match (nodes.first(), nodes.last()) {
        (Some(&first), Some(&last)) => {
            if x.is_nan() || x <= first {
                values[0]
            } else if x >= last {
                values[values.len() - 1]
            } else {
                let (i, t) = bracket(nodes, x);
                lerp(values[i], values[i + 1], t)
            }
        }
        _ => 1.0,
    }
}

/// A refused IES file: the file (`origin`), the 1-based line and what is wrong.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{origin}:{line}: {problem}")]
pub struct IesError {
    /// The path the importer read, as it passed it.
    pub origin: String,
    /// The 1-based line of the offending token (the last line when the file ends early).
    pub line: usize,
    /// What is wrong.
    pub problem: IesProblem,
}

/// What is wrong with an IES file; [`IesError`] adds the file and line.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum IesProblem {
    /// The file ends before a needed value.
    #[error("the file ends before the {what}")]
    Truncated {
        /// The value that was expected.
        what: &'static str,
    },
    /// A token that should be a number is not one (or is not finite).
    #[error("{what} '{token}' is not a finite number")]
    NotANumber {
        /// The field.
        what: &'static str,
        /// The token as written.
        token: String,
    },
    /// A number outside what its field allows.
    #[error("{what} '{token}' {why}")]
    Invalid {
        /// The field.
        what: &'static str,
        /// The token as written.
        token: String,
        /// Why it is refused, as a predicate ("must be ...").
        why: String,
    },
    /// A count over its cap, refused before allocating.
    #[error("{what} is {count}, over the cap of {cap}")]
    TooMany {
        /// The counted thing.
        what: &'static str,
        /// The count the file claims.
        count: u64,
        /// The cap.
        cap: usize,
    },
    /// Fewer values follow than the counts claim, refused before allocating.
    #[error("the counts need {needed} {what}, but only {present} values follow")]
    TooFewValues {
        /// What the values are.
        what: &'static str,
        /// Values the counts need.
        needed: usize,
        /// Values present.
        present: usize,
    },
    /// Values left after the candela table.
    #[error(
        "'{token}' follows the candela table: the counts and the values disagree \
         ({extra} values too many)"
    )]
    TrailingValues {
        /// The first extra token.
        token: String,
        /// How many extra tokens.
        extra: usize,
    },
    /// No `TILT=` line.
    #[error("no 'TILT=' line: an LM-63 file has one before its numeric block")]
    NoTilt,
    /// `TILT=<filename>`, which a pure parser cannot follow.
    #[error(
        "'TILT={name}' names a separate tilt file; inline its data with TILT=INCLUDE \
         (the parser reads no other files)"
    )]
    TiltFile {
        /// The file name as written.
        name: String,
    },
    /// An `IESNA:`/`IES:` first line naming an edition this parser does not know.
    #[error(
        "unknown LM-63 edition '{line}' (known: IESNA91, IESNA:LM-63-1995, \
         IESNA:LM-63-2002, IES:LM-63-2019, or none for 1986)"
    )]
    UnknownForm {
        /// The first line as written.
        line: String,
    },
    /// Photometric type A or B.
    #[error(
        "photometric type {letter} ({code}) is not supported: only type C (1), the \
         type of building luminaires, is"
    )]
    UnsupportedType {
        /// "A" or "B".
        letter: &'static str,
        /// The code as written.
        code: String,
    },
}
