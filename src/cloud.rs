//! PLY point-cloud loading. (Stand-in until the loader lands.)
use std::path::{Path, PathBuf};

use crate::axes::Axis;

#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Point {
    pub position: [f32; 3],
    pub scalar: f32,
    pub hp: f32,
}
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DataMode {
    Song,
    Timeline,
    Generic,
}
#[derive(Clone, Debug, Default)]
pub struct Axes {
    pub x: Axis,
    pub y: Axis,
    pub z: Axis,
    pub scalar: Axis,
    pub hp: Axis,
}
#[derive(Clone, Debug)]
pub struct CloudMeta {
    pub mode: DataMode,
    pub axes: Axes,
}
#[derive(Clone, Copy, Debug)]
pub struct Aabb {
    pub min: glam::Vec3,
    pub max: glam::Vec3,
}
pub struct PointCloud {
    pub path: PathBuf,
    pub points: Vec<Point>,
    pub meta: CloudMeta,
    pub bounds: Aabb,
}
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct CloudError(String);

pub fn load(path: &Path) -> Result<PointCloud, CloudError> {
    Err(CloudError(format!(
        "{}: loader not built yet",
        path.display()
    )))
}

impl PointCloud {
    /// A cloud made in code (tests, benchmarks): axes labelled as a song's.
    pub fn synthetic(points: Vec<Point>, mode: DataMode) -> Self {
        let mut min = glam::Vec3::splat(f32::INFINITY);
        let mut max = glam::Vec3::splat(f32::NEG_INFINITY);
        for p in &points {
            min = min.min(p.position.into());
            max = max.max(p.position.into());
        }
        let axis = |unit: &str| Axis {
            label: String::new(),
            unit: unit.into(),
            min: -1.0,
            max: 1.0,
        };
        Self {
            path: PathBuf::from("synthetic"),
            points,
            meta: CloudMeta {
                mode,
                axes: Axes {
                    x: axis("s"),
                    y: axis("dB"),
                    z: axis("Hz"),
                    scalar: axis(""),
                    hp: axis(""),
                },
            },
            bounds: Aabb { min, max },
        }
    }
}
