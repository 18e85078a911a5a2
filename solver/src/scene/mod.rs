//! Scenes as the solver sees them: planar polygons with materials, re-centred in
//! f64, with the settings that travel into the solution header.
//!
//! Importers for OBJ + MTL, the TOML scene config, the legacy geometry file
//! (000 appendix B) and the display parameter file (000 appendix A) all produce a
//! [`Scene`]. Units: positions in scene units, `emission` is emitted radiance
//! (W·sr⁻¹·m⁻², linear RGB), `kd`/`ks` are reflectances in [0, 1].

use crate::camera::{Camera, UpAxis};
use glam::DVec3;
use std::path::PathBuf;

/// Where a piece of input came from, for warnings and errors.
#[derive(Clone, Debug, PartialEq, Eq, Default)]
pub struct SourceRef {
    pub file: PathBuf,
    /// 1-based line number, when the parser knows it.
    pub line: Option<usize>,
    /// A human name for the item: "face 12", "polygon 3", "material white".
    pub item: String,
}

impl std::fmt::Display for SourceRef {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}", self.file.display())?;
        if let Some(line) = self.line {
            write!(f, ":{line}")?;
        }
        if !self.item.is_empty() {
            write!(f, " ({})", self.item)?;
        }
        Ok(())
    }
}

/// A surface material. Kd + Ks ≤ 1 per channel after import (design notes).
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    pub name: String,
    /// Diffuse hemispherical reflectance, linear RGB.
    pub kd: DVec3,
    /// Reflectance of the glossy lobe, linear RGB.
    pub ks: DVec3,
    /// RMS surface slope of the glossy lobe (000 eq. 4.1).
    pub alpha: f64,
    /// Emitted radiance, linear RGB, one-sided toward the polygon normal.
    pub emission: DVec3,
}

impl Material {
    pub fn is_emitter(&self) -> bool {
        self.emission.max_element() > 0.0
    }
    pub fn is_glossy(&self) -> bool {
        self.ks.max_element() > 0.0
    }
}

/// A planar, convex-or-not simple polygon after import and welding.
#[derive(Clone, Debug, PartialEq)]
pub struct Polygon {
    /// Re-centred positions, counter-clockwise seen from the front.
    pub vertices: Vec<DVec3>,
    /// Per-vertex shading normals for curved (smooth) surfaces; `None` for flat ones.
    pub vertex_normals: Option<Vec<DVec3>>,
    /// Index into [`Scene::materials`].
    pub material: usize,
    /// User-set patch subdivision (000 appendix B `patch N`): N × N patches.
    pub patches: u32,
    pub source: SourceRef,
}

impl Polygon {
    /// Newell's normal, normalised; zero for a degenerate polygon.
    pub fn normal(&self) -> DVec3 {
        let mut n = DVec3::ZERO;
        for (i, a) in self.vertices.iter().enumerate() {
            let b = self.vertices[(i + 1) % self.vertices.len()];
            n += a.cross(b);
        }
        n.normalize_or_zero()
    }

    /// Area by Newell's formula.
    pub fn area(&self) -> f64 {
        let mut n = DVec3::ZERO;
        for (i, a) in self.vertices.iter().enumerate() {
            let b = self.vertices[(i + 1) % self.vertices.len()];
            n += a.cross(b);
        }
        0.5 * n.length()
    }
}

/// A warning about the input: what was changed and where.
#[derive(Clone, Debug, PartialEq)]
pub struct Warning {
    pub source: SourceRef,
    pub message: String,
}

impl std::fmt::Display for Warning {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}: {}", self.source, self.message)
    }
}

/// A scene ready for meshing.
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    pub polygons: Vec<Polygon>,
    pub materials: Vec<Material>,
    pub units_per_metre: f64,
    pub up_axis: UpAxis,
    /// The initial camera in original scene coordinates, if the input names one.
    pub camera: Option<Camera>,
    /// The bounding-box centre subtracted (in f64) from every input position.
    pub recentre_offset: DVec3,
    pub warnings: Vec<Warning>,
}
