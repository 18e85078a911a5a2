//! Triangle meshes as the generator builds them, and the checks the tests run
//! on them: closed and consistently wound (every directed edge once, its
//! reverse once), outward (positive signed volume), non-degenerate.

use std::collections::HashMap;

/// A point or direction in scene units (millimetres).
pub type Vec3 = [f64; 3];

pub fn sub(a: Vec3, b: Vec3) -> Vec3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

pub fn add(a: Vec3, b: Vec3) -> Vec3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

pub fn scale(a: Vec3, s: f64) -> Vec3 {
    [a[0] * s, a[1] * s, a[2] * s]
}

pub fn dot(a: Vec3, b: Vec3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

pub fn cross(a: Vec3, b: Vec3) -> Vec3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

pub fn length(a: Vec3) -> f64 {
    dot(a, a).sqrt()
}

/// Which side of a closed object is its front (the side the solver lights).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Closure {
    /// A closed solid seen from outside (a box, a sphere, a wall slab).
    Outward,
    /// A closed shell seen from inside (a room).
    Inward,
    /// Not closed (a floor quad, a light, the open Cornell box).
    Open,
}

/// One triangle corner: a position index and, for smooth surfaces, a normal index.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Corner {
    pub position: u32,
    pub normal: Option<u32>,
}

impl Corner {
    pub fn flat(position: u32) -> Self {
        Corner {
            position,
            normal: None,
        }
    }
}

/// A named group of triangles with one material (an OBJ `o`/`g` + `usemtl`).
#[derive(Clone, Debug)]
pub struct Object {
    pub name: String,
    pub material: String,
    pub closure: Closure,
    pub triangles: Vec<[Corner; 3]>,
}

/// Positions and normals shared by all objects, and the objects.
#[derive(Clone, Debug, Default)]
pub struct Mesh {
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    pub objects: Vec<Object>,
}

impl Mesh {
    pub fn triangle_count(&self) -> usize {
        self.objects.iter().map(|o| o.triangles.len()).sum()
    }

    pub fn add_position(&mut self, p: Vec3) -> u32 {
        self.positions.push(p);
        (self.positions.len() - 1) as u32
    }

    pub fn add_normal(&mut self, n: Vec3) -> u32 {
        let l = length(n);
        self.normals.push(scale(n, 1.0 / l));
        (self.normals.len() - 1) as u32
    }

    /// Starts a new object; the following triangles go into it.
    pub fn begin_object(&mut self, name: impl Into<String>, material: &str, closure: Closure) {
        self.objects.push(Object {
            name: name.into(),
            material: material.to_owned(),
            closure,
            triangles: Vec::new(),
        });
    }

    /// Adds a triangle to the current object, wound so that its geometric
    /// normal has a non-negative component along `front` (the side the solver
    /// lights: the winding decides the front).
    pub fn triangle_facing(&mut self, corners: [Corner; 3], front: Vec3) {
        let [a, b, c] = corners;
        let n = self.geometric_normal(&corners);
        let oriented = if dot(n, front) < 0.0 {
            [a, c, b]
        } else {
            [a, b, c]
        };
        self.push_triangle(oriented);
    }

    /// Adds a quad (counter-clockwise seen from the front) as two triangles.
    pub fn quad(&mut self, corners: [Corner; 4]) {
        let [a, b, c, d] = corners;
        self.push_triangle([a, b, c]);
        self.push_triangle([a, c, d]);
    }

    /// Adds a triangle to the current object. The generators always call
    /// `begin_object` first (a programming error otherwise, never input), so
    /// the expect below cannot be reached from a user's flags.
    pub fn push_triangle(&mut self, corners: [Corner; 3]) {
        self.objects
            .last_mut()
            .expect("begin_object before adding triangles")
            .triangles
            .push(corners);
    }

    /// (b − a) × (c − a): twice the area times the unit normal.
    pub fn geometric_normal(&self, corners: &[Corner; 3]) -> Vec3 {
        let p = |c: &Corner| self.positions[c.position as usize];
        cross(
            sub(p(&corners[1]), p(&corners[0])),
            sub(p(&corners[2]), p(&corners[0])),
        )
    }

    pub fn triangle_area(&self, corners: &[Corner; 3]) -> f64 {
        0.5 * length(self.geometric_normal(corners))
    }

    /// The smallest ratio of a triangle's area to its longest edge squared over
    /// the whole mesh: 0 for a degenerate (zero-area or sliver) triangle, √3/4
    /// for an equilateral one.
    pub fn min_shape_quality(&self) -> f64 {
        let mut worst = f64::INFINITY;
        for object in &self.objects {
            for t in &object.triangles {
                let p = |i: usize| self.positions[t[i].position as usize];
                let longest = (0..3)
                    .map(|i| length(sub(p((i + 1) % 3), p(i))))
                    .fold(0.0, f64::max);
                worst = worst.min(self.triangle_area(t) / (longest * longest));
            }
        }
        worst
    }

    /// The closed object's signed volume by the divergence theorem: the sum of
    /// a · (b × c) / 6 over its triangles. Positive when the triangles face
    /// outward, negative when they face inward. Positions are taken relative to
    /// the object's first vertex (the sum does not depend on the origin for a
    /// closed surface), so a small box far from the origin keeps its digits.
    pub fn signed_volume(&self, object: &Object) -> f64 {
        let Some(first) = object.triangles.first() else {
            return 0.0;
        };
        let origin = self.positions[first[0].position as usize];
        object
            .triangles
            .iter()
            .map(|t| {
                let p = |i: usize| sub(self.positions[t[i].position as usize], origin);
                dot(p(0), cross(p(1), p(2))) / 6.0
            })
            .sum()
    }
}

/// Checks that `object` is a closed, consistently wound surface: every directed
/// edge (a → b) occurs exactly once and its reverse (b → a) exactly once, so
/// each undirected edge is used by exactly two triangles with opposite
/// orientations. Returns the first offending edge.
pub fn check_closed(object: &Object) -> Result<(), String> {
    let mut directed: HashMap<(u32, u32), u32> = HashMap::new();
    for t in &object.triangles {
        for i in 0..3 {
            let edge = (t[i].position, t[(i + 1) % 3].position);
            *directed.entry(edge).or_default() += 1;
        }
    }
    for (&(a, b), &count) in &directed {
        if count != 1 {
            return Err(format!(
                "object {}: edge {a} → {b} is used {count} times in one direction",
                object.name
            ));
        }
        if directed.get(&(b, a)) != Some(&1) {
            return Err(format!(
                "object {}: edge {a} → {b} has no reverse: the surface is open or inconsistently wound",
                object.name
            ));
        }
    }
    Ok(())
}
