//! Built-in solids, so a design can be sliced with no file at all.

use super::Mesh;
use serde::{Deserialize, Serialize};

/// A built-in solid standing on the plate (min Z = 0), centred on X = Y = 0. Sizes in mm.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "shape", rename_all = "snake_case", deny_unknown_fields)]
pub enum Shape {
    /// Box with edge lengths `size` = [x, y, z] mm.
    Cube {
        /// Edge lengths in mm.
        size: [f64; 3],
    },
    /// Sphere of `radius` mm, `segments` around (latitude bands = segments / 2).
    Sphere {
        /// Radius in mm.
        radius: f64,
        /// Facets around the equator (8–512).
        #[serde(default = "default_segments")]
        segments: u32,
    },
    /// Upright cylinder.
    Cylinder {
        /// Radius in mm.
        radius: f64,
        /// Height in mm.
        height: f64,
        /// Facets around (8–512).
        #[serde(default = "default_segments")]
        segments: u32,
    },
    /// Upright cylinder whose top is a paraboloid dish `dish_depth` deep at the centre
    /// (the GIPPO paper's concave cylinder: every layer near the top is different).
    ConcaveCylinder {
        /// Radius in mm.
        radius: f64,
        /// Height at the rim in mm.
        height: f64,
        /// Depth of the dish at the centre in mm (less than `height`).
        dish_depth: f64,
        /// Facets around (8–512).
        #[serde(default = "default_segments")]
        segments: u32,
    },
}

fn default_segments() -> u32 {
    64
}

/// Form rows of a built-in shape input (paths relative to the [`crate::design::Input`]).
pub const FIELDS: &[crate::settings::Field] = &[
    crate::settings::vec3("builtin.size", "Input", "Cube size X, Y, Z", "mm", 0.01, 2000.0, 0.1, ""),
    crate::settings::num("builtin.radius", "Input", "Radius", "mm", 0.01, 1000.0, 0.1, ""),
    crate::settings::num("builtin.height", "Input", "Height", "mm", 0.01, 2000.0, 0.1, ""),
    crate::settings::num("builtin.dish_depth", "Input", "Dish depth", "mm", 0.0, 2000.0, 0.1, "Depth of the concave top at the centre."),
    crate::settings::int("builtin.segments", "Input", "Facets around", 8.0, 512.0, "More facets: a smoother round part."),
];

impl Shape {
    /// One shape of each kind with its default size (the page's shape menu): name, label, shape.
    pub fn defaults() -> Vec<(&'static str, &'static str, Shape)> {
        vec![
            ("cube", "Cube", Shape::Cube { size: [20.0, 20.0, 20.0] }),
            ("sphere", "Sphere", Shape::Sphere { radius: 10.0, segments: 64 }),
            ("cylinder", "Cylinder", Shape::Cylinder { radius: 10.0, height: 20.0, segments: 64 }),
            ("concave_cylinder", "Concave cylinder", Shape::ConcaveCylinder { radius: 10.0, height: 10.0, dish_depth: 4.0, segments: 64 }),
        ]
    }

    /// Triangulates the shape.
    pub fn mesh(&self) -> Mesh {
        match *self {
            Shape::Cube { size } => cube(size),
            Shape::Sphere { radius, segments } => uv_sphere(radius, segments.clamp(8, 512)),
            Shape::Cylinder { radius, height, segments } => cylinder(radius, height, segments.clamp(8, 512)),
            Shape::ConcaveCylinder { radius, height, dish_depth, segments } => {
                concave_cylinder(radius, height, dish_depth.clamp(0.0, height * 0.99), segments.clamp(8, 512))
            }
        }
    }
}

fn cube(s: [f64; 3]) -> Mesh {
    let (hx, hy, z) = (s[0] / 2.0, s[1] / 2.0, s[2]);
    let v = |x: f64, y: f64, z: f64| [x as f32, y as f32, z as f32];
    let vertices = vec![v(-hx, -hy, 0.0), v(hx, -hy, 0.0), v(hx, hy, 0.0), v(-hx, hy, 0.0), v(-hx, -hy, z), v(hx, -hy, z), v(hx, hy, z), v(-hx, hy, z)];
    let triangles = vec![
        [0, 2, 1],
        [0, 3, 2], // bottom (facing -Z)
        [4, 5, 6],
        [4, 6, 7], // top
        [0, 1, 5],
        [0, 5, 4], // -Y
        [1, 2, 6],
        [1, 6, 5], // +X
        [2, 3, 7],
        [2, 7, 6], // +Y
        [3, 0, 4],
        [3, 4, 7], // -X
    ];
    Mesh { vertices, triangles }
}

/// UV sphere standing on the plate, `seg` facets around (no clamping: benchmarks use ~1000).
pub fn uv_sphere(r: f64, seg: u32) -> Mesh {
    let rings = (seg / 2).max(4);
    let mut m = Mesh::default();
    m.vertices.push([0.0, 0.0, 0.0]); // south pole
    for i in 1..rings {
        let phi = std::f64::consts::PI * i as f64 / rings as f64;
        let (sp, cp) = (libm::sin(phi), libm::cos(phi));
        for j in 0..seg {
            let th = 2.0 * std::f64::consts::PI * j as f64 / seg as f64;
            m.vertices.push([(r * sp * libm::cos(th)) as f32, (r * sp * libm::sin(th)) as f32, (r - r * cp) as f32]);
        }
    }
    let north = m.vertices.len() as u32;
    m.vertices.push([0.0, 0.0, (2.0 * r) as f32]);
    let ring = |i: u32, j: u32| 1 + (i - 1) * seg + (j % seg);
    for j in 0..seg {
        m.triangles.push([0, ring(1, j + 1), ring(1, j)]);
        m.triangles.push([north, ring(rings - 1, j), ring(rings - 1, j + 1)]);
    }
    for i in 1..rings - 1 {
        for j in 0..seg {
            let (a, b, c, d) = (ring(i, j), ring(i, j + 1), ring(i + 1, j + 1), ring(i + 1, j));
            m.triangles.push([a, b, c]);
            m.triangles.push([a, c, d]);
        }
    }
    m
}

fn cylinder(r: f64, h: f64, seg: u32) -> Mesh {
    let mut m = Mesh::default();
    m.vertices.push([0.0, 0.0, 0.0]);
    m.vertices.push([0.0, 0.0, h as f32]);
    for j in 0..seg {
        let th = 2.0 * std::f64::consts::PI * j as f64 / seg as f64;
        let (x, y) = ((r * libm::cos(th)) as f32, (r * libm::sin(th)) as f32);
        m.vertices.push([x, y, 0.0]);
        m.vertices.push([x, y, h as f32]);
    }
    let lo = |j: u32| 2 + 2 * (j % seg);
    let hi = |j: u32| 3 + 2 * (j % seg);
    for j in 0..seg {
        m.triangles.push([0, lo(j + 1), lo(j)]);
        m.triangles.push([1, hi(j), hi(j + 1)]);
        m.triangles.push([lo(j), lo(j + 1), hi(j + 1)]);
        m.triangles.push([lo(j), hi(j + 1), hi(j)]);
    }
    m
}

fn concave_cylinder(r: f64, h: f64, depth: f64, seg: u32) -> Mesh {
    let rings = (seg / 4).max(4);
    let mut m = Mesh::default();
    let top_z = |t: f64| h - depth * (1.0 - t * t); // t = radius fraction
    m.vertices.push([0.0, 0.0, 0.0]);
    m.vertices.push([0.0, 0.0, top_z(0.0) as f32]);
    // Ring k (1..=rings) of the dish at radius fraction k/rings; ring `rings` is the rim.
    for k in 1..=rings {
        let t = k as f64 / rings as f64;
        for j in 0..seg {
            let th = 2.0 * std::f64::consts::PI * j as f64 / seg as f64;
            m.vertices.push([(t * r * libm::cos(th)) as f32, (t * r * libm::sin(th)) as f32, top_z(t) as f32]);
        }
    }
    let bottom = m.vertices.len() as u32;
    for j in 0..seg {
        let th = 2.0 * std::f64::consts::PI * j as f64 / seg as f64;
        m.vertices.push([(r * libm::cos(th)) as f32, (r * libm::sin(th)) as f32, 0.0]);
    }
    let ring = |k: u32, j: u32| 2 + (k - 1) * seg + (j % seg);
    let low = |j: u32| bottom + (j % seg);
    for j in 0..seg {
        m.triangles.push([1, ring(1, j), ring(1, j + 1)]);
        for k in 1..rings {
            let (a, b, c, d) = (ring(k, j), ring(k + 1, j), ring(k + 1, j + 1), ring(k, j + 1));
            m.triangles.push([a, b, c]);
            m.triangles.push([a, c, d]);
        }
        let (rim0, rim1) = (ring(rings, j), ring(rings, j + 1));
        m.triangles.push([low(j), low(j + 1), rim1]);
        m.triangles.push([low(j), rim1, rim0]);
        m.triangles.push([0, low(j + 1), low(j)]);
    }
    m
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every edge of a closed, consistently oriented mesh appears once in each direction.
    fn assert_closed(m: &Mesh) {
        let mut edges = std::collections::BTreeMap::new();
        for t in &m.triangles {
            for k in 0..3 {
                *edges.entry((t[k], t[(k + 1) % 3])).or_insert(0) += 1;
            }
        }
        for (&(a, b), &n) in &edges {
            assert_eq!(n, 1, "edge {a}-{b} used {n} times");
            assert_eq!(edges.get(&(b, a)), Some(&1), "edge {a}-{b} has no twin");
        }
    }

    #[test]
    fn builtins_are_closed_and_stand_on_the_plate() {
        for s in [
            Shape::Cube { size: [20.0, 10.0, 5.0] },
            Shape::Sphere { radius: 10.0, segments: 32 },
            Shape::Cylinder { radius: 5.0, height: 8.0, segments: 24 },
            Shape::ConcaveCylinder { radius: 5.0, height: 4.0, dish_depth: 2.0, segments: 32 },
        ] {
            let m = s.mesh();
            assert_closed(&m);
            let b = m.bounds().unwrap();
            assert!(b.min.z.abs() < 1e-6, "{s:?} min z {}", b.min.z);
        }
    }
}
