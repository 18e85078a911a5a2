//! The flags of `solver solve` and the settings patch they make.

use clap::builder::TypedValueParser;
use solution::format::SolveMode;

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
use crate::method::Method;
use crate::settings::{Preset, SettingsPatch, Shooters};
use std::path::PathBuf;

/// Exit code of a solve stopped by Ctrl-C after saving its checkpoint (128 + SIGINT,
/// as shells report an interrupted program).
pub const EXIT_INTERRUPTED: u8 = 130;

const AFTER_LONG_HELP: &str = "\
Exit codes: 0 done, 1 error, 2 bad command line, 130 Ctrl-C (saved; --resume goes on).";

/// `solver solve SCENE -o OUT …`: flags map one to one onto [`SettingsPatch`].
#[derive(clap::Args, Debug, Clone)]
#[command(after_long_help = AFTER_LONG_HELP)]
pub struct SolveArgs {
    /// The scene: `.obj` (+ `.mtl`), `.gltf` / `.glb` (glTF 2.0, metres; docs/gltf.md), `.toml` scene config or a legacy geometry file.
    #[arg(value_name = "SCENE")]
    pub scene: PathBuf,

    /// Where to write the solution file.
    #[arg(short, long, value_name = "OUT")]
    pub out: PathBuf,

    /// Quality preset: draft, medium (default) or final.
    #[arg(
        long,
        value_enum,
        value_name = "PRESET",
        long_help = "A full set of defaults from config/presets.toml: draft is fastest and \
            noisiest, medium (default) shows no noise, final is the most accurate and \
            about 7 times slower than medium. The scene config, a display file and the \
            flags override its values, in that order (docs/guide.md, \"Presets\").",
        hide_possible_values = true
    )]
    pub preset: Option<Preset>,

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
            --resume continues."
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
        long,
        long_help = "Trace no visibility rays, so nothing casts a shadow (Remington 1992, \
            appendix D `-t`). Much faster; for checking a scene, not for results."
    )]
    pub no_shadows: bool,

    /// Visibility rays in proportion to what a shot adds, below this fraction of a receiver's light.
    #[arg(
        long,
        value_name = "FRACTION",
        long_help = "A receiver gets all --samples rays only from shots that add at least \
            this fraction of its light, fewer in proportion below (0 to 1; 0 \
            traces every ray). The estimate stays unbiased and only its noise \
            grows; every preset's 0.01 halves the Cornell box's final time at the \
            same error (docs/lab/ray-share.md)."
    )]
    pub full_rays_above: Option<f64>,

    /// Smallest element edge on a glossy surface, as K × α × half the scene's diagonal.
    #[arg(
        long,
        value_name = "K",
        long_help = "Directional mode: glossy elements stop splitting at an edge of K × α × \
            half the scene's diagonal, α the lobe's RMS slope. Smaller K gives \
            sharper highlights for more elements and time (final's 0.125 takes \
            twice 0.25's time; docs/lab/glossy-final-floor.md)."
    )]
    pub glossy_edge: Option<f64>,

    /// What shoots in one pass: patch (default) or grouped.
    #[arg(
        long,
        value_enum,
        value_name = "WHO",
        long_help = "What shoots in one pass. grouped (every preset): a bright patch and \
            its bright neighbours together, each receiver's rays shared among them \
            by importance, far fewer passes where many small patches are lit; \
            patch: one patch per shot, as Remington (1992). Diffuse mode only \
            (docs/lab/grouped-shooters.md).",
        hide_possible_values = true
    )]
    pub shooters: Option<Shooters>,

    /// Visibility rays per receiving vertex for a grouped shot.
    #[arg(
        long,
        value_name = "N",
        long_help = "Visibility rays per receiving vertex for a grouped shot (1 to 4096), \
            shared among its members by what each adds. More rays lower the noise \
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
        long_help = "diffuse (default): one radiance per vertex, MTL Ks ignored. \
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
        long_help = "Turn import warnings (Kd + Ks above 1 scaled down, degenerate or \
            non-planar faces, …) into errors, for scenes that must import cleanly."
    )]
    pub strict: bool,

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
        long,
        long_help = "Leave out Cohen et al.'s (1988) ambient estimate of the light not yet \
            shot, which files otherwise carry (in diffuse mode weighted by each \
            vertex's enclosure). Partial solutions then look darker but hold only \
            light actually shot (docs/lab/ambient-term.md)."
    )]
    pub no_ambient: bool,

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

    /// Continue the solve saved in OUT.checkpoint.
    #[arg(
        long,
        long_help = "Continue the solve saved in OUT.checkpoint after Ctrl-C, a crash or a \
            shot budget; the scene and the result-affecting settings must be the \
            same. The result equals an uninterrupted solve's."
    )]
    pub resume: bool,

    /// Legacy display parameter file (Remington 1992, appendix A).
    #[arg(
        long,
        value_name = "FILE",
        long_help = "A legacy display parameter file (Remington 1992, appendix A): its \
            camera serves --preview and the solution when the scene names none; \
            its ambient and threshold lines are the lowest-precedence settings."
    )]
    pub display: Option<PathBuf>,

    /// Also write a tone-mapped PNG rendering of the solution.
    #[arg(
        long,
        value_name = "PNG",
        long_help = "Also render the finished solution on the CPU from the scene's camera \
            and write it as a tone-mapped sRGB PNG."
    )]
    pub preview: Option<PathBuf>,

    /// Write the closing summary as JSON.
    #[arg(
        long,
        value_name = "FILE",
        long_help = "Write the closing summary (elements, vertices, shots, rays, seconds, \
            rays per second, threads, unshot fraction) as one JSON object."
    )]
    pub stats_json: Option<PathBuf>,
}

impl SolveArgs {
    /// The preset, medium when none is named.
    pub fn preset(&self) -> Preset {
        self.preset.unwrap_or_default()
    }

    /// The settings these flags set; everything else is left to lower sources.
    pub fn patch(&self) -> SettingsPatch {
        SettingsPatch {
            mode: self.mode,
            cube_resolution: self.cube_resolution,
            method: self.method,
            full_rays_above: self.full_rays_above,
            glossy_edge: self.glossy_edge,
            shooters: self.shooters,
            group_samples: self.group_samples,
            samples: self.samples,
            hemicube_resolution: self.hemicube_resolution,
            shadows: self.no_shadows.then_some(false),
            threshold: self.threshold,
            max_shots: self.max_shots,
            seed: self.seed,
            threads: self.threads,
            checkpoint_every: self.checkpoint_every,
            ambient: self.no_ambient.then_some(false),
            units_per_metre: self.units_per_metre,
            strict: self.strict.then_some(true),
            crease_angle: self.crease_angle,
            memory_budget: self.memory_budget,
            patch_size: self.patch_size,
            min_element_size: self.min_element_size,
            site_angle: self.site_angle,
            ..SettingsPatch::default()
        }
    }
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

/// Which flag sets a setting, for error messages (`samples` → `--samples`).
pub fn flag_name(setting: &str) -> String {
    match setting {
        "shadows" => "--no-shadows".into(),
        "ambient" => "--no-ambient".into(),
        other => format!("--{}", other.replace('_', "-")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::settings::SolverSettings;
    use clap::Parser;

    #[derive(Parser)]
    struct Wrapper {
        #[command(flatten)]
        args: SolveArgs,
    }

    fn parse(extra: &[&str]) -> SolveArgs {
        let mut argv = vec!["solver", "scene.obj", "-o", "out.sol"];
        argv.extend_from_slice(extra);
        Wrapper::try_parse_from(argv).unwrap().args
    }

    #[test]
    fn unset_flags_leave_the_patch_empty() {
        assert_eq!(parse(&[]).patch(), SettingsPatch::default());
    }

    #[test]
    fn flags_become_the_patch() {
        let args = parse(&[
            "--samples",
            "9",
            "--threshold",
            "0.25",
            "--no-shadows",
            "--no-ambient",
            "--strict",
            "--method",
            "wallace",
            "--mode",
            "directional",
            "--threads",
            "3",
            "--patch-size",
            "0.05",
            "--min-element-size",
            "0.01",
        ]);
        let p = args.patch();
        assert_eq!(p.samples, Some(9));
        assert_eq!(p.threshold, Some(0.25));
        assert_eq!(p.shadows, Some(false));
        assert_eq!(p.ambient, Some(false));
        assert_eq!(p.strict, Some(true));
        assert_eq!(p.method, Some(Method::Wallace));
        assert_eq!(p.mode, Some(SolveMode::Directional));
        assert_eq!(p.threads, Some(3));
        assert_eq!(p.patch_size, Some(0.05));
        assert_eq!(p.min_element_size, Some(0.01));
        // The global flat rule is gone.
        for flag in ["--patches", "--min-element-area"] {
            let argv = ["solver", "scene.obj", "-o", "out.sol", flag, "4"];
            assert!(Wrapper::try_parse_from(argv).is_err(), "{flag}");
        }
    }

    #[test]
    fn memory_budget_sizes_parse_with_units() {
        assert_eq!(parse_bytes("8GiB"), Ok(8 << 30));
        assert_eq!(parse_bytes("500MB"), Ok(500_000_000));
        assert_eq!(parse_bytes("1.5 gib"), Ok(3 << 29));
        assert_eq!(parse_bytes("1048576"), Ok(1 << 20));
        assert_eq!(parse_bytes("64KiB"), Ok(64 << 10));
        assert!(parse_bytes("8 parsecs")
            .unwrap_err()
            .contains("unknown unit"));
        assert!(parse_bytes("lots").unwrap_err().contains("not a size"));
        assert!(parse_bytes("-1GiB").is_err());
        assert_eq!(
            parse(&["--memory-budget", "2GiB"]).patch().memory_budget,
            Some(2 << 30)
        );
    }

    #[test]
    fn site_angle_flag_and_toml_key_reach_the_settings() {
        // 10° unless asked for; 0 turns the sites off; above 30° is refused.
        let default = SolverSettings::resolve(Preset::Draft, &[&parse(&[]).patch()]).unwrap();
        assert_eq!(default.site_angle, crate::settings::DEFAULT_SITE_ANGLE);
        let flag = parse(&["--site-angle", "0"]).patch();
        assert_eq!(
            SolverSettings::resolve(Preset::Draft, &[&flag])
                .unwrap()
                .site_angle,
            0.0
        );
        let config: SettingsPatch = toml::from_str("site_angle = 5.0").unwrap();
        assert_eq!(
            SolverSettings::resolve(Preset::Draft, &[&config])
                .unwrap()
                .site_angle,
            5.0
        );
        let wide = parse(&["--site-angle", "45"]).patch();
        let error = SolverSettings::resolve(Preset::Draft, &[&wide]).unwrap_err();
        assert!(error.to_string().contains("site_angle"), "{error}");
    }

    #[test]
    fn shooters_flag_and_toml_key_reach_the_settings() {
        // Grouped shots in every preset unless asked for one patch a shot; a
        // grouped shot's rays from the preset, at least the patch shot's.
        for preset in [Preset::Draft, Preset::Medium, Preset::Final] {
            let default = SolverSettings::resolve(preset, &[&parse(&[]).patch()]).unwrap();
            assert_eq!(default.shooters, Shooters::Grouped);
            assert!(default.group_samples >= default.samples);
            let patch = parse(&["--shooters", "patch"]).patch();
            let resolved = SolverSettings::resolve(preset, &[&patch]).unwrap();
            assert_eq!(resolved.shooters, Shooters::Patch);
        }
        let flag = parse(&["--shooters", "grouped", "--group-samples", "48"]).patch();
        assert_eq!(flag.shooters, Some(Shooters::Grouped));
        assert_eq!(flag.group_samples, Some(48));
        let config: SettingsPatch =
            toml::from_str("shooters = \"grouped\"\ngroup_samples = 24").unwrap();
        let resolved =
            SolverSettings::resolve(Preset::Draft, &[&config, &parse(&[]).patch()]).unwrap();
        assert_eq!(resolved.shooters, Shooters::Grouped);
        assert_eq!(resolved.group_samples, 24);
        let zero: SettingsPatch = toml::from_str("group_samples = 0").unwrap();
        let err = SolverSettings::resolve(Preset::Draft, &[&zero]).unwrap_err();
        assert_eq!(err.name, "group_samples");
        assert!(toml::from_str::<SettingsPatch>("shooters = \"clusters\"").is_err());
    }

    #[test]
    fn flag_names_match_the_command_line() {
        assert_eq!(flag_name("max_shots"), "--max-shots");
        assert_eq!(flag_name("shadows"), "--no-shadows");
    }
}
