//! `--glossy NAME[=KS,NS]`: makes chosen materials of a generated scene glossy,
//! so that glossy scale scenes are generated rather than hand-edited (issue 43).
//!
//! NAME is one of the family's materials, or the name of an object (the
//! Cornell box's `floor`, which shares `white` with the walls and the boxes):
//! that object then gets a material of its own, named after it, copied from
//! the one it had. The material gains `Ks` and `Ns` ([`Glossy`]); where
//! Kd + Ks would exceed 1 in a channel, Kd is scaled down as a whole (its
//! colour kept) so that every channel sums to 1 at most, as the solver
//! requires (it would otherwise scale both down, with a warning that
//! `--strict` refuses). The scene's config then asks for
//! `mode = "directional"` ([`crate::scene::toml_text`]).

use crate::scene::{Glossy, Material, Scene};
use anyhow::{anyhow, bail};
use std::collections::BTreeSet;
use std::str::FromStr;

/// `--glossy NAME` without values: a polished surface, half of its light
/// reflected into a lobe of RMS slope α = √(2 / 102) ≈ 0.14.
pub const DEFAULT_GLOSSY: Glossy = Glossy {
    ks: [0.5; 3],
    ns: 100.0,
};

/// How many object names an unknown-name error lists (the Cornell box and
/// the floor plan have thousands of numbered objects).
const LISTED_OBJECTS: usize = 8;

/// One `--glossy` argument.
#[derive(Clone, Debug, PartialEq)]
pub struct GlossyRequest {
    /// A material's or an object's name.
    pub name: String,
    pub glossy: Glossy,
}

impl FromStr for GlossyRequest {
    type Err = String;

    /// `NAME`, `NAME=KS,NS` (grey Ks) or `NAME=R,G,B,NS`.
    fn from_str(text: &str) -> Result<Self, String> {
        let (name, values) = match text.split_once('=') {
            Some((name, values)) => (name.trim(), Some(values)),
            None => (text.trim(), None),
        };
        if name.is_empty() {
            return Err(format!("`{text}`: the material's name is missing"));
        }
        let glossy = match values {
            None => DEFAULT_GLOSSY,
            Some(values) => parse_values(values).map_err(|e| format!("`{text}`: {e}"))?,
        };
        Ok(GlossyRequest {
            name: name.to_owned(),
            glossy,
        })
    }
}

/// `KS,NS` or `R,G,B,NS`, each Ks in [0, 1] with one above 0, Ns ≥ 0.
fn parse_values(values: &str) -> Result<Glossy, String> {
    let numbers = values
        .split(',')
        .map(|v| {
            let v = v.trim();
            v.parse::<f64>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or_else(|| format!("`{v}` is not a number"))
        })
        .collect::<Result<Vec<f64>, String>>()?;
    let (ks, ns) = match numbers[..] {
        [ks, ns] => ([ks; 3], ns),
        [r, g, b, ns] => ([r, g, b], ns),
        _ => {
            return Err(format!(
                "expected KS,NS (e.g. 0.6,1000) or R,G,B,NS, found {} values",
                numbers.len()
            ))
        }
    };
    if ks.iter().any(|&k| !(0.0..=1.0).contains(&k)) || ks.iter().all(|&k| k == 0.0) {
        return Err(format!(
            "Ks must lie in [0, 1], one channel above 0, is {} {} {}",
            ks[0], ks[1], ks[2]
        ));
    }
    if ns < 0.0 {
        return Err(format!("Ns must not be negative, is {ns}"));
    }
    Ok(Glossy { ks, ns })
}

/// Makes each requested material of `scene` (a `family` scene) glossy.
/// Returns one line for each material whose Kd was scaled down. An unknown
/// name, or one given twice, is an error that changes nothing.
pub fn apply(
    scene: &mut Scene,
    family: &str,
    requests: &[GlossyRequest],
) -> anyhow::Result<Vec<String>> {
    let mut seen = BTreeSet::new();
    for r in requests {
        if !seen.insert(r.name.as_str()) {
            bail!("--glossy {} is given twice", r.name);
        }
        if !has_material(scene, &r.name) && !scene.mesh.objects.iter().any(|o| o.name == r.name) {
            bail!("{}", unknown_name(scene, family, &r.name));
        }
    }
    // Objects are split off first, from the materials as the family made
    // them, so that the requests' order does not matter (`--glossy white
    // --glossy floor` copies white's Kd before it is scaled).
    for r in requests {
        if !has_material(scene, &r.name) {
            split_object(scene, &r.name)?;
        }
    }
    let mut notes = Vec::new();
    for r in requests {
        let material = scene
            .materials
            .iter_mut()
            .find(|m| m.name == r.name)
            .ok_or_else(|| anyhow!("material `{}` vanished while it was split", r.name))?;
        notes.extend(make_glossy(material, r.glossy));
    }
    if !requests.is_empty() {
        let what: Vec<String> = requests.iter().map(describe).collect();
        scene
            .description
            .push_str(&format!("; glossy {}", what.join(", ")));
    }
    Ok(notes)
}

fn has_material(scene: &Scene, name: &str) -> bool {
    scene.materials.iter().any(|m| m.name == name)
}

/// `floor (Ks 0.6 0.6 0.6, Ns 1000)`, for the scene's description line.
fn describe(r: &GlossyRequest) -> String {
    let g = r.glossy;
    format!(
        "{} (Ks {} {} {}, Ns {})",
        r.name, g.ks[0], g.ks[1], g.ks[2], g.ns
    )
}

/// The error for a name that is neither a material nor an object.
fn unknown_name(scene: &Scene, family: &str, name: &str) -> String {
    let materials: Vec<&str> = scene.materials.iter().map(|m| m.name.as_str()).collect();
    let mut objects: Vec<&str> = Vec::new();
    for o in &scene.mesh.objects {
        if !objects.contains(&o.name.as_str()) {
            objects.push(&o.name);
        }
    }
    let shown = objects.len().min(LISTED_OBJECTS);
    let more = if objects.len() > shown {
        format!(", … ({} objects)", objects.len())
    } else {
        String::new()
    };
    format!(
        "--glossy {name}: {family} has no material or object of that name; its materials are {} \
         (an object's name, such as {}{more}, gives that object a glossy material of its own)",
        materials.join(", "),
        objects[..shown].join(", ")
    )
}

/// Gives the objects called `name` a new material `name`, a copy of the one
/// they share.
fn split_object(scene: &mut Scene, name: &str) -> anyhow::Result<()> {
    let used: BTreeSet<&str> = scene
        .mesh
        .objects
        .iter()
        .filter(|o| o.name == name)
        .map(|o| o.material.as_str())
        .collect();
    let [source] = used.into_iter().collect::<Vec<_>>()[..] else {
        bail!("--glossy {name}: the objects called `{name}` have different materials; name one of those");
    };
    let copy = scene
        .materials
        .iter()
        .find(|m| m.name == source)
        .ok_or_else(|| {
            anyhow!("object `{name}` uses material `{source}`, which the scene lacks")
        })?;
    let copy = Material {
        name: name.to_owned(),
        ..copy.clone()
    };
    scene.materials.push(copy);
    for o in scene.mesh.objects.iter_mut().filter(|o| o.name == name) {
        o.material = name.to_owned();
    }
    Ok(())
}

/// Sets `material`'s glossy part, scaling its Kd down (colour kept) where
/// Kd + Ks exceeds 1; says so when it does.
fn make_glossy(material: &mut Material, glossy: Glossy) -> Option<String> {
    material.glossy = Some(glossy);
    let kd = material.kd;
    let factor = (0..3)
        .filter(|&c| kd[c] + glossy.ks[c] > 1.0)
        .map(|c| (1.0 - glossy.ks[c]) / kd[c])
        .fold(1.0_f64, f64::min);
    if factor >= 1.0 {
        return None;
    }
    // Rounded to 6 decimals for a readable MTL, unless that would break the
    // solver's check (the f64 sum Kd + Ks above 1): then 1 − Ks, whose sum
    // with Ks rounds to 1 at most.
    let kd_for = |c: usize| {
        let ks = glossy.ks[c];
        let rounded = (kd[c] * factor * 1e6).round() / 1e6;
        if rounded + ks <= 1.0 {
            rounded
        } else {
            (1.0 - ks).max(0.0)
        }
    };
    material.kd = std::array::from_fn(kd_for);
    Some(format!(
        "{}: Kd {} {} {} scaled by {factor:.3} to {} {} {}, so that Kd + Ks ≤ 1",
        material.name, kd[0], kd[1], kd[2], material.kd[0], material.kd[1], material.kd[2]
    ))
}
