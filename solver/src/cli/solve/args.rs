//! The flags of `solver solve`: its files and preset here, and every setting
//! flag from [`SettingsPatch`], which declares each setting once for the
//! command line and the TOML config alike.

use crate::scene::{SkyFlag, SkyFlagKind, SunFlag, DEFAULT_SUN_LUX};
use crate::settings::{Preset, SettingsPatch};
use clap::Args;
use std::path::PathBuf;

/// Exit code of a solve stopped by Ctrl-C after saving its checkpoint (128 + SIGINT,
/// as shells report an interrupted program).
pub const EXIT_INTERRUPTED: u8 = 130;

/// Exit code of a progressive solve that stopped at its shot cap (`max_shots`, from
/// the preset or `--max-shots`) above its threshold: the file is marked partial and
/// the checkpoint is kept. Not 3, which `runtime mirror` already means.
pub const EXIT_SHOT_CAP: u8 = 4;

const AFTER_LONG_HELP: &str = "\
Exit codes: 0 done, 1 error, 2 bad command line, 4 stopped at the shot cap (--max-shots) \
above the threshold (the file is partial; the checkpoint is kept: --resume with a larger \
--max-shots goes on), 130 Ctrl-C (saved; --resume goes on).";

/// `solver solve SCENE -o OUT …`: the setting flags are [`SettingsPatch`]'s.
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

    // The setting flags: the struct that is also a TOML config's `[solver]` table.
    #[command(flatten)]
    pub settings: SettingsPatch,

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

    /// Add a sun at AZIMUTH,ELEVATION degrees, and LUX (default 100000).
    #[arg(
        long,
        value_name = "AZIMUTH,ELEVATION[,LUX]",
        value_parser = parse_sun,
        allow_hyphen_values = true,
        long_help = "Light the scene with a sun, in place of the scene's: azimuth in degrees \
            clockwise from north (-z in a y-up scene, +y in a z-up one, or the config's \
            `north`), elevation above the horizon, and its illuminance in lux on a plane \
            facing it (default 100000, bright sunlight). Sharp shadows; sunlight through \
            a window needs fine elements where its patch ends."
    )]
    pub sun: Option<SunFlag>,

    /// Add a sky: uniform[,LUX], overcast[,LUX] or clear[,TURBIDITY].
    #[arg(
        long,
        value_name = "KIND[,VALUE]",
        value_parser = parse_sky,
        long_help = "Light the scene with a sky, in place of the scene's: `uniform` or \
            `overcast` (CIE standard overcast) giving LUX on an open horizontal plane \
            (default 10000), or `clear` (Preetham), tied to the sun, with its turbidity \
            (2 to 10, default 3). Soft light from every opening, at the cost of sky \
            samples per receiver."
    )]
    pub sky: Option<SkyFlag>,

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
}

/// The numbers of a comma-separated flag value, each finite.
fn numbers(text: &str, what: &str) -> Result<Vec<f64>, String> {
    text.split(',')
        .map(|t| match t.trim().parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(v),
            _ => Err(format!("{what}: `{}` is not a finite number", t.trim())),
        })
        .collect()
}

/// `--sun AZIMUTH,ELEVATION[,LUX]`: elevation in [−90, 90], lux ≥ 0.
fn parse_sun(text: &str) -> Result<SunFlag, String> {
    let v = numbers(text, "--sun")?;
    let (azimuth_deg, elevation_deg, lux) = match v[..] {
        [a, e] => (a, e, DEFAULT_SUN_LUX),
        [a, e, l] => (a, e, l),
        _ => {
            return Err(format!(
                "--sun {text}: give AZIMUTH,ELEVATION or AZIMUTH,ELEVATION,LUX (degrees, lux)"
            ))
        }
    };
    if !(-90.0..=90.0).contains(&elevation_deg) {
        return Err(format!(
            "--sun: elevation {elevation_deg} is outside [-90, 90] degrees"
        ));
    }
    if lux < 0.0 {
        return Err(format!("--sun: illuminance {lux} lux is negative"));
    }
    Ok(SunFlag {
        azimuth_deg,
        elevation_deg,
        lux,
    })
}

/// `--sky KIND[,VALUE]`: a known kind, VALUE ≥ 0 (lux) or in [2, 10]
/// (a clear sky's turbidity).
fn parse_sky(text: &str) -> Result<SkyFlag, String> {
    let (kind, value) = match text.split_once(',') {
        Some((k, v)) => (k.trim(), Some(numbers(v, "--sky")?)),
        None => (text.trim(), None),
    };
    let kind = match kind {
        "uniform" => SkyFlagKind::Uniform,
        "overcast" | "cie-overcast" => SkyFlagKind::Overcast,
        "clear" => SkyFlagKind::Clear,
        other => {
            return Err(format!(
                "--sky: `{other}` is not a sky kind: use uniform, overcast or clear"
            ))
        }
    };
    let value = match value.as_deref() {
        None => None,
        Some(&[v]) => Some(v),
        Some(_) => return Err(format!("--sky {text}: give KIND or KIND,VALUE")),
    };
    match (kind, value) {
        (SkyFlagKind::Clear, Some(t)) if !(2.0..=10.0).contains(&t) => Err(format!(
            "--sky clear,{t}: the turbidity must be in [2, 10] (Preetham et al.'s fit)"
        )),
        (_, Some(lux)) if lux < 0.0 => Err(format!("--sky: illuminance {lux} lux is negative")),
        _ => Ok(SkyFlag { kind, value }),
    }
}

/// Which flag sets a setting, for error messages (`samples` → `--samples`,
/// `shadows` → `--no-shadows`), as [`SettingsPatch`] declares it.
pub fn flag_name(setting: &str) -> String {
    let flags = SettingsPatch::augment_args(clap::Command::new("solve"));
    let long = flags
        .get_arguments()
        .find(|arg| arg.get_id() == setting)
        .and_then(|arg| arg.get_long());
    match long {
        Some(long) => format!("--{long}"),
        None => format!("--{}", setting.replace('_', "-")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::method::Method;
    use crate::settings::{parse_bytes, Shooters, SolverSettings};
    use clap::Parser;
    use solution::format::SolveMode;

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
        assert_eq!(parse(&[]).settings, SettingsPatch::default());
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
        let p = args.settings;
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
            parse(&["--memory-budget", "2GiB"]).settings.memory_budget,
            Some(2 << 30)
        );
    }

    #[test]
    fn site_angle_flag_and_toml_key_reach_the_settings() {
        // 10° unless asked for; 0 turns the sites off; above 30° is refused.
        let default = SolverSettings::resolve(Preset::Draft, &[&parse(&[]).settings]).unwrap();
        assert_eq!(default.site_angle, crate::settings::DEFAULT_SITE_ANGLE);
        let flag = parse(&["--site-angle", "0"]).settings;
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
        let wide = parse(&["--site-angle", "45"]).settings;
        let error = SolverSettings::resolve(Preset::Draft, &[&wide]).unwrap_err();
        assert!(error.to_string().contains("site_angle"), "{error}");
    }

    #[test]
    fn shooters_flag_and_toml_key_reach_the_settings() {
        // Grouped shots in every preset unless asked for one patch a shot; a
        // grouped shot's rays from the preset, at least the patch shot's.
        for preset in [Preset::Draft, Preset::Medium, Preset::Final] {
            let default = SolverSettings::resolve(preset, &[&parse(&[]).settings]).unwrap();
            assert_eq!(default.shooters, Shooters::Grouped);
            assert!(default.group_samples >= default.samples);
            let patch = parse(&["--shooters", "patch"]).settings;
            let resolved = SolverSettings::resolve(preset, &[&patch]).unwrap();
            assert_eq!(resolved.shooters, Shooters::Patch);
        }
        let flag = parse(&["--shooters", "grouped", "--group-samples", "48"]).settings;
        assert_eq!(flag.shooters, Some(Shooters::Grouped));
        assert_eq!(flag.group_samples, Some(48));
        let config: SettingsPatch =
            toml::from_str("shooters = \"grouped\"\ngroup_samples = 24").unwrap();
        let resolved =
            SolverSettings::resolve(Preset::Draft, &[&config, &parse(&[]).settings]).unwrap();
        assert_eq!(resolved.shooters, Shooters::Grouped);
        assert_eq!(resolved.group_samples, 24);
        let zero: SettingsPatch = toml::from_str("group_samples = 0").unwrap();
        let err = SolverSettings::resolve(Preset::Draft, &[&zero]).unwrap_err();
        assert_eq!(err.name, "group_samples");
        assert!(toml::from_str::<SettingsPatch>("shooters = \"clusters\"").is_err());
    }

    #[test]
    fn sun_and_sky_flags_parse_with_their_defaults_and_refuse_bad_values() {
        let args = parse(&["--sun", "-90,30", "--sky", "overcast,20000"]);
        assert_eq!(
            args.sun,
            Some(SunFlag {
                azimuth_deg: -90.0,
                elevation_deg: 30.0,
                lux: DEFAULT_SUN_LUX
            })
        );
        assert_eq!(
            args.sky,
            Some(SkyFlag {
                kind: SkyFlagKind::Overcast,
                value: Some(20000.0)
            })
        );
        assert_eq!(parse_sun("180, 45, 5000").unwrap().lux, 5000.0);
        assert_eq!(
            parse_sky("clear").unwrap(),
            SkyFlag {
                kind: SkyFlagKind::Clear,
                value: None
            }
        );
        for (bad, needle) in [
            ("180", "AZIMUTH,ELEVATION"),
            ("0,95", "95"),
            ("0,45,-1", "-1"),
            ("a,4", "`a`"),
        ] {
            let e = parse_sun(bad).unwrap_err();
            assert!(e.contains(needle), "{bad}: {e}");
        }
        for (bad, needle) in [
            ("stormy", "stormy"),
            ("clear,12", "12"),
            ("uniform,-3", "-3"),
            ("uniform,nan", "nan"),
        ] {
            let e = parse_sky(bad).unwrap_err();
            assert!(e.contains(needle), "{bad}: {e}");
        }
    }

    #[test]
    fn flag_names_match_the_command_line() {
        assert_eq!(flag_name("max_shots"), "--max-shots");
        assert_eq!(flag_name("shadows"), "--no-shadows");
        assert_eq!(flag_name("ambient"), "--no-ambient");
        assert_eq!(flag_name("memory_budget"), "--memory-budget");
    }

    #[test]
    fn switches_set_their_toml_key_only_when_given() {
        // `--no-shadows`, `--no-ambient` and `--strict` fill the keys
        // `shadows`, `ambient` and `strict`; absent, they leave them to the
        // config and the preset, and they take no value.
        let given = parse(&["--no-shadows", "--no-ambient", "--strict"]).settings;
        assert_eq!(
            (given.shadows, given.ambient, given.strict),
            (Some(false), Some(false), Some(true))
        );
        let config: SettingsPatch =
            toml::from_str("shadows = false\nambient = false\nstrict = true").unwrap();
        assert_eq!(given, config);
        let absent = parse(&[]).settings;
        assert_eq!(
            (absent.shadows, absent.ambient, absent.strict),
            (None, None, None)
        );
        for flag in ["--no-shadows=true", "--no-ambient=false", "--strict=false"] {
            let argv = ["solver", "scene.obj", "-o", "out.sol", flag];
            assert!(Wrapper::try_parse_from(argv).is_err(), "{flag}");
        }
    }

    #[test]
    fn toml_only_settings_are_not_flags_and_the_flags_stay_few() {
        for flag in [
            "--edge-threshold",
            "--max-depth",
            "--sh-error-target",
            "--adaptive",
        ] {
            let argv = ["solver", "scene.obj", "-o", "out.sol", flag, "1"];
            assert!(Wrapper::try_parse_from(argv).is_err(), "{flag}");
        }
        let config: SettingsPatch = toml::from_str("edge_threshold = 0.2\nmax_depth = 4").unwrap();
        assert_eq!(
            (config.edge_threshold, config.max_depth),
            (Some(0.2), Some(4))
        );
        // Issue 40's bound on `solver solve`: at most 30 flags, counting -h,
        // which clap adds when it builds the command. Issue 41's `--sun` and
        // `--sky` took the places of `--full-rays-above` and `--glossy-edge`,
        // now `[solver]` keys only (tuning the presets choose).
        let command = <Wrapper as clap::CommandFactory>::command();
        let flags = command
            .get_arguments()
            .filter(|arg| !arg.is_positional())
            .count();
        assert!(flags <= 30, "{flags} flags and -h");
    }
}
