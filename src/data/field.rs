//! A field on the CPU: density and mean hp on a box of voxels, as a `.npy` file holds it or as a
//! voxel grid is read back for picking. Same layout as [`crate::render::grid::VoxelGrid`]: voxel
//! (i, j, k) is element `i + dims.x * (j + dims.y * k)`, centred at
//! `box_min + (ijk + 0.5) * voxel_size`.

use glam::{UVec3, Vec3};

/// Density and mean hp per voxel over a box.
#[derive(Clone, Debug, Default)]
pub struct Field {
    pub dims: UVec3,
    pub box_min: Vec3,
    pub box_max: Vec3,
    pub density: Vec<f32>,
    pub hp_mean: Vec<f32>,
}

impl Field {
    /// The element of voxel `v`.
    pub fn index(&self, v: UVec3) -> usize {
        (v.x + self.dims.x * (v.y + self.dims.y * v.z)) as usize
    }

    /// The voxel holding `p`, or None outside the box.
    pub fn voxel_of(&self, p: Vec3) -> Option<UVec3> {
        let size = (self.box_max - self.box_min) / self.dims.as_vec3();
        let f = ((p - self.box_min) / size).floor();
        if f.min_element() < 0.0 {
            return None;
        }
        let v = f.as_uvec3();
        (v.x < self.dims.x && v.y < self.dims.y && v.z < self.dims.z).then_some(v)
    }
}
