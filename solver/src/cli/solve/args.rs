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
Settings come from four places; a higher one overrides a lower one key by key:
  1. these flags
  2. the TOML scene config (when SCENE is a .toml file)
  3. the legacy display file (--display, Remington 1992, appendix A)
  4. the preset (--preset, default medium; config/presets.toml)
Meshing is size-driven (--patch-size, --min-element-size, fractions of the scene
diagonal); a TOML config's objects and a legacy geometry file may give a polygon
its own patch count.

No lost work: every --checkpoint-every shots the solver saves OUT.checkpoint and
rewrites OUT as a valid solution marked partial, which a viewer can watch. Ctrl-C
stops after the current shot, saves both and exits with code 130; run the same
command again with --resume to continue. A solve that ends at its shot budget
before reaching the threshold keeps its checkpoint too, so --resume with a larger
--max-shots carries on. The checkpoint is removed once the solve converges.

Exit codes: 0 done, 1 error, 2 bad command line, 130 interrupted (resumable).";

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
        long_help = "Quality preset: a full set of defaults from config/presets.toml, \
            chosen against a path-traced truth (docs/accuracy.md). draft: a coarse mesh \
            and a loose threshold, under a second for the Cornell box, with visible \
            noise in penumbrae (about 4% error). medium (default): enough rays that \
            two seeds look alike, about 3 s for the Cornell box on two cores (about 2.3% \
            error). final: a fine mesh, about 7 times slower than medium (about 1.4% \
            error, about 21 s). Any other flag overrides the preset's value."
    )]
    pub preset: Option<Preset>,

    /// Visibility rays per receiving vertex and source patch.
    #[arg(
        long,
        value_name = "N",
        long_help = "Visibility rays per receiving vertex and source patch (1 to 4096). \
            More rays give smoother penumbrae and less shadow noise. Time grows about \
            linearly with N where shots are bright; with --full-rays-above (every preset: \
            0.01) a receiver gets all N only from shots that add at least that share of \
            its light, so late, dim shots cost far less than N rays each."
    )]
    pub samples: Option<u32>,

    /// Stop when unshot power falls below this fraction of emitted power.
    #[arg(
        long,
        value_name = "X",
        long_help = "Stop when the total unshot power falls below X times the total \
            emitted power (0 < X < 1). Smaller is more accurate (more interreflected \
            light is accounted for) and costs more shots; halving X costs roughly a \
            constant number of extra shots per halving."
    )]
    pub threshold: Option<f64>,

    /// Stop after this many shots whatever the unshot power.
    #[arg(
        long,
        value_name = "N",
        long_help = "Stop after N shots whatever the unshot power: a time budget. The \
            result is then less converged than the threshold asks; the checkpoint is \
            kept so that --resume with a larger N continues."
    )]
    pub max_shots: Option<u64>,

    /// Seed of the jittered sample positions.
    #[arg(
        long,
        value_name = "S",
        long_help = "Seed of the stratified, jittered visibility samples. The same seed \
            and settings give the same solution bit for bit, with any thread count; \
            another seed gives other (equally valid) shadow noise."
    )]
    pub seed: Option<u64>,

    /// Worker threads (default: every core).
    #[arg(
        long,
        value_name = "N",
        long_help = "Worker threads (1 to 1024; default every core). Speed only: the \
            result does not depend on it."
    )]
    pub threads: Option<usize>,

    /// Trace no visibility rays: no shadows, much faster.
    #[arg(
        long,
        long_help = "Trace no visibility rays (Remington 1992, appendix D `-t`): every vertex sees \
            every source, so there are no shadows. Much faster; for checking a scene, \
            not for results."
    )]
    pub no_shadows: bool,

    /// Visibility rays in proportion to what a shot adds, below this fraction of a receiver's light.
    #[arg(
        long,
        value_name = "FRACTION",
        long_help = "A receiver gets every one of --samples visibility rays from a shot \
            whose unoccluded contribution is at least this fraction of the light it \
            already holds (its radiance plus the reflected ambient term); below, it gets \
            rays in proportion, at least one (0 to 1; 0 traces every ray, the thesis's \
            method). The estimate stays unbiased; only its noise grows, where the shot's \
            share is small: at most sqrt(FRACTION / (4 x samples)) of a vertex's radiance \
            in all. Larger: fewer rays late in a solve of many small patches, where most \
            shots are dim. An emitting patch's own shots, which refinement replays, keep every ray. Every preset uses \
            0.01: the Cornell box's final solve takes 21 s instead of 37 s at the same \
            error against the path-traced truth (1.44% against 1.43%, docs/lab/ray-share.md)."
    )]
    pub full_rays_above: Option<f64>,

    /// Smallest element edge on a glossy surface, as K × α × half the scene's diagonal.
    #[arg(
        long,
        value_name = "K",
        long_help = "Directional mode: adaptive subdivision of a glossy surface stops at \
            elements whose longest edge is K × α × D, with α the lobe's RMS slope and D \
            half the scene's diagonal (the distance its surfaces are seen from). The \
            preset's --min-element-size floors every surface as well. Where a lobe \
            varies, the split test refines toward this floor: an edge splits when the \
            radiance an eye at distance D sees can turn by more than the edge threshold \
            along it. A highlight's \
            width on a surface is about 2α·D_e, with D_e the harmonic mean of the eye's \
            and the source's distances over two; K = 0.25 puts four vertices across it. \
            Smaller K: sharper highlights and reflections, at the cost of more \
            elements, each with (L+1)² coefficients per channel. Default: the preset's \
            (0.5 for draft and medium, 0.125 for final: on the glossy Cornell box it \
            meets HDR-FLIP 0.06 from both cameras, where 0.25 misses it from the floor \
            camera, at twice the solve time; docs/lab/glossy-final-floor.md and \
            docs/lab/glossy-view-term.md have the cost and error of each)."
    )]
    pub glossy_edge: Option<f64>,

    /// What shoots in one pass: patch (default) or grouped.
    #[arg(
        long,
        value_enum,
        value_name = "WHO",
        long_help = "What shoots in one pass. grouped (every preset): the patch with the \
            most unshot power and up to 16,383 patches within a fifth of the scene \
            diagonal with at least a tenth of its unshot power (a small face: of its \
            unshot radiance) shoot together (the \
            shooter side of Smits, Arvo and Greenberg's 1994 clustering): each receiver \
            sees the group through a cluster tree (near patches by their exact form \
            factor, far clusters as one item each) and shares its rays among them by \
            importance, an estimate of the sum of their shots. Far fewer shots, and \
            passes over the receivers, where many small patches are lit (thousands of \
            boxes on a floor): 100k boxes at medium converge in 40 s on 2 cores and 1M at \
            draft in 5 minutes, which the patch shooter does not in 5 and 10 minutes. An emitter's patch shoots its \
            emission alone first (recorded for refinement's replay). patch: the patch \
            with the most unshot power, one per shot (Remington 1992). On the Cornell \
            box against the path-traced truth grouped is the more accurate at every \
            preset (final: 1.27% against 1.44% MARE, 19 s against 24 s when compared, 13 s \
            since; medium: 1.74% against 2.3%, 1.2 s against 4.8 s) but noisier between seeds at equal rays \
            (--group-samples; docs/lab/grouped-shooters.md, \"Grouped shooters by default\"). \
            Diffuse mode only (directional solves shoot patches)."
    )]
    pub shooters: Option<Shooters>,

    /// Visibility rays per receiving vertex for a grouped shot.
    #[arg(
        long,
        value_name = "N",
        long_help = "Visibility rays per receiving vertex for a grouped shot (1 to 4096), \
            shared among the group's members in proportion to what each adds (--shooters \
            grouped; the presets: draft 16, medium 64, final 256). A group carries many \
            patches' light in one pass, so it needs more rays than one patch shot: on the \
            Cornell box at final, 32 measured 1.54% MARE against the path-traced truth, 64 \
            1.37% (12 s) and 256 1.27% (20 s); at medium 64 rays leave 0.89% image noise \
            between seeds and 512 0.47% (4.4 s, the main job). Time grows with N where shots are \
            bright: 100k boxes at medium took 167 s at 32 and 196 s at 64 \
            (docs/lab/grouped-shooters.md, \"Grouped shooters against the truth\"). Ignored by patch \
            shots, which use --samples."
    )]
    pub group_samples: Option<u32>,

    /// Hemicube cells per side of the top face (even, 2 to 2048).
    #[arg(
        long,
        value_name = "R",
        long_help = "Cells per side of a hemicube's top face (even, 2 to 2048; default \
            128): 3R² cells in all. Used by --method hemicube and --method \
            gauss-seidel. The error of a hemicube factor falls like 1/R where polygon \
            edges line up with the cells and faster otherwise; time grows like R²."
    )]
    pub hemicube_resolution: Option<u32>,

    /// progressive (default), or a seed baseline: hemicube, wallace, gauss-seidel, cube.
    #[arg(
        long,
        value_enum,
        value_name = "METHOD",
        long_help = "The solution method. progressive (default): progressive refinement \
            with the exact form factor, adaptive meshing, checkpoints and --resume, in \
            either mode. The seed papers' baselines, kept to measure against: hemicube \
            and wallace (progressive refinement with a hemicube's visibility or \
            Wallace's disc factor) and gauss-seidel (the full form-factor matrix) solve \
            diffuse mode only; cube (Immel, Cohen and Greenberg's global cube) solves \
            directional mode only. A method that cannot solve the mode is refused \
            before any work (docs/accuracy.md compares them)."
    )]
    pub method: Option<Method>,

    /// diffuse (default) or directional (glossy, spherical harmonics).
    #[arg(
        long,
        value_parser = solve_mode_parser(),
        value_name = "MODE",
        long_help = "diffuse (default): one radiance per vertex; MTL Ks is ignored with \
            a note. directional: glossy surfaces store outgoing radiance as spherical \
            harmonics (order chosen per material from its glossiness); highlights \
            follow the viewer, at a cost in time and file size that grows with the \
            square of the order."
    )]
    pub mode: Option<SolveMode>,

    /// Global-cube cells per face edge k (2 to 256): D = 6k² directions.
    #[arg(
        long,
        value_name = "K",
        long_help = "Cells per cube face edge for --method cube (2 to 256; default \
            8): D = 6k² directions per glossy vertex. Memory and time grow like k² \
            (values) to k⁴ (each glossy material's direction-to-direction BRDF matrix \
            and the reflection per sweep); in return highlights are sharper and placed \
            more accurately: a lobe narrower than a cell (about 90°/k) is aliased \
            between cell centres. The solve refuses, before allocating, a k whose \
            memory estimate exceeds its stated bound."
    )]
    pub cube_resolution: Option<u32>,

    /// Target patch size, as a fraction of the scene's bounding-box diagonal.
    #[arg(
        long,
        value_name = "F",
        long_help = "Target patch size as a fraction of the scene's bounding-box diagonal \
            (0 < F <= 1; presets: draft 0.15, medium 0.075, final 0.075). Each polygon \
            gets N × N patches with N = ceil(longest edge / (F × diagonal)), so a polygon \
            smaller than the target stays one patch as it is, however finely the model \
            was tessellated (at most 1024 per side, with a warning). Smaller F: more \
            patches to shoot from and receive at, so more time and memory, and less \
            meshing bias in the light the patches shoot. A TOML scene config can set \
            `patch_size` or `patches` per object or material, in scene units or metres."
    )]
    pub patch_size: Option<f64>,

    /// Smallest element's longest edge, as a fraction of the scene's diagonal.
    #[arg(
        long,
        value_name = "F",
        long_help = "Adaptive subdivision stops at elements whose longest edge is at \
            most F × the scene's bounding-box diagonal (0 < F <= 1; presets: draft and \
            medium 0.026, final 0.0065), the same absolute floor on every polygon, \
            large or small. Smaller F: shadow boundaries and gradients are followed more \
            closely (less meshing bias), at the cost of more elements, vertices, rays \
            and memory. A TOML scene config can set `min_element_size` per object or \
            material."
    )]
    pub min_element_size: Option<f64>,

    /// Scene units per metre (e.g. 1000 for millimetres).
    #[arg(
        long,
        value_name = "U",
        long_help = "How many scene units make a metre (default 1, or the scene \
            config's). Stored in the solution so that the runtime scales head \
            tracking, walking speed and eye separation; it does not change the \
            lighting."
    )]
    pub units_per_metre: Option<f64>,

    /// Peak memory the solve plans within (e.g. 8GiB, 500MB).
    #[arg(
        long,
        value_name = "SIZE",
        value_parser = parse_bytes,
        long_help = "Peak memory the progressive solve plans within: bytes, or a number \
            with KB/MB/GB/TB (powers of 1000) or KiB/MiB/GiB/TiB (powers of 1024), e.g. \
            8GiB or 500MB. Default: 80% of the machine's available memory \
            (/proc/meminfo MemAvailable; 4 GiB when it cannot be read), printed at the \
            start. The solve estimates its peak (mesh, vertex state, SH coefficients, \
            recorded shots, checkpoint and output) before allocating and before each \
            refinement, and plans against 90% of the budget. Near it, a directional solve \
            caps glossy materials' SH orders (blurrier reflections) and refinement stops \
            subdividing (coarser shadows), each with a warning; a scene whose unrefined \
            mesh cannot fit even at SH order 0 is refused with the estimate. A larger \
            budget trades memory for finer meshes and sharper highlights."
    )]
    pub memory_budget: Option<u64>,

    /// Make import warnings errors.
    #[arg(
        long,
        long_help = "Turn import warnings (Kd + Ks > 1 scaled down, degenerate or \
            non-planar faces, …) into errors, for scenes that must import cleanly."
    )]
    pub strict: bool,

    /// Save a checkpoint and a partial solution every K shots.
    #[arg(
        long,
        value_name = "K",
        long_help = "Every K shots (K >= 1) save OUT.checkpoint and rewrite OUT as a \
            partial solution. Smaller K loses less work on a crash and lets a viewer \
            follow the solve more closely; each save costs the time to write the \
            whole mesh."
    )]
    pub checkpoint_every: Option<u64>,

    /// Do not add the ambient estimate of unshot light to partial solutions.
    #[arg(
        long,
        long_help = "Do not add Cohen et al.'s ambient term (the estimated light not yet \
            shot, Remington 1992, appendix A line 8) to partial solutions. With it, early partial \
            solutions look about as bright as the converged one; without it they show \
            only the light shot so far. A converged file carries it too, for the light its \
            threshold leaves unshot. In diffuse mode each vertex gets the term weighted by how \
            enclosed it is (the share of its hemisphere that meets a surface, over the scene's \
            mean), so a face looking out of an open scene is not over-brightened; a closed room \
            gets Cohen's term unchanged (docs/lab/ambient-term.md)."
    )]
    pub no_ambient: bool,

    /// Degrees of shading-normal change a finely tessellated smooth surface's sites span (0: every point receives).
    #[arg(
        long,
        value_name = "DEGREES",
        long_help = "Points of a smooth surface exported finer than the preset's smallest \
            element receive each shot at sites, spread so that every point has one within \
            the smallest element size whose shading normal is within this angle of its \
            own, and take a weighted mean of the sites around it (default 10). Cost \
            follows the sites, not the triangles: the 1M spheres room has 14,737 \
            sites for 574,051 points. Smaller angles add sites, more cost \
            and less blur of the shading across the normal; under a source the \
            interpolation misses by the normals' curvature across the sites, about \
            1 - cos(angle) of the peak (1.6% measured at 10 degrees). 0: every point \
            receives on its own. Flat shooting in diffuse mode only (docs/lab/sites.md, \
            \"Sites\")."
    )]
    pub site_angle: Option<f64>,

    /// Largest angle (degrees) between neighbouring polygons that still shade as one smooth surface.
    #[arg(
        long,
        value_name = "DEGREES",
        long_help = "Neighbouring polygons of one material whose normals differ by less \
            than this angle (default 30) form a smooth surface: they share vertices in \
            the solution (no cracks) and receive light with a shading normal \
            interpolated from their corners (the OBJ's `vn` where given and \
            consistent, else the angle-weighted mean of the face normals). A larger \
            angle rounds off more edges that were meant to be sharp; a smaller one \
            shows the facets of coarse tessellations. 0 keeps every polygon a flat \
            facet (today's behaviour, to measure against)."
    )]
    pub crease_angle: Option<f64>,

    /// Continue the solve saved in OUT.checkpoint.
    #[arg(
        long,
        long_help = "Continue the solve saved in OUT.checkpoint (after Ctrl-C, a crash \
            or a shot budget). The scene and the result-affecting settings must be the \
            same as those of the saved solve, or the checkpoint is refused; \
            --max-shots, --threshold, --threads and --checkpoint-every may change. The \
            final solution equals that of an uninterrupted solve."
    )]
    pub resume: bool,

    /// Legacy display parameter file (Remington 1992, appendix A).
    #[arg(
        long,
        value_name = "FILE",
        long_help = "A legacy display parameter file (Remington 1992, appendix A): its camera is used \
            by --preview and stored in the solution when the scene names none; its \
            ambient and threshold lines become settings of the lowest precedence."
    )]
    pub display: Option<PathBuf>,

    /// Also write a tone-mapped PNG rendering of the solution.
    #[arg(
        long,
        value_name = "PNG",
        long_help = "Also render the finished solution on the CPU from the scene \
            config's camera (else the display file's, else the solution's default) and \
            write it as a tone-mapped sRGB PNG of the camera's image size."
    )]
    pub preview: Option<PathBuf>,

    /// Write the closing summary as JSON.
    #[arg(
        long,
        value_name = "FILE",
        long_help = "Write the closing summary as one JSON object with the keys \
            elements, vertices, shots, rays, seconds, rays_per_second, threads and \
            unshot_fraction."
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
