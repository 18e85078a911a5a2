//! The fix for a scene with no light, said in the input's own format: a glTF
//! user is told about `emissiveFactor`, not about MTL's `Ke`. The sun and sky
//! options are named for every input, since any scene can be lit by them.

use std::path::{Path, PathBuf};

/// The ways to light a scene read from `files` (its geometry files; their
/// extensions say their formats), from a TOML scene config when `from_config`:
/// each format's emission statement, its lamps where it has them, and the
/// sun and sky of a scene config or of `solver solve`'s flags.
pub fn no_emitter_hint(files: &[PathBuf], from_config: bool) -> String {
    let extension = |f: &Path| {
        f.extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .unwrap_or_default()
    };
    let has = |kinds: &[&str]| files.iter().any(|f| kinds.contains(&extension(f).as_str()));
    let gltf = has(&["gltf", "glb"]);
    let obj = has(&["obj", "mtl"]);
    // A scene built in code has polygons from no file (an empty path).
    let legacy = files.iter().any(|f| {
        !f.as_os_str().is_empty()
            && !["gltf", "glb", "obj", "mtl", "toml"].contains(&extension(f).as_str())
    });
    let mut ways = Vec::new();
    if from_config {
        ways.push(
            "`emission = [r, g, b]` under `[materials.NAME]` in the TOML scene config".to_owned(),
        );
    }
    if obj {
        ways.push("`Ke r g b` in the MTL file".to_owned());
    }
    if gltf {
        ways.push(
            "`\"emissiveFactor\": [r, g, b]` on a glTF material (with \
             `KHR_materials_emissive_strength` for radiance above 1)"
                .to_owned(),
        );
    }
    if legacy {
        ways.push("`emit r g b` on a legacy attribute line".to_owned());
    }
    let lamps = if gltf {
        ", add `KHR_lights_punctual` lights to the glTF file"
    } else {
        ""
    };
    let lights = if from_config {
        "add `[sun]`, `[sky]` or `[[lights]]` tables to the scene config"
    } else {
        "light it from a TOML scene config with `[sun]`, `[sky]` or `[[lights]]` tables"
    };
    let ways = if ways.is_empty() {
        String::new()
    } else {
        format!(" ({})", ways.join(", or "))
    };
    format!(
        "Give a material an emission{ways}{lamps}, {lights}, or pass `solver solve` the flags \
         `--sun AZIMUTH,ELEVATION` and `--sky KIND` (docs/lights.md)"
    )
}

/// The distinct source files of `files`, in their first order: the geometry
/// files a scene's polygons came from.
pub fn distinct_files<'a>(files: impl IntoIterator<Item = &'a Path>) -> Vec<PathBuf> {
    let mut seen = std::collections::HashSet::new();
    files
        .into_iter()
        .filter(|f| seen.insert(*f))
        .map(Path::to_path_buf)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each input format is told its own emission statement, and every one the
    /// sun and sky options.
    #[test]
    fn each_format_is_told_its_own_fix() {
        let hint = |files: &[&str], config: bool| {
            let files: Vec<PathBuf> = files.iter().map(PathBuf::from).collect();
            no_emitter_hint(&files, config)
        };
        let always = ["`[sun]`, `[sky]`", "--sun AZIMUTH,ELEVATION", "--sky KIND"];
        // The files, whether from a TOML config, the phrases the hint must
        // hold and those it must not.
        type Case = (
            &'static [&'static str],
            bool,
            &'static [&'static str],
            &'static [&'static str],
        );
        let cases: [Case; 6] = [
            (
                &["car.gltf"],
                false,
                &["emissiveFactor", "KHR_lights_punctual"],
                &["Ke r g b", "emission = [r, g, b]", "emit r g b"],
            ),
            (
                &["car.GLB"],
                false,
                &["emissiveFactor", "KHR_lights_punctual"],
                &["Ke r g b"],
            ),
            (
                &["room.obj"],
                false,
                &["`Ke r g b` in the MTL file"],
                &[
                    "emissiveFactor",
                    "KHR_lights_punctual",
                    "emission = [r, g, b]",
                ],
            ),
            (
                &["room.obj"],
                true,
                &[
                    "`emission = [r, g, b]` under `[materials.NAME]`",
                    "Ke r g b",
                ],
                &["emissiveFactor"],
            ),
            (
                &["room.geom"],
                false,
                &["`emit r g b` on a legacy attribute line"],
                &["Ke r g b", "emissiveFactor"],
            ),
            (
                &[""],
                false,
                &["Give a material an emission, light it"],
                &["emit r g b", "()"],
            ),
        ];
        for (files, config, present, absent) in cases {
            let text = hint(files, config);
            for phrase in always.iter().chain(present) {
                assert!(text.contains(phrase), "{files:?}: {phrase:?} not in {text}");
            }
            for phrase in absent {
                assert!(!text.contains(phrase), "{files:?}: {phrase:?} in {text}");
            }
        }
    }

    #[test]
    fn distinct_files_keep_their_first_order() {
        let files = [Path::new("b.obj"), Path::new("a.obj"), Path::new("b.obj")];
        assert_eq!(
            distinct_files(files),
            [PathBuf::from("b.obj"), PathBuf::from("a.obj")]
        );
    }
}
