//! From the solution's frame (scene units, re-centred, any of four up axes)
//! to glTF's (metres, +y up, right-handed: glTF 2.0 specification, §3.4).
//!
//! Positions are baked, not placed by a node transform: each stored f32
//! position gets the header's f64 `recentre_offset` added back and is divided
//! by `units_per_metre` in f64, rotated, then rounded to f32 once. The exported
//! coordinate is therefore within half an f32 ulp (2⁻²⁴ relative) of the
//! metres value of the stored position plus the offset, and a viewer needs no
//! node transform to see the scene at its true place and size.

use glam::{DMat3, DQuat, DVec3};
use solution::camera::{Camera, UpAxis};

/// The change of frame: scene units to metres, the scene's up axis to +y.
#[derive(Clone, Copy, Debug)]
pub struct GltfFrame {
    offset: DVec3,
    units_per_metre: f64,
    up: UpAxis,
}

impl GltfFrame {
    pub fn new(recentre_offset: [f64; 3], units_per_metre: f64, up: UpAxis) -> GltfFrame {
        GltfFrame {
            offset: DVec3::from(recentre_offset),
            units_per_metre,
            up,
        }
    }

    /// The proper rotation (determinant +1) that takes the scene's up axis to
    /// +y. A rotation rather than a reflection keeps counter-clockwise front
    /// faces counter-clockwise, so indices are copied as stored. Each case only
    /// permutes and negates components, so it is exact in f32 and f64.
    pub fn rotate(&self, v: DVec3) -> DVec3 {
        match self.up {
            UpAxis::PosY => v,
            // Half a turn about x.
            UpAxis::NegY => DVec3::new(v.x, -v.y, -v.z),
            // A quarter turn about x: +z to +y, +y to −z.
            UpAxis::PosZ => DVec3::new(v.x, v.z, -v.y),
            // The opposite quarter turn: −z to +y, +y to +z.
            UpAxis::NegZ => DVec3::new(v.x, -v.z, v.y),
        }
    }

    /// A point in the scene's original (not re-centred) coordinates, in
    /// glTF metres (f64).
    pub fn scene_point(&self, p: DVec3) -> DVec3 {
        self.rotate(p / self.units_per_metre)
    }

    /// A stored (re-centred) position, in glTF metres rounded once to f32.
    pub fn file_position(&self, p: [f32; 3]) -> [f32; 3] {
        let scene = DVec3::from(p.map(f64::from)) + self.offset;
        self.scene_point(scene).as_vec3().to_array()
    }

    /// A direction (normal), rotated; exact, since the rotation only permutes
    /// and negates.
    pub fn direction(&self, d: [f32; 3]) -> [f32; 3] {
        let [x, y, z] = d;
        match self.up {
            UpAxis::PosY => [x, y, z],
            UpAxis::NegY => [x, -y, -z],
            UpAxis::PosZ => [x, z, -y],
            UpAxis::NegZ => [x, -z, y],
        }
    }

    /// A length in scene units, in metres.
    pub fn length(&self, scene_units: f64) -> f64 {
        scene_units / self.units_per_metre
    }

    /// The glTF camera node's placement for `camera` (original scene
    /// coordinates): the translation (eye, metres) and the rotation that takes
    /// the node's −z to the view direction and its +y to the camera's
    /// re-orthogonalised up (spec §3.10.1: a camera looks down its node's −z
    /// with +y up). Returns (translation, rotation as x, y, z, w).
    pub fn camera_node(&self, camera: &Camera) -> ([f64; 3], [f64; 4]) {
        let (right, up, forward) = camera.basis();
        let columns = DMat3::from_cols(self.rotate(right), self.rotate(up), -self.rotate(forward));
        let rotation = DQuat::from_mat3(&columns).normalize();
        let eye = self.scene_point(DVec3::from(camera.eye));
        (eye.to_array(), rotation.to_array())
    }
}
