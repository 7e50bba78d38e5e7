//! The voxel grid: the scalar fields that the volume and surface views are built from.
//!
//! Layout (keep in sync with every shader that reads a grid): `dims` voxels along x, y, z;
//! voxel (i, j, k) is element `i + dims.x * (j + dims.y * k)` of each buffer, an `f32`; its
//! centre is at `box_min + (ijk + 0.5) * voxel_size` in data space, where
//! `voxel_size = (box_max - box_min) / dims`.
//! `density` holds the normalized loudness density in [0, 1]; `hp_mean` the mean hp of the points
//! in the voxel (0.5 where a voxel holds none).

pub mod difference;
pub mod downsample;
pub mod reference;
pub mod settings;
pub mod voxelize;
pub mod voxelize_cpu;
pub mod voxelize_host;

use glam::{UVec3, Vec3};
use wgpu::util::DeviceExt;

use crate::render::gpu::readback::{ReadbackError, read_buffer};

pub struct VoxelGrid {
    pub dims: UVec3,
    pub box_min: Vec3,
    pub box_max: Vec3,
    /// `f32` per voxel, STORAGE | COPY_SRC | COPY_DST.
    pub density: wgpu::Buffer,
    /// `f32` per voxel, STORAGE | COPY_SRC | COPY_DST.
    pub hp_mean: wgpu::Buffer,
}

impl VoxelGrid {
    pub fn voxel_count(&self) -> u64 {
        u64::from(self.dims.x) * u64::from(self.dims.y) * u64::from(self.dims.z)
    }

    pub fn voxel_size(&self) -> Vec3 {
        (self.box_max - self.box_min) / self.dims.as_vec3()
    }

    /// A grid from fields computed on the CPU (tests, analytic fields, imported grids).
    pub fn from_fields(
        device: &wgpu::Device,
        dims: UVec3,
        box_min: Vec3,
        box_max: Vec3,
        density: &[f32],
        hp_mean: &[f32],
    ) -> Self {
        let n = (dims.x * dims.y * dims.z) as usize;
        assert_eq!(density.len(), n, "density has the wrong voxel count");
        assert_eq!(hp_mean.len(), n, "hp_mean has the wrong voxel count");
        // Padded to whole groups of four voxels as the voxelize pass leaves its fields (the
        // passes that read four voxels at a time bind them whole), the padding an empty voxel.
        let padded = |field: &[f32], empty: f32| {
            let mut padded = Vec::with_capacity(n.div_ceil(4) * 4);
            padded.extend_from_slice(field);
            padded.resize(n.div_ceil(4) * 4, empty);
            padded
        };
        let padding = !n.is_multiple_of(4);
        let (density_padded, hp_padded);
        let (density, hp_mean) = if padding {
            density_padded = padded(density, 0.0);
            hp_padded = padded(hp_mean, 0.5);
            (&density_padded[..], &hp_padded[..])
        } else {
            (density, hp_mean)
        };
        let usage = wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_SRC
            | wgpu::BufferUsages::COPY_DST;
        let density = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("grid::density"),
            contents: bytemuck::cast_slice(density),
            usage,
        });
        let hp_mean = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("grid::hp_mean"),
            contents: bytemuck::cast_slice(hp_mean),
            usage,
        });
        Self {
            dims,
            box_min,
            box_max,
            density,
            hp_mean,
        }
    }

    /// Reads a field back to the CPU (tests, export).
    pub fn read_field(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        field: &wgpu::Buffer,
    ) -> Result<Vec<f32>, ReadbackError> {
        let bytes = read_buffer(
            device,
            queue,
            "grid::readback",
            field,
            self.voxel_count() * 4,
        )?;
        Ok(bytemuck::cast_slice(&bytes).to_vec())
    }
}

/// The smoothing sigma a song's grid gets by default, in voxels.
pub const SONG_SMOOTHING: f32 = 1.0;
/// The smoothing sigma a timeline's grid gets by default, in voxels: a timeline holds a few
/// hundred points a song in a 224^3 grid, so with a song's sigma of 1 each point is a speck of
/// its own and the isosurface at 0.5 of the 99th-percentile density is "a few specks" (the
/// demo timeline: 20 songs of 400 points). Sigma 4 (1.8 % of the box a side) joins each song's
/// points into one body, which is the shape of its loudness over the years.
pub const TIMELINE_SMOOTHING: f32 = 4.0;

pub fn default_smoothing(mode: crate::data::cloud::DataMode) -> f32 {
    use crate::data::cloud::DataMode;
    match mode {
        DataMode::Timeline => TIMELINE_SMOOTHING,
        DataMode::Song | DataMode::Generic => SONG_SMOOTHING,
    }
}
