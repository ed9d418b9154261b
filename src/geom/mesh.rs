use glam::DVec3;

/// An indexed triangle mesh in millimetres. Triangles are counter-clockwise seen from
/// outside. Importers guarantee every index is in range; nothing else is guaranteed
/// (meshes may be open, have duplicates or overlap themselves; the slicer copes).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    /// Vertex positions in mm.
    pub vertices: Vec<[f32; 3]>,
    /// Vertex indices, three per triangle.
    pub triangles: Vec<[u32; 3]>,
}

/// Axis-aligned bounding box in mm.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// Smallest corner.
    pub min: DVec3,
    /// Largest corner.
    pub max: DVec3,
}

impl Aabb {
    /// Size along each axis.
    pub fn size(&self) -> DVec3 {
        self.max - self.min
    }
}

impl Mesh {
    /// A mesh from a triangle soup, 9 floats per triangle (a `mesh` view's data); vertices are
    /// not welded (each triangle has its own three).
    pub fn from_triangle_floats(data: &[f32]) -> Mesh {
        let tris = data.len() / 9;
        let mut m = Mesh { vertices: Vec::with_capacity(tris * 3), triangles: Vec::with_capacity(tris) };
        for (t, c) in data.chunks_exact(9).enumerate() {
            m.vertices.extend_from_slice(&[[c[0], c[1], c[2]], [c[3], c[4], c[5]], [c[6], c[7], c[8]]]);
            let b = (3 * t) as u32;
            m.triangles.push([b, b + 1, b + 2]);
        }
        m
    }

    /// The bounding box of all vertices referenced or not; `None` for an empty mesh.
    pub fn bounds(&self) -> Option<Aabb> {
        let mut it = self.vertices.iter();
        let first = it.next()?;
        let mut min = DVec3::new(first[0] as f64, first[1] as f64, first[2] as f64);
        let mut max = min;
        for v in it {
            let p = DVec3::new(v[0] as f64, v[1] as f64, v[2] as f64);
            min = min.min(p);
            max = max.max(p);
        }
        Some(Aabb { min, max })
    }

    /// Vertex `i` as f64.
    #[inline]
    pub fn vertex(&self, i: u32) -> DVec3 {
        let v = self.vertices[i as usize];
        DVec3::new(v[0] as f64, v[1] as f64, v[2] as f64)
    }

    /// Moves every vertex by `d` mm.
    pub fn translate(&mut self, d: DVec3) {
        for v in &mut self.vertices {
            v[0] = (v[0] as f64 + d.x) as f32;
            v[1] = (v[1] as f64 + d.y) as f32;
            v[2] = (v[2] as f64 + d.z) as f32;
        }
    }

    /// Binary STL bytes (80-byte header, facet normals computed, little-endian).
    pub fn to_stl_binary(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(84 + 50 * self.triangles.len());
        let mut header = [b' '; 80];
        header[..12].copy_from_slice(b"weft binary ");
        out.extend_from_slice(&header);
        out.extend_from_slice(&(self.triangles.len() as u32).to_le_bytes());
        for t in &self.triangles {
            let [a, b, c] = [self.vertex(t[0]), self.vertex(t[1]), self.vertex(t[2])];
            let n = (b - a).cross(c - a).normalize_or_zero();
            for x in [n.x, n.y, n.z] {
                out.extend_from_slice(&(x as f32).to_le_bytes());
            }
            for &i in t {
                for x in self.vertices[i as usize] {
                    out.extend_from_slice(&x.to_le_bytes());
                }
            }
            out.extend_from_slice(&[0, 0]);
        }
        out
    }

    /// Appends another mesh (indices shifted).
    pub fn append(&mut self, other: &Mesh) {
        let base = self.vertices.len() as u32;
        self.vertices.extend_from_slice(&other.vertices);
        self.triangles.extend(other.triangles.iter().map(|t| [t[0] + base, t[1] + base, t[2] + base]));
    }
}
