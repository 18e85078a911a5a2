//! Solver settings, quality presets and their precedence.
//!
//! Precedence, highest first (design notes): command-line flags, the TOML scene
//! config, the legacy display file, the preset's defaults. Every source but the
//! preset produces a [`SettingsPatch`] (all fields optional); [`SolverSettings::resolve`]
//! applies them in order. `settings/patch.rs` declares each setting a source
//! can set once, as a TOML key and, where it is one, a `solver solve` flag;
//! this file holds the resolved settings, their defaults and their ranges.
//! The presets live in `config/presets.toml`, embedded at build time so the
//! binary never depends on the working directory.

use crate::method::Method;
use serde::{Deserialize, Serialize};
use solution::format::{SolveMode, MAX_SH_ORDER};

mod patch;
pub(crate) use patch::solve_mode_parser;
pub use patch::{parse_bytes, SettingsPatch};

/// The presets file, embedded.
pub const PRESETS_TOML: &str = include_str!("../../config/presets.toml");

/// A named quality preset.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
#[derive(clap::ValueEnum)]
pub enum Preset {
    Draft,
    #[default]
    Medium,
    Final,
}

impl Preset {
    pub fn name(self) -> &'static str {
        match self {
            Preset::Draft => "draft",
            Preset::Medium => "medium",
            Preset::Final => "final",
        }
    }
}

/// How the point-to-source form factor is computed (design notes, "Form
/// factors"); chosen by [`Method`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum FormFactorMethod {
    /// Exact unoccluded point-to-polygon factor × visible fraction of the rays.
    #[default]
    Analytic,
    /// Remington 1992, eq. 3.1 (disc approximation per sample), kept to measure against.
    Wallace,
    /// The exact unoccluded factor × visibility read from a hemicube item
    /// buffer on the shooting patch (radiosity lecture notes; `hemicube_resolution`).
    Hemicube,
}

/// What shoots in one pass (`--shooters`; `solve/group_shot.rs`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
#[derive(clap::ValueEnum)]
pub enum Shooters {
    /// One patch per shot: Remington's (1992) progressive refinement.
    #[default]
    Patch,
    /// A reflecting patch and its bright neighbours shoot together, each receiver's rays shared among them by importance.
    Grouped,
}

/// Default of `group_samples` where no preset sets it (every preset does:
/// 16, 64, 256): twice the base `samples`, since a group's rays are shared
/// among its members (docs/lab/grouped-shooters.md, "Grouped shooters against the truth").
pub const DEFAULT_GROUP_SAMPLES: u32 = 32;

fn default_group_samples() -> u32 {
    DEFAULT_GROUP_SAMPLES
}

/// How directional mode stores a glossy vertex's outgoing radiance; chosen
/// by [`Method`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum DirectionalRepresentation {
    /// Spherical harmonics of an order chosen per material (Remington 1992, ch. 4), shot progressively.
    #[default]
    Sh,
    /// Immel, Cohen and Greenberg's (1986) global cube of 6k² directions (`cube_resolution`), gathered by Gauss–Seidel.
    Cube,
}

/// Default cells per cube face edge of the global-cube representation (`cube_resolution`).
pub const DEFAULT_CUBE_RESOLUTION: u32 = 8;

fn default_cube_resolution() -> u32 {
    DEFAULT_CUBE_RESOLUTION
}

/// Default cells per side of a hemicube's top face (`hemicube_resolution`).
pub const DEFAULT_HEMICUBE_RESOLUTION: u32 = 128;

fn default_hemicube_resolution() -> u32 {
    DEFAULT_HEMICUBE_RESOLUTION
}

/// Every knob of a solve, fully resolved.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SolverSettings {
    pub preset: Preset,
    pub mode: SolveMode,
    /// The solution method (`crate::method`). Not stored: the file records
    /// the form factor and the directional representation it implies.
    #[serde(skip)]
    pub method: Method,
    /// The form factor of progressive shots, as `method` implies.
    pub form_factors: FormFactorMethod,
    /// Visibility rays per (receiving vertex, source patch).
    pub samples: u32,
    /// Cells per side of a hemicube's top face (radiosity lecture notes; even, 2 to 2048): the
    /// Gauss–Seidel gather's form factors and the hemicube shooter's item buffer.
    #[serde(default = "default_hemicube_resolution")]
    pub hemicube_resolution: u32,
    /// Trace visibility rays at all (Remington 1992, appendix D `-t` turns them off).
    pub shadows: bool,
    /// Stop when total unshot power < threshold × total emitted power.
    pub threshold: f64,
    /// Stop after this many shots whatever the unshot power.
    pub max_shots: u64,
    pub seed: u64,
    /// Worker threads; `None` uses every core. Results do not depend on it.
    pub threads: Option<usize>,
    /// Target patch size as a fraction of the scene's bounding-box diagonal
    /// (`crate::mesh::sizing`), for every polygon whose input (a legacy
    /// geometry file's count, a TOML object's `patches` or `patch_size`) does
    /// not size it.
    pub patch_size: f64,
    /// Adaptive subdivision after each shot (Remington 1992, §3.3).
    pub adaptive: bool,
    /// Split an ordinary edge when |ΔL| exceeds this fraction of the local radiance.
    pub edge_threshold: f64,
    /// The same on shadow-boundary edges (tighter).
    pub shadow_threshold: f64,
    /// Smallest element's longest edge as a fraction of the scene's diagonal.
    pub min_element_size: f64,
    /// Deepest quadtree level below a patch.
    pub max_depth: u32,
    /// Write a checkpoint (and a `partial` solution) every this many shots.
    pub checkpoint_every: u64,
    /// Estimate unshot light with Cohen et al.'s ambient term for display.
    pub ambient: bool,
    /// Relative L2 error target of a glossy lobe's Legendre fit; sets L per material.
    pub sh_error_target: f64,
    /// Highest SH order a material may get; a lobe that needs more is capped with a warning.
    pub max_sh_order: u32,
    /// Directional mode's representation, as `method` implies: SH, or Immel,
    /// Cohen and Greenberg's (1986) global cube.
    #[serde(default)]
    pub directional: DirectionalRepresentation,
    /// Cells per face edge k of the global cube (D = 6k² directions per vertex).
    #[serde(default = "default_cube_resolution")]
    pub cube_resolution: u32,
    /// One patch per shot, or groups of nearby reflecting patches shot together.
    #[serde(default)]
    pub shooters: Shooters,
    /// Visibility rays per receiving vertex for a grouped shot, shared among
    /// its members by importance (`solve/group_shot.rs`).
    #[serde(default = "default_group_samples")]
    pub group_samples: u32,
    /// Scene units per metre (scene config or flag).
    pub units_per_metre: f64,
    /// Turn import warnings (Kd + Ks > 1, …) into errors.
    pub strict: bool,
    /// Smooth surfaces (`scene::smooth`): neighbouring polygons of one material
    /// whose normals differ by less than this many degrees share vertices and
    /// interpolated shading normals; 0 keeps every polygon a flat facet.
    #[serde(default = "default_crease_angle")]
    pub crease_angle: f64,
    /// Peak memory the progressive solve plans within, bytes (`None`: no
    /// limit); see `solve::budget`. Not stored in solutions or checkpoints: it
    /// bounds how a result is reached, and the command line's default follows
    /// the machine's available memory.
    #[serde(skip)]
    pub memory_budget: Option<u64>,
    /// The process's resident bytes measured just before meshing, when the
    /// command line could read them (`None` in the pure core and its tests):
    /// the memory estimate's fixed term is at least this (`solve::budget`),
    /// since import leaves freed pages resident that no structure owns. Not
    /// stored, like `memory_budget`.
    #[serde(skip)]
    pub resident_before_meshing: Option<u64>,
    /// Not a setting (no flag, key or file sets it; it is not stored): tests
    /// set it to shoot every patch's mean unshot radiance uniformly
    /// (Remington 1992), as the global cube gathers it, instead of from the
    /// quadrants of an unevenly lit patch (`solve::regions`), so that a test
    /// can hold two methods to the same linear system.
    #[serde(skip)]
    pub uniform_shooters: bool,
    /// The points of a finely tessellated smooth surface receive at sites
    /// spread so that each point has one within its smallest element size
    /// and within this many degrees of its shading normal, and take a
    /// weighted mean of the sites around it (`solve::sites`); 0: every point
    /// receives. Files written before the setting read 0, as they were
    /// solved.
    #[serde(default)]
    pub site_angle: f64,
    /// Mesh every receiver whole instead of cutting it along the lines where
    /// other objects touch or cover it (`mesh::contact`). Off by default; for
    /// measuring what the cut changes.
    #[serde(default)]
    pub whole_receivers: bool,
    /// A receiver gets every visibility ray from a shot whose unoccluded
    /// gain is at least this fraction of its radiance, fewer in proportion
    /// below (`solve::ray_share`); 0 traces every ray to every receiver.
    #[serde(default)]
    pub full_rays_above: f64,
    /// The smallest element edge on a glossy surface, as a multiple of its
    /// lobe's α times the scene's viewing distance (half its diagonal; see
    /// `solve::directional::min_glossy_edge`).
    #[serde(default = "default_glossy_edge")]
    pub glossy_edge: f64,
}

/// The glossy floor's factor before it became a setting (checkpoints
/// written then were solved with it).
fn default_glossy_edge() -> f64 {
    0.5
}

/// The default site angle (degrees, `solve::sites`): the interpolated
/// irradiance under a source misses by the normals' curvature across the
/// sites, E_peak Σ |w_s| (1 − n_s · n) at each point, of the order of
/// 1 − cos 10° = 1.5% of the peak; measured 1.6% at the worst point of a
/// 4,608-facet sphere against 0.13% with every point receiving (test
/// `sites_on_a_fine_sphere_follow_lamberts_law`).
pub const DEFAULT_SITE_ANGLE: f64 = 10.0;

fn default_crease_angle() -> f64 {
    crate::scene::DEFAULT_CREASE_ANGLE
}

/// A setting whose value is out of its range.
#[derive(Debug, thiserror::Error, PartialEq)]
#[error("setting `{name}` = {value} is out of range: {expected}")]
pub struct SettingsError {
    pub name: &'static str,
    pub value: String,
    pub expected: String,
}

impl SolverSettings {
    /// The built-in defaults that every preset patches (independent of any file).
    fn base() -> Self {
        SolverSettings {
            preset: Preset::Medium,
            mode: SolveMode::Diffuse,
            method: Method::Progressive,
            form_factors: FormFactorMethod::Analytic,
            samples: 16,
            hemicube_resolution: DEFAULT_HEMICUBE_RESOLUTION,
            shadows: true,
            threshold: 0.005,
            max_shots: 20_000,
            seed: 1,
            threads: None,
            patch_size: 0.075,
            adaptive: true,
            edge_threshold: 0.3,
            shadow_threshold: 0.1,
            min_element_size: 0.026,
            max_depth: 6,
            checkpoint_every: 500,
            ambient: true,
            sh_error_target: 1e-3,
            max_sh_order: 64,
            directional: DirectionalRepresentation::Sh,
            cube_resolution: DEFAULT_CUBE_RESOLUTION,
            shooters: Shooters::Patch,
            group_samples: DEFAULT_GROUP_SAMPLES,
            units_per_metre: 1.0,
            strict: false,
            crease_angle: default_crease_angle(),
            memory_budget: None,
            resident_before_meshing: None,
            uniform_shooters: false,
            site_angle: DEFAULT_SITE_ANGLE,
            whole_receivers: false,
            full_rays_above: 0.0,
            glossy_edge: default_glossy_edge(),
        }
    }

    /// The preset's settings, read from the embedded `config/presets.toml`.
    pub fn preset(preset: Preset) -> Self {
        let mut settings = Self::base();
        settings.preset = preset;
        // The embedded file is part of the binary and checked by a unit test, so a
        // parse failure here is a build defect; fall back to the base settings
        // rather than panic.
        if let Ok(table) =
            toml::from_str::<std::collections::BTreeMap<String, SettingsPatch>>(PRESETS_TOML)
        {
            if let Some(patch) = table.get(preset.name()) {
                settings.apply(patch);
            }
        }
        settings
    }

    /// Overwrites every field that `patch` sets.
    pub fn apply(&mut self, patch: &SettingsPatch) {
        patch.assign(self);
        // The method implies the two recorded fields that name its parts.
        if let Some(method) = patch.method {
            self.form_factors = method.form_factors();
            self.directional = method.directional();
        }
    }

    /// Whether every patch shoots its mean unshot radiance uniformly: only
    /// when a test asks (`uniform_shooters`); emitters' recorded shots always
    /// do.
    pub(crate) fn shoots_uniformly(&self) -> bool {
        self.uniform_shooters
    }

    /// Preset defaults, then each patch from lowest to highest precedence:
    /// `[display_file, scene_config, flags]`.
    pub fn resolve(
        preset: Preset,
        patches_low_to_high: &[&SettingsPatch],
    ) -> Result<Self, SettingsError> {
        let mut settings = Self::preset(preset);
        for patch in patches_low_to_high {
            settings.apply(patch);
        }
        settings.validate()?;
        Ok(settings)
    }

    /// Checks every range; the error names the setting and the value.
    pub fn validate(&self) -> Result<(), SettingsError> {
        fn check(
            ok: bool,
            name: &'static str,
            value: impl ToString,
            expected: impl Into<String>,
        ) -> Result<(), SettingsError> {
            if ok {
                Ok(())
            } else {
                Err(SettingsError {
                    name,
                    value: value.to_string(),
                    expected: expected.into(),
                })
            }
        }
        if let Err(conflict) = self.method.check_mode(self.mode) {
            return Err(SettingsError {
                name: "method",
                value: self.method.name().to_string(),
                expected: conflict,
            });
        }
        check(
            self.samples >= 1 && self.samples <= 4096,
            "samples",
            self.samples,
            "1 to 4096",
        )?;
        check(
            self.group_samples >= 1 && self.group_samples <= 4096,
            "group_samples",
            self.group_samples,
            "1 to 4096",
        )?;
        check(
            (2..=2048).contains(&self.hemicube_resolution)
                && self.hemicube_resolution.is_multiple_of(2),
            "hemicube_resolution",
            self.hemicube_resolution,
            "an even number from 2 to 2048",
        )?;
        check(
            self.threshold.is_finite() && self.threshold > 0.0 && self.threshold < 1.0,
            "threshold",
            self.threshold,
            "0 < threshold < 1",
        )?;
        check(
            (0.0..=30.0).contains(&self.site_angle),
            "site_angle",
            self.site_angle,
            "0 to 30 degrees",
        )?;
        check(
            (0.0..=90.0).contains(&self.crease_angle),
            "crease_angle",
            self.crease_angle,
            "0 to 90 degrees",
        )?;
        check(
            self.edge_threshold.is_finite() && self.edge_threshold > 0.0,
            "edge_threshold",
            self.edge_threshold,
            "> 0",
        )?;
        check(
            self.shadow_threshold.is_finite() && self.shadow_threshold > 0.0,
            "shadow_threshold",
            self.shadow_threshold,
            "> 0",
        )?;
        for (name, v) in [
            ("patch_size", self.patch_size),
            ("min_element_size", self.min_element_size),
        ] {
            check(
                v.is_finite() && v > 0.0 && v <= 1.0,
                name,
                v,
                "0 < fraction of the scene diagonal <= 1",
            )?;
        }
        check(self.max_depth <= 16, "max_depth", self.max_depth, "0 to 16")?;
        check(
            self.checkpoint_every >= 1,
            "checkpoint_every",
            self.checkpoint_every,
            ">= 1",
        )?;
        check(
            self.sh_error_target.is_finite()
                && self.sh_error_target > 0.0
                && self.sh_error_target < 1.0,
            "sh_error_target",
            self.sh_error_target,
            "0 < target < 1",
        )?;
        // The one SH order limit the writer and every reader share.
        check(
            self.max_sh_order <= MAX_SH_ORDER,
            "max_sh_order",
            self.max_sh_order,
            format!("0 to {MAX_SH_ORDER} (solution::format::MAX_SH_ORDER)"),
        )?;
        check(
            (2..=256).contains(&self.cube_resolution),
            "cube_resolution",
            self.cube_resolution,
            "2 to 256 cells per cube face edge",
        )?;
        check(
            self.full_rays_above.is_finite()
                && self.full_rays_above >= 0.0
                && self.full_rays_above <= 1.0,
            "full_rays_above",
            self.full_rays_above,
            "0 to 1 (a fraction of a receiver's radiance; 0 traces every ray)",
        )?;
        check(
            self.glossy_edge.is_finite() && self.glossy_edge > 0.0 && self.glossy_edge <= 10.0,
            "glossy_edge",
            self.glossy_edge,
            "above 0, at most 10 (a multiple of α × half the scene's diagonal)",
        )?;
        check(
            self.units_per_metre.is_finite() && self.units_per_metre > 0.0,
            "units_per_metre",
            self.units_per_metre,
            "a finite number > 0",
        )?;
        check(
            self.memory_budget.is_none_or(|b| b >= 1 << 20),
            "memory_budget",
            format!("{:?}", self.memory_budget),
            "at least 1 MiB (1048576 bytes)",
        )?;
        check(
            self.threads.is_none_or(|t| (1..=1024).contains(&t)),
            "threads",
            format!("{:?}", self.threads),
            "1 to 1024",
        )?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_file_parses_and_every_preset_is_valid() {
        let table: std::collections::BTreeMap<String, SettingsPatch> =
            toml::from_str(PRESETS_TOML).expect("config/presets.toml must parse");
        for preset in [Preset::Draft, Preset::Medium, Preset::Final] {
            assert!(
                table.contains_key(preset.name()),
                "missing preset {}",
                preset.name()
            );
            SolverSettings::preset(preset).validate().unwrap();
        }
        // Finer presets never cost less: no fewer samples and no looser
        // threshold (medium and final share the threshold and may share the
        // samples: against the truth the mesh is what separates them, as the
        // size test below checks).
        let (d, m, f) = (
            SolverSettings::preset(Preset::Draft),
            SolverSettings::preset(Preset::Medium),
            SolverSettings::preset(Preset::Final),
        );
        assert!(d.samples <= m.samples && m.samples <= f.samples);
        assert!(d.group_samples <= m.group_samples && m.group_samples <= f.group_samples);
        assert!(d.threshold > m.threshold && m.threshold >= f.threshold);
        assert!(d.glossy_edge >= m.glossy_edge && m.glossy_edge >= f.glossy_edge);
    }

    #[test]
    fn precedence_is_flags_over_config_over_display_over_preset() {
        let display = SettingsPatch {
            samples: Some(3),
            threshold: Some(0.3),
            seed: Some(7),
            ..Default::default()
        };
        let config = SettingsPatch {
            samples: Some(5),
            threshold: Some(0.2),
            ..Default::default()
        };
        let flags = SettingsPatch {
            samples: Some(9),
            ..Default::default()
        };
        let s = SolverSettings::resolve(Preset::Draft, &[&display, &config, &flags]).unwrap();
        assert_eq!(s.samples, 9);
        assert_eq!(s.threshold, 0.2);
        assert_eq!(s.seed, 7);
        assert_eq!(
            s.patch_size,
            SolverSettings::preset(Preset::Draft).patch_size
        );
    }

    #[test]
    fn finer_presets_mesh_finer_and_flags_override_the_sizes() {
        // Finer presets: patches no larger, elements no larger.
        let size = |p| SolverSettings::preset(p).patch_size;
        let floor = |p| SolverSettings::preset(p).min_element_size;
        assert!(size(Preset::Draft) >= size(Preset::Medium));
        assert!(size(Preset::Medium) >= size(Preset::Final));
        assert!(floor(Preset::Draft) >= floor(Preset::Medium));
        assert!(floor(Preset::Medium) > floor(Preset::Final));
        // A size from the flags replaces the preset's.
        let flags = SettingsPatch {
            patch_size: Some(0.05),
            ..Default::default()
        };
        let s = SolverSettings::resolve(Preset::Medium, &[&flags]).unwrap();
        assert_eq!(s.patch_size, 0.05);
        // The global flat rule is gone: its keys are unknown in a config.
        for key in ["patches = 4", "min_element_area = 0.002"] {
            assert!(toml::from_str::<SettingsPatch>(key).is_err(), "{key}");
        }
    }

    #[test]
    fn out_of_range_sizes_are_named() {
        for (name, patch) in [
            (
                "patch_size",
                SettingsPatch {
                    patch_size: Some(0.0),
                    ..Default::default()
                },
            ),
            (
                "patch_size",
                SettingsPatch {
                    patch_size: Some(1.5),
                    ..Default::default()
                },
            ),
            (
                "min_element_size",
                SettingsPatch {
                    min_element_size: Some(f64::NAN),
                    ..Default::default()
                },
            ),
        ] {
            let err = SolverSettings::resolve(Preset::Draft, &[&patch]).unwrap_err();
            assert_eq!(err.name, name);
        }
    }

    #[test]
    fn the_method_sets_its_form_factor_and_representation_and_refuses_a_mode_it_cannot_solve() {
        use crate::method::Method;
        let config: SettingsPatch = toml::from_str("method = \"hemicube\"").unwrap();
        let s = SolverSettings::resolve(Preset::Draft, &[&config]).unwrap();
        assert_eq!(
            (s.method, s.form_factors, s.directional),
            (
                Method::Hemicube,
                FormFactorMethod::Hemicube,
                DirectionalRepresentation::Sh
            )
        );
        let cube = SettingsPatch {
            method: Some(Method::Cube),
            mode: Some(SolveMode::Directional),
            ..Default::default()
        };
        let s = SolverSettings::resolve(Preset::Draft, &[&cube]).unwrap();
        assert_eq!(s.directional, DirectionalRepresentation::Cube);
        // The issue's example: the mode from the config, the method from the flags.
        let config = SettingsPatch {
            mode: Some(SolveMode::Directional),
            ..Default::default()
        };
        let flags = SettingsPatch {
            method: Some(Method::GaussSeidel),
            ..Default::default()
        };
        let err = SolverSettings::resolve(Preset::Draft, &[&config, &flags]).unwrap_err();
        assert_eq!((err.name, err.value.as_str()), ("method", "gauss-seidel"));
        assert!(err.to_string().contains("directional"), "{err}");
        // The keys the method replaced are gone.
        for key in ["form_factors = \"hemicube\"", "directional = \"cube\""] {
            assert!(toml::from_str::<SettingsPatch>(key).is_err(), "{key}");
        }
    }

    #[test]
    fn out_of_range_setting_is_named() {
        let flags = SettingsPatch {
            samples: Some(0),
            ..Default::default()
        };
        let err = SolverSettings::resolve(Preset::Draft, &[&flags]).unwrap_err();
        assert_eq!(err.name, "samples");
    }

    /// A patch that sets every key, each to a valid value unlike every preset's.
    const EVERY_KEY: &str = r#"
        mode = "directional"
        method = "cube"
        samples = 7
        hemicube_resolution = 64
        shadows = false
        threshold = 0.03
        max_shots = 77
        seed = 9
        threads = 3
        patch_size = 0.2
        adaptive = false
        edge_threshold = 0.7
        shadow_threshold = 0.33
        min_element_size = 0.05
        max_depth = 3
        checkpoint_every = 11
        ambient = false
        sh_error_target = 0.02
        max_sh_order = 12
        cube_resolution = 5
        shooters = "patch"
        group_samples = 99
        units_per_metre = 2.5
        strict = true
        crease_angle = 12.0
        memory_budget = 123456789
        site_angle = 4.0
        full_rays_above = 0.2
        glossy_edge = 0.3
    "#;

    #[test]
    fn every_key_of_a_patch_reaches_the_settings() {
        let patch: SettingsPatch = toml::from_str(EVERY_KEY).unwrap();
        let keys = serde_json::to_value(&patch).unwrap();
        let keys = keys.as_object().unwrap();
        // Read from the struct: a new field that the list above lacks fails here.
        for (key, value) in keys {
            assert!(!value.is_null(), "EVERY_KEY lacks `{key}`");
        }
        let settings = SolverSettings::resolve(Preset::Draft, &[&patch]).unwrap();
        let resolved = serde_json::to_value(&settings).unwrap();
        for (key, value) in keys {
            match resolved.get(key) {
                Some(got) => assert_eq!(got, value, "`{key}`"),
                // The two settings that solution files do not record.
                None => match key.as_str() {
                    "method" => assert_eq!(Some(settings.method), patch.method),
                    "memory_budget" => assert_eq!(settings.memory_budget, patch.memory_budget),
                    _ => panic!("`{key}` is neither recorded nor checked"),
                },
            }
        }
        assert_eq!(
            (settings.form_factors, settings.directional),
            (FormFactorMethod::Analytic, DirectionalRepresentation::Cube)
        );
    }

    #[test]
    fn the_recorded_settings_keep_their_keys_in_order() {
        // Every solution file's header holds this JSON; its keys and their
        // order are part of the format. No value holds a comma or a colon.
        let json = serde_json::to_string(&SolverSettings::preset(Preset::Medium)).unwrap();
        let keys: Vec<&str> = json
            .trim_matches(['{', '}'])
            .split(',')
            .map(|pair| pair.split(':').next().unwrap().trim_matches('"'))
            .collect();
        assert_eq!(
            keys,
            [
                "preset",
                "mode",
                "form_factors",
                "samples",
                "hemicube_resolution",
                "shadows",
                "threshold",
                "max_shots",
                "seed",
                "threads",
                "patch_size",
                "adaptive",
                "edge_threshold",
                "shadow_threshold",
                "min_element_size",
                "max_depth",
                "checkpoint_every",
                "ambient",
                "sh_error_target",
                "max_sh_order",
                "directional",
                "cube_resolution",
                "shooters",
                "group_samples",
                "units_per_metre",
                "strict",
                "crease_angle",
                "site_angle",
                "whole_receivers",
                "full_rays_above",
                "glossy_edge",
            ]
        );
    }
}
