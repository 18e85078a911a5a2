//! Which solution method a solve runs (`--method`, TOML `method`), chosen and
//! checked against the mode before any work.
//!
//! Progressive refinement (Remington 1992, §3.7) is the method: it solves
//! diffuse mode with one radiance per vertex and directional mode with
//! spherical harmonics, shooting, refining and checkpointing alike. The others
//! are the seed papers' baselines, kept at the scope those papers measured:
//! progressive refinement with a hemicube's or Wallace's form factor, the
//! full-matrix Gauss–Seidel gather (diffuse), and Immel, Cohen and
//! Greenberg's (1986) global cube (directional).

use crate::settings::{DirectionalRepresentation, FormFactorMethod};
use serde::{Deserialize, Serialize};
use solution::format::SolveMode;

/// A solution method.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
#[derive(clap::ValueEnum)]
pub enum Method {
    /// Progressive refinement with the exact form factor; diffuse or directional (SH).
    #[default]
    Progressive,
    /// Progressive refinement with visibility from a hemicube on the source (diffuse only).
    Hemicube,
    /// Progressive refinement with Wallace's disc form factor (Remington 1992, eq. 3.1; diffuse only).
    Wallace,
    /// The full form-factor matrix gathered by Gauss–Seidel sweeps (diffuse only).
    GaussSeidel,
    /// Immel, Cohen and Greenberg's (1986) global cube, gathered by Gauss–Seidel (directional only).
    Cube,
}

/// What a solve with a method runs: progressive refinement (which checkpoints
/// and resumes) or one of the one-call gathers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Dispatch {
    Progressive,
    GaussSeidel,
    Cube,
}

impl Method {
    /// The name `--method` and the TOML key take.
    pub fn name(self) -> &'static str {
        match self {
            Method::Progressive => "progressive",
            Method::Hemicube => "hemicube",
            Method::Wallace => "wallace",
            Method::GaussSeidel => "gauss-seidel",
            Method::Cube => "cube",
        }
    }

    /// The point-to-source form factor a progressive shot uses.
    pub fn form_factors(self) -> FormFactorMethod {
        match self {
            Method::Hemicube => FormFactorMethod::Hemicube,
            Method::Wallace => FormFactorMethod::Wallace,
            _ => FormFactorMethod::Analytic,
        }
    }

    /// How directional mode stores glossy radiance under this method.
    pub fn directional(self) -> DirectionalRepresentation {
        match self {
            Method::Cube => DirectionalRepresentation::Cube,
            _ => DirectionalRepresentation::Sh,
        }
    }

    /// Which solve runs.
    pub fn dispatch(self) -> Dispatch {
        match self {
            Method::Progressive | Method::Hemicube | Method::Wallace => Dispatch::Progressive,
            Method::GaussSeidel => Dispatch::GaussSeidel,
            Method::Cube => Dispatch::Cube,
        }
    }

    /// The one mode this method solves, or `None` for both.
    pub fn only_mode(self) -> Option<SolveMode> {
        match self {
            Method::Progressive => None,
            Method::Hemicube | Method::Wallace | Method::GaussSeidel => Some(SolveMode::Diffuse),
            Method::Cube => Some(SolveMode::Directional),
        }
    }

    /// Refuses a mode the method does not solve, naming both. The baselines
    /// stay at the scope their papers measured: Gauss–Seidel and the two
    /// factors were diffuse radiosity, the global cube is directional.
    pub fn check_mode(self, mode: SolveMode) -> Result<(), String> {
        match self.only_mode() {
            Some(only) if only != mode => Err(format!(
                "--method {} solves {} mode only, and the mode is {} (--mode or the scene \
                 config's `mode`); use --method progressive{}",
                self.name(),
                mode_name(only),
                mode_name(mode),
                if mode == SolveMode::Directional {
                    " for glossy surfaces"
                } else {
                    " for a diffuse solve"
                }
            )),
            _ => Ok(()),
        }
    }
}

fn mode_name(mode: SolveMode) -> &'static str {
    match mode {
        SolveMode::Diffuse => "diffuse",
        SolveMode::Directional => "directional",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const ALL: [Method; 5] = [
        Method::Progressive,
        Method::Hemicube,
        Method::Wallace,
        Method::GaussSeidel,
        Method::Cube,
    ];

    #[test]
    fn each_method_dispatches_to_its_solve_with_its_form_factor_and_representation() {
        use DirectionalRepresentation::{Cube, Sh};
        use FormFactorMethod::{Analytic, Hemicube, Wallace};
        let expected = [
            (Dispatch::Progressive, Analytic, Sh),
            (Dispatch::Progressive, Hemicube, Sh),
            (Dispatch::Progressive, Wallace, Sh),
            (Dispatch::GaussSeidel, Analytic, Sh),
            (Dispatch::Cube, Analytic, Cube),
        ];
        for (method, want) in ALL.into_iter().zip(expected) {
            assert_eq!(
                (
                    method.dispatch(),
                    method.form_factors(),
                    method.directional()
                ),
                want,
                "{method:?}"
            );
        }
    }

    #[test]
    fn incompatible_modes_are_refused_naming_the_method_and_the_mode() {
        for method in ALL {
            for mode in [SolveMode::Diffuse, SolveMode::Directional] {
                let result = method.check_mode(mode);
                let allowed = method.only_mode().is_none_or(|m| m == mode);
                assert_eq!(result.is_ok(), allowed, "{method:?} {mode:?}");
                if let Err(message) = result {
                    assert!(message.contains(method.name()), "{message}");
                    assert!(message.contains(mode_name(mode)), "{message}");
                }
            }
        }
        // The example: Gauss–Seidel in directional mode used to run the cube.
        let err = Method::GaussSeidel
            .check_mode(SolveMode::Directional)
            .unwrap_err();
        assert!(err.contains("--method gauss-seidel solves diffuse mode only"));
    }

    #[test]
    fn names_round_trip_through_the_toml_key() {
        for method in ALL {
            let text = format!("method = \"{}\"", method.name());
            #[derive(Deserialize)]
            struct Key {
                method: Method,
            }
            let key: Key = toml::from_str(&text).unwrap();
            assert_eq!(key.method, method);
        }
    }
}
