//! [`SettingsPatch`]: the one declaration of every setting a source can set.
//!
//! The same struct is the `[solver]` table of a TOML scene config, a preset
//! of `config/presets.toml` and a legacy display file's settings (serde), and
//! the settings flags of `solver solve` (clap, flattened into `SolveArgs`).
//! A field with `#[arg(skip)]` is a TOML key only. The macro below also
//! writes [`SettingsPatch::assign`] from the same list, so no setting can be
//! declared and then forgotten when patches are applied.

use super::{Shooters, SolverSettings};
use crate::method::Method;
use clap::builder::TypedValueParser;
use serde::{Deserialize, Serialize};
use solution::format::SolveMode;

/// Declares the struct as written and an `assign` that copies each field it
/// sets onto the field of the same name of [`SolverSettings`] (through
/// `From`, so an `Option<usize>` setting such as `threads` takes a `usize`).
macro_rules! settings_patch {
    (
        $(#[$struct_meta:meta])*
        pub struct SettingsPatch {
            $( $(#[$meta:meta])* pub $field:ident: $ty:ty, )*
        }
    ) => {
        $(#[$struct_meta])*
        pub struct SettingsPatch {
            $( $(#[$meta])* pub $field: $ty, )*
        }

        impl SettingsPatch {
            /// Overwrites every field of `settings` that this patch sets, by name.
            pub(super) fn assign(&self, settings: &mut SolverSettings) {
                $(
                    if let Some(value) = self.$field.clone() {
                        settings.$field = value.into();
                    }
                )*
            }
        }
    };
}

settings_patch! {
    /// A partial set of settings from one source (flags, TOML config, display
    /// file, preset): every field optional, `None` leaving it to lower sources.
    /// The fields that are flags come in `solver solve --help`'s order.
    #[derive(Clone, Debug, PartialEq, Default, Serialize, Deserialize, clap::Args)]
    #[serde(deny_unknown_fields)]
    pub struct SettingsPatch {
        /// Visibility rays per receiving vertex and source patch.
        #[arg(
            long,
            value_name = "N",
            long_help = "Visibility rays per receiving vertex and source patch (1 to 4096). \
                More rays give smoother penumbrae, at a cost that grows about linearly \
                with N."
        )]
        pub samples: Option<u32>,

        /// Stop when unshot power falls below this fraction of emitted power.
        #[arg(
            long,
            value_name = "X",
            long_help = "Stop when the unshot power falls below X times the emitted power (0 < \
                X < 1). Smaller is more accurate and costs more shots."
        )]
        pub threshold: Option<f64>,

        /// Stop after this many shots whatever the unshot power.
        #[arg(
            long,
            value_name = "N",
            long_help = "Stop after N shots, converged or not: a time budget, whose checkpoint \
                --resume continues. A solve stopped by it above its threshold writes a \
                partial file and exits with status 4."
        )]
        pub max_shots: Option<u64>,

        /// Seed of the jittered sample positions.
        #[arg(
            long,
            value_name = "S",
            long_help = "Seed of the jittered visibility samples. The same seed and settings \
                give the same file bit for bit, on any thread count."
        )]
        pub seed: Option<u64>,

        /// Worker threads (default: every core).
        #[arg(
            long,
            value_name = "N",
            long_help = "Worker threads (1 to 1024; default every core). Speed only: the result \
                does not depend on it."
        )]
        pub threads: Option<usize>,

        /// Trace no visibility rays: no shadows, much faster.
        #[arg(
            long = "no-shadows",
            num_args = 0,
            default_missing_value = "false",
            long_help = "Trace no visibility rays, so nothing casts a shadow (Remington 1992, \
                appendix D `-t`). Much faster; for checking a scene, not for results."
        )]
        pub shadows: Option<bool>,

        /// What shoots in one pass: patch (default) or grouped.
        #[arg(
            long,
            value_enum,
            value_name = "WHO",
            long_help = "What shoots in one pass. grouped (every preset): a bright patch and \
                its bright neighbours together, each receiver's rays shared among them \
                by importance, far fewer passes where many small patches are lit; \
                patch: one patch per shot, as Remington (1992). Emitters' first \
                shots shoot alone in directional mode \
                (docs/lab/grouped-shooters.md, docs/lab/glossy-grouped-shooters.md).",
            hide_possible_values = true
        )]
        pub shooters: Option<Shooters>,

        /// Visibility rays per receiving vertex for a grouped shot.
        #[arg(
            long,
            value_name = "N",
            long_help = "Visibility rays per receiving vertex for a grouped shot (1 to 4096), \
                shared among its members by what each adds; a glossy receiver in directional \
                mode traces several times as many. More rays lower the noise \
                between seeds; time grows with N where shots are bright \
                (docs/lab/grouped-shooters.md)."
        )]
        pub group_samples: Option<u32>,

        /// Hemicube cells per side of the top face (even, 2 to 2048).
        #[arg(
            long,
            value_name = "R",
            long_help = "Cells per side of a hemicube's top face for --method hemicube and \
                gauss-seidel (even, 2 to 2048; default 128). The factor's error falls \
                like 1/R; time grows like R²."
        )]
        pub hemicube_resolution: Option<u32>,

        /// progressive (default), or a seed baseline: hemicube, wallace, gauss-seidel, cube.
        #[arg(
            long,
            value_enum,
            value_name = "METHOD",
            long_help = "progressive (default): progressive refinement with exact form factors, \
                adaptive meshing and checkpoints, in either mode. The seed papers' \
                baselines, to measure against: hemicube, wallace and gauss-seidel \
                (diffuse only) and cube (directional only; no textures or smooth \
                surfaces). A method that cannot solve the scene is refused before any \
                work (docs/guide.md, \"The method\").",
            hide_possible_values = true
        )]
        pub method: Option<Method>,

        /// diffuse (default) or directional (glossy, spherical harmonics).
        #[arg(
            long,
            value_parser = solve_mode_parser(),
            value_name = "MODE",
            long_help = "diffuse (default): one radiance per vertex; a glossy material's Ks is \
                folded into its Kd (per channel, capped at 1), with a warning. \
                directional: glossy surfaces store outgoing radiance as spherical \
                harmonics, so highlights follow the viewer, at a cost in time and file \
                size that grows with the square of the SH order.",
            hide_possible_values = true
        )]
        pub mode: Option<SolveMode>,

        /// Global-cube cells per face edge k (2 to 256): D = 6k² directions.
        #[arg(
            long,
            value_name = "K",
            long_help = "Cells per cube face edge k for --method cube (2 to 256; default 8): D \
                = 6k² directions per glossy vertex. Larger k gives sharper, better \
                placed highlights; memory and time grow like k² to k⁴."
        )]
        pub cube_resolution: Option<u32>,

        /// Target patch size, as a fraction of the scene's bounding-box diagonal.
        #[arg(
            long,
            value_name = "F",
            long_help = "Target patch size as a fraction of the scene's diagonal (0 < F <= 1): \
                a polygon gets N × N patches, N = ceil(longest edge / (F × diagonal)). \
                Smaller F costs time and memory for less meshing bias; a TOML config \
                may set it per object or material."
        )]
        pub patch_size: Option<f64>,

        /// Smallest element's longest edge, as a fraction of the scene's diagonal.
        #[arg(
            long,
            value_name = "F",
            long_help = "Adaptive subdivision stops at elements of this fraction of the scene's \
                diagonal (0 < F <= 1), on every polygon alike. Smaller F follows \
                shadows and gradients more closely, at the cost of more elements, rays \
                and memory."
        )]
        pub min_element_size: Option<f64>,

        /// Scene units per metre (e.g. 1000 for millimetres).
        #[arg(
            long,
            value_name = "U",
            long_help = "How many scene units make a metre (default 1, or the scene config's). \
                The runtime scales head tracking, walking and eye separation by it; \
                the lighting does not change."
        )]
        pub units_per_metre: Option<f64>,

        // A TOML config gives bytes; the flag also takes a unit.
        /// Peak memory the solve plans within (e.g. 8GiB, 500MB).
        #[arg(
            long,
            value_name = "SIZE",
            value_parser = parse_bytes,
            long_help = "Peak memory the solve plans within, e.g. 8GiB or 500MB (default: 80% \
                of available memory). Near it glossy SH orders are capped and \
                refinement stops, each with a warning; a scene that cannot fit is \
                refused before allocating."
        )]
        pub memory_budget: Option<u64>,

        /// Make import warnings errors.
        #[arg(
            long,
            num_args = 0,
            default_missing_value = "true",
            long_help = "Turn import warnings (Kd + Ks above 1 scaled down, degenerate or \
                non-planar faces, …) into errors, for scenes that must import cleanly."
        )]
        pub strict: Option<bool>,

        /// Save a checkpoint and a partial solution every K shots.
        #[arg(
            long,
            value_name = "K",
            long_help = "Every K shots, save OUT.checkpoint and rewrite OUT as a partial \
                solution a viewer can watch. Smaller K loses less work on a crash; \
                each save costs writing the whole mesh."
        )]
        pub checkpoint_every: Option<u64>,

        /// Do not add the ambient estimate of unshot light to partial solutions.
        #[arg(
            long = "no-ambient",
            num_args = 0,
            default_missing_value = "false",
            long_help = "Leave out Cohen et al.'s (1988) ambient estimate of the light not yet \
                shot, which files otherwise carry (in diffuse mode weighted by each \
                vertex's enclosure). Partial solutions then look darker but hold only \
                light actually shot (docs/lab/ambient-term.md)."
        )]
        pub ambient: Option<bool>,

        /// Degrees of shading-normal change a finely tessellated smooth surface's sites span (0: every point receives).
        #[arg(
            long,
            value_name = "DEGREES",
            long_help = "A smooth surface exported finer than the smallest element receives at \
                sites, one within that size and this shading-normal angle of every \
                point (default 10 degrees; 0: every point receives). Smaller angles \
                add sites and cost, and blur the shading less; diffuse mode \
                (docs/lab/sites.md)."
        )]
        pub site_angle: Option<f64>,

        /// Largest angle (degrees) between neighbouring polygons that still shade as one smooth surface.
        #[arg(
            long,
            value_name = "DEGREES",
            long_help = "Neighbouring polygons of one material whose normals differ by less \
                than this angle (default 30 degrees) shade as one smooth surface with \
                shared vertices. A larger angle rounds off edges meant to be sharp; 0 \
                keeps every polygon a flat facet."
        )]
        pub crease_angle: Option<f64>,

        // The keys below are TOML only (scene configs and presets): tuning that
        // the presets choose and no command line needs. `SolverSettings` says
        // what each means.
        /// A receiver gets all `samples` rays only from shots that add at
        /// least this fraction of its light, fewer in proportion below (0 to
        /// 1; 0 traces every ray): unbiased, only noisier; every preset's
        /// 0.01 halves the Cornell box's final time at the same error
        /// (docs/lab/ray-share.md).
        #[arg(skip)]
        pub full_rays_above: Option<f64>,
        /// Directional mode: glossy elements stop splitting at an edge of
        /// K × α × half the scene's diagonal, α the lobe's RMS slope
        /// (final's 0.125 takes twice 0.25's time;
        /// docs/lab/glossy-final-floor.md).
        #[arg(skip)]
        pub glossy_edge: Option<f64>,
        #[arg(skip)]
        pub adaptive: Option<bool>,
        #[arg(skip)]
        pub edge_threshold: Option<f64>,
        #[arg(skip)]
        pub shadow_threshold: Option<f64>,
        #[arg(skip)]
        pub max_depth: Option<u32>,
        #[arg(skip)]
        pub sh_error_target: Option<f64>,
        #[arg(skip)]
        pub max_sh_order: Option<u32>,
    }
}

/// `--mode`'s parser. `SolveMode` lives in the contract crate, which does not depend
/// on clap, so the command line maps its names here.
pub(crate) fn solve_mode_parser() -> impl clap::builder::TypedValueParser<Value = SolveMode> {
    clap::builder::PossibleValuesParser::new(["diffuse", "directional"]).map(|name| {
        match name.as_str() {
            "directional" => SolveMode::Directional,
            _ => SolveMode::Diffuse,
        }
    })
}

/// A size for `--memory-budget`: a non-negative number of bytes, optionally
/// with a unit, KB/MB/GB/TB (powers of 1000) or KiB/MiB/GiB/TiB (powers of
/// 1024), case-insensitive, with or without a space (`8GiB`, `500 MB`,
/// `1.5GiB`, `1048576`).
pub fn parse_bytes(text: &str) -> Result<u64, String> {
    let t = text.trim();
    let split = t
        .find(|c: char| !(c.is_ascii_digit() || c == '.'))
        .unwrap_or(t.len());
    let (number, unit) = (t[..split].trim(), t[split..].trim());
    let value: f64 = number
        .parse()
        .map_err(|_| format!("`{text}` is not a size: expected a number such as 8GiB or 500MB"))?;
    let scale: f64 = match unit.to_ascii_lowercase().as_str() {
        "" | "b" => 1.0,
        "kb" => 1e3,
        "mb" => 1e6,
        "gb" => 1e9,
        "tb" => 1e12,
        "kib" => 1024.0,
        "mib" => 1024.0 * 1024.0,
        "gib" => 1024.0 * 1024.0 * 1024.0,
        "tib" => 1024.0 * 1024.0 * 1024.0 * 1024.0,
        _ => {
            return Err(format!(
                "`{text}`: unknown unit `{unit}` (use B, KB, MB, GB, TB, KiB, MiB, GiB or TiB)"
            ))
        }
    };
    let bytes = value * scale;
    if !bytes.is_finite() || bytes >= u64::MAX as f64 {
        return Err(format!("`{text}` is too large"));
    }
    Ok(bytes.round() as u64)
}
