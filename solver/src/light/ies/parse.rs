//! LM-63 text to [`IesProfile`]: the header lines, the `TILT=` line and its block, the
//! numeric block, and the checks on counts, angles and values.

use super::{
    IesError, IesForm, IesKeyword, IesProblem, IesProfile, IesTilt, LampGeometry, Symmetry,
    MAX_ANGLES, MAX_CANDELA_VALUES, MAX_TILT_PAIRS,
};

/// One number-shaped token of the data after `TILT=`, with its 1-based line.
#[derive(Clone, Copy)]
struct Token<'a> {
    text: &'a str,
    line: usize,
}

/// Reads tokens in order, producing errors that name the origin and the line.
struct Cursor<'a> {
    tokens: Vec<Token<'a>>,
    next: usize,
    origin: &'a str,
    /// The file's last line, which a truncation error names.
    last_line: usize,
}

impl<'a> Cursor<'a> {
    fn error(&self, line: usize, problem: IesProblem) -> IesError {
        IesError {
            origin: self.origin.to_owned(),
            line,
            problem,
        }
    }

    fn remaining(&self) -> usize {
        self.tokens.len() - self.next
    }

    /// The next token, or a truncation error naming `what`.
    fn token(&mut self, what: &'static str) -> Result<Token<'a>, IesError> {
        let token = self.tokens.get(self.next).copied();
        let token =
            token.ok_or_else(|| self.error(self.last_line, IesProblem::Truncated { what }))?;
        self.next += 1;
        Ok(token)
    }

    /// The next token as a finite number, with its token for later messages.
    fn number(&mut self, what: &'static str) -> Result<(f64, Token<'a>), IesError> {
        let token = self.token(what)?;
        match token.text.parse::<f64>() {
            Ok(value) if value.is_finite() => Ok((value, token)),
            _ => Err(self.error(
                token.line,
                IesProblem::NotANumber {
                    what,
                    token: token.text.to_owned(),
                },
            )),
        }
    }

    /// An error for a number that its field does not allow.
    fn invalid(&self, token: Token<'_>, what: &'static str, why: &str) -> IesError {
        self.error(
            token.line,
            IesProblem::Invalid {
                what,
                token: token.text.to_owned(),
                why: why.to_owned(),
            },
        )
    }

    /// The next token as a whole number in `min..=cap` (a count or a code). Tolerates
    /// `10.0`, which some writers emit. Over the cap is [`IesProblem::TooMany`].
    fn count(&mut self, what: &'static str, min: u64, cap: usize) -> Result<usize, IesError> {
        let (value, token) = self.number(what)?;
        if value.fract() != 0.0 || value < 0.0 {
            return Err(self.invalid(token, what, "must be a whole number ≥ 0"));
        }
        if value < min as f64 {
            return Err(self.invalid(token, what, &format!("must be at least {min}")));
        }
        if value > cap as f64 {
            // Truncation is deliberate: the value is finite and only reported.
            #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
            let count = value.min(u64::MAX as f64) as u64;
            return Err(self.error(token.line, IesProblem::TooMany { what, count, cap }));
        }
        // In range 0..=cap, whole: the cast is exact.
        #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
        Ok(value as usize)
    }

    /// Refuses the file unless `needed` more values follow; called before allocating.
    fn ensure(&self, needed: usize, what: &'static str) -> Result<(), IesError> {
        let present = self.remaining();
        if present < needed {
            return Err(self.error(
                self.last_line,
                IesProblem::TooFewValues {
                    what,
                    needed,
                    present,
                },
            ));
        }
        Ok(())
    }

    /// `n` values (already ensured present), each checked by `check`.
    fn values(
        &mut self,
        n: usize,
        what: &'static str,
        check: impl Fn(f64) -> Option<&'static str>,
    ) -> Result<Vec<f64>, IesError> {
        let mut out = Vec::with_capacity(n);
        for _ in 0..n {
            let (value, token) = self.number(what)?;
            if let Some(why) = check(value) {
                return Err(self.invalid(token, what, why));
            }
            out.push(value);
        }
        Ok(out)
    }

    /// `n` angles in `lo..=hi`, strictly ascending; the token that breaks the order
    /// is named.
    fn ascending_angles(
        &mut self,
        n: usize,
        what: &'static str,
        lo: f64,
        hi: f64,
    ) -> Result<Vec<f64>, IesError> {
        let start = self.next;
        let angles = self.values(n, what, |a| {
            (!(lo..=hi).contains(&a)).then_some("is outside the range LM-63 allows")
        })?;
        if let Some(i) = angles.windows(2).position(|w| w[1] <= w[0]) {
            let token = self.tokens[start + i + 1];
            return Err(self.invalid(token, what, "must be greater than the angle before it"));
        }
        Ok(angles)
    }
}

/// The file's lines without their CR LF or LF ends; a file that uses lone CRs (old
/// Macintosh writers) is split on those.
fn lines(text: &str) -> Vec<&str> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    if !text.contains('\n') && text.contains('\r') {
        return text.split('\r').collect();
    }
    text.split('\n')
        .map(|l| l.strip_suffix('\r').unwrap_or(l))
        .collect()
}

/// The edition the first line names, and whether that line is a marker (not header text).
fn form(first: &str, origin: &str) -> Result<(IesForm, bool), IesError> {
    let compact: String = first
        .chars()
        .filter(|c| !c.is_whitespace())
        .collect::<String>()
        .to_ascii_uppercase();
    let form = match compact.as_str() {
        "IESNA91" => IesForm::Lm1991,
        "IESNA:LM-63-1995" => IesForm::Lm1995,
        "IESNA:LM-63-2002" => IesForm::Lm2002,
        "IES:LM-63-2019" => IesForm::Lm2019,
        other if other.starts_with("IESNA:") || other.starts_with("IES:") => {
            return Err(IesError {
                origin: origin.to_owned(),
                line: 1,
                problem: IesProblem::UnknownForm {
                    line: first.trim().to_owned(),
                },
            })
        }
        _ => return Ok((IesForm::Lm1986, false)),
    };
    Ok((form, true))
}

/// What a `TILT=` line says.
enum TiltLine {
    None,
    Include,
}

/// The header: keyword or text lines up to `TILT=`, the TILT value, and the index
/// of the first line after it.
fn header(
    lines: &[&str],
    start: usize,
    origin: &str,
) -> Result<(Vec<IesKeyword>, TiltLine, usize), IesError> {
    let mut keywords = Vec::new();
    for (i, raw) in lines.iter().enumerate().skip(start) {
        let line = raw.trim();
        let upper = line.to_ascii_uppercase();
        if let Some(rest) = upper.strip_prefix("TILT") {
            if let Some(value) = rest.trim_start().strip_prefix('=') {
                let tilt = match value.trim() {
                    "NONE" => TiltLine::None,
                    "INCLUDE" => TiltLine::Include,
                    _ => {
                        // Name the file as written, not upper-cased.
                        let eq = line.find('=').map_or(line.len(), |p| p + 1);
                        return Err(IesError {
                            origin: origin.to_owned(),
                            line: i + 1,
                            problem: IesProblem::TiltFile {
                                name: line[eq..].trim().to_owned(),
                            },
                        });
                    }
                };
                return Ok((keywords, tilt, i + 1));
            }
        }
        let (keyword, value) = match line.strip_prefix('[').and_then(|r| r.split_once(']')) {
            Some((k, v)) => (k.trim().to_owned(), v.trim().to_owned()),
            None => (String::new(), line.to_owned()),
        };
        keywords.push(IesKeyword {
            keyword,
            value,
            line: i + 1,
        });
    }
    Err(IesError {
        origin: origin.to_owned(),
        line: lines.len(),
        problem: IesProblem::NoTilt,
    })
}

/// The `TILT=INCLUDE` block: geometry, pair count, angles, factors.
fn tilt_block(cursor: &mut Cursor<'_>) -> Result<IesTilt, IesError> {
    let (code, token) = cursor.number("lamp-to-luminaire geometry")?;
    let geometry = match code {
        1.0 => LampGeometry::Vertical,
        2.0 => LampGeometry::HorizontalAlong0To180,
        3.0 => LampGeometry::HorizontalAlong90To270,
        _ => {
            let why = "must be 1 (vertical), 2 or 3 (horizontal)";
            return Err(cursor.invalid(token, "lamp-to-luminaire geometry", why));
        }
    };
    let pairs = cursor.count("number of tilt angles", 1, MAX_TILT_PAIRS)?;
    cursor.ensure(2 * pairs, "tilt angles and factors")?;
    let angles = cursor.ascending_angles(pairs, "tilt angle", -360.0, 360.0)?;
    let factors = cursor.values(pairs, "tilt multiplying factor", |f| {
        (f < 0.0).then_some("must be ≥ 0")
    })?;
    Ok(IesTilt {
        geometry,
        angles,
        factors,
    })
}

/// The thirteen numbers between the TILT data and the angles.
struct Numbers {
    lamps: usize,
    lumens: Option<f64>,
    multiplier: f64,
    nv: usize,
    nh: usize,
    /// The line of the horizontal count, which a too-large table names.
    counts_line: usize,
    opening_m: [f64; 3],
    ballast: f64,
    field_twelve: f64,
    watts: f64,
}

fn positive(v: f64) -> Option<&'static str> {
    (v <= 0.0).then_some("must be greater than 0")
}

/// Reads the thirteen numbers; `form` says whether the twelfth is a factor to check.
fn numbers(cursor: &mut Cursor<'_>, form: IesForm) -> Result<Numbers, IesError> {
    // The lamp count is informational; a cap keeps the rated lumens finite.
    let lamps = cursor.count("number of lamps", 1, 1_000_000)?;
    let (lumens, token) = cursor.number("lumens per lamp")?;
    if lumens != -1.0 && lumens <= 0.0 {
        let why = "must be greater than 0, or -1 for absolute photometry";
        return Err(cursor.invalid(token, "lumens per lamp", why));
    }
    let (multiplier, token) = cursor.number("candela multiplier")?;
    if let Some(why) = positive(multiplier) {
        return Err(cursor.invalid(token, "candela multiplier", why));
    }
    let nv = cursor.count("number of vertical angles", 2, MAX_ANGLES)?;
    let nh = cursor.count("number of horizontal angles", 1, MAX_ANGLES)?;
    let counts_line = cursor.tokens[cursor.next - 1].line;
    let (kind, token) = cursor.number("photometric type")?;
    let letter = match kind {
        1.0 => None,
        2.0 => Some("B"),
        3.0 => Some("A"),
        _ => return Err(cursor.invalid(token, "photometric type", "must be 1, 2 or 3")),
    };
    if let Some(letter) = letter {
        let code = token.text.to_owned();
        return Err(cursor.error(token.line, IesProblem::UnsupportedType { letter, code }));
    }
    let (units, token) = cursor.number("units type")?;
    let metres_per_unit = match units {
        1.0 => 0.3048,
        2.0 => 1.0,
        _ => return Err(cursor.invalid(token, "units type", "must be 1 (feet) or 2 (metres)")),
    };
    let mut opening_m = [0.0; 3];
    for (slot, what) in opening_m.iter_mut().zip(["width", "length", "height"]) {
        *slot = cursor.number(what)?.0 * metres_per_unit;
    }
    let (ballast, token) = cursor.number("ballast factor")?;
    if let Some(why) = positive(ballast) {
        return Err(cursor.invalid(token, "ballast factor", why));
    }
    let (field_twelve, token) = cursor.number("ballast-lamp factor / future use field")?;
    if form.has_ballast_lamp_factor() && field_twelve <= 0.0 {
        let why = "must be greater than 0 (the ballast-lamp photometric factor)";
        return Err(cursor.invalid(token, "ballast-lamp photometric factor", why));
    }
    let (watts, _) = cursor.number("input watts")?;
    Ok(Numbers {
        lamps,
        lumens: (lumens != -1.0).then_some(lumens),
        multiplier,
        nv,
        nh,
        counts_line,
        opening_m,
        ballast,
        field_twelve,
        watts,
    })
}

/// The symmetry the horizontal angles' ends imply (type C), or why they are refused.
fn symmetry(horizontal: &[f64]) -> Result<Symmetry, &'static str> {
    let (first, last) = (horizontal[0], horizontal[horizontal.len() - 1]);
    match (first, last, horizontal.len()) {
        (0.0, 0.0, 1) => Ok(Symmetry::Axial),
        (0.0, 90.0, _) => Ok(Symmetry::Quadrant),
        (0.0, 180.0, _) => Ok(Symmetry::Bilateral),
        (0.0, 360.0, _) => Ok(Symmetry::None),
        (90.0, 270.0, _) => Ok(Symmetry::Bilateral90),
        (_, _, 1) => Err("must be 0 when it is the only horizontal angle"),
        (0.0, _, _) => Err("must end the horizontal angles at 90, 180 or 360 (type C)"),
        _ => Err("must start the horizontal angles at 0 (or 90 for a 90..270 range)"),
    }
}

pub(super) fn parse(text: &str, origin: &str) -> Result<IesProfile, IesError> {
    let lines = lines(text);
    let (form, marked) = form(lines[0], origin)?;
    let (keywords, tilt_line, data_start) = header(&lines, usize::from(marked), origin)?;
    let tokens = lines
        .iter()
        .enumerate()
        .skip(data_start)
        .flat_map(|(i, line)| {
            line.split(|c: char| c.is_whitespace() || c == ',')
                .filter(|t| !t.is_empty())
                .map(move |text| Token { text, line: i + 1 })
        })
        .collect();
    let mut cursor = Cursor {
        tokens,
        next: 0,
        origin,
        last_line: lines.len(),
    };
    let tilt = match tilt_line {
        TiltLine::None => None,
        TiltLine::Include => Some(tilt_block(&mut cursor)?),
    };
    let numbers = numbers(&mut cursor, form)?;
    let ballast_lamp_factor = if form.has_ballast_lamp_factor() {
        numbers.field_twelve
    } else {
        1.0
    };
    let (nv, nh) = (numbers.nv, numbers.nh);
    // Both counts are capped at 10,000, so the product cannot overflow.
    let cells = nv * nh;
    if cells > MAX_CANDELA_VALUES {
        let line = numbers.counts_line;
        let problem = IesProblem::TooMany {
            what: "the number of candela values (vertical × horizontal angles)",
            count: cells as u64,
            cap: MAX_CANDELA_VALUES,
        };
        return Err(cursor.error(line, problem));
    }
    cursor.ensure(nv + nh + cells, "angles and candela values")?;
    let vertical = cursor.ascending_angles(nv, "vertical angle", 0.0, 180.0)?;
    let h_start = cursor.next;
    let horizontal = cursor.ascending_angles(nh, "horizontal angle", 0.0, 360.0)?;
    let symmetry = symmetry(&horizontal).map_err(|why| {
        let ends = if nh == 1 || horizontal[0] != 0.0 {
            0
        } else {
            nh - 1
        };
        cursor.invalid(cursor.tokens[h_start + ends], "horizontal angle", why)
    })?;
    let raw = cursor.values(cells, "candela value", |c| {
        (c < 0.0).then_some("must be ≥ 0")
    })?;
    if let Some(token) = cursor.tokens.get(cursor.next) {
        let problem = IesProblem::TrailingValues {
            token: token.text.to_owned(),
            extra: cursor.remaining(),
        };
        return Err(cursor.error(token.line, problem));
    }
    Ok(IesProfile {
        form,
        keywords,
        tilt,
        lamp_count: u32::try_from(numbers.lamps).unwrap_or(u32::MAX),
        lumens_per_lamp: numbers.lumens,
        candela_multiplier: numbers.multiplier,
        opening_m: numbers.opening_m,
        ballast_factor: numbers.ballast,
        ballast_lamp_factor,
        field_twelve: numbers.field_twelve,
        input_watts: numbers.watts,
        vertical,
        horizontal,
        raw,
        symmetry,
    })
}
