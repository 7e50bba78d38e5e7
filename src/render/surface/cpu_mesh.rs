//! An extracted surface read back to the CPU, for tests and export.

use glam::Vec3;

/// An extracted surface on the CPU (tests, export): indexed triangles in data space.
#[derive(Clone, Debug, Default)]
pub struct CpuMesh {
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    pub hp: Vec<f32>,
    pub indices: Vec<u32>,
}

impl CpuMesh {
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }

    pub fn triangle(&self, t: usize) -> [Vec3; 3] {
        let i = &self.indices[t * 3..t * 3 + 3];
        [
            self.positions[i[0] as usize],
            self.positions[i[1] as usize],
            self.positions[i[2] as usize],
        ]
    }

    /// Total area, in data-space units.
    pub fn area(&self) -> f64 {
        (0..self.triangle_count())
            .map(|t| {
                let [a, b, c] = self.triangle(t);
                f64::from((b - a).cross(c - a).length()) * 0.5
            })
            .sum()
    }

    /// The same surface with vertices at bit-identical positions merged (crossings that land
    /// exactly on a shared grid sample), and triangles that collapse to a line or point dropped.
    pub fn welded(&self) -> CpuMesh {
        let mut map = std::collections::HashMap::new();
        let mut out = CpuMesh::default();
        let mut remap = Vec::with_capacity(self.positions.len());
        for (i, p) in self.positions.iter().enumerate() {
            let key = [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()];
            let index = *map.entry(key).or_insert_with(|| {
                out.positions.push(*p);
                out.normals.push(self.normals[i]);
                out.hp.push(self.hp[i]);
                (out.positions.len() - 1) as u32
            });
            remap.push(index);
        }
        for tri in self.indices.chunks_exact(3) {
            let [a, b, c] = [0, 1, 2].map(|k| remap[tri[k] as usize]);
            if a != b && b != c && a != c {
                out.indices.extend_from_slice(&[a, b, c]);
            }
        }
        out
    }
}
