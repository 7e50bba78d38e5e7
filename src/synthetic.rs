//! Clouds made in code, for tests and benchmarks.

use std::path::PathBuf;

use crate::axes::{Axes, Axis};
use crate::cloud::{Aabb, CloudMeta, DataMode, Point, PointCloud};

impl PointCloud {
    /// A cloud made in code: axes labelled as a song's (time 0-30 s, level -80-0 dB,
    /// frequency 0-22.05 kHz) or a timeline's (years 1970-2020).
    pub fn synthetic(points: Vec<Point>, mode: DataMode) -> Self {
        let axes = match mode {
            DataMode::Timeline => Axes {
                x: Axis::linear("year", "year", 1970.0, 2020.0),
                y: Axis::linear("level", "dB", -60.0, 0.0),
                z: Axis::linear("crest factor", "dB", 3.0, 20.0),
                scalar: Axis::linear("loudness", "dB", -60.0, 0.0),
                hp: Axis::linear("hp", "", 0.0, 1.0),
            },
            _ => Axes {
                x: Axis::linear("time", "s", 0.0, 30.0),
                y: Axis::linear("level", "dB", -80.0, 0.0),
                z: Axis::linear("frequency", "Hz", 0.0, 22050.0),
                scalar: Axis::linear("loudness", "dB", -80.0, 0.0),
                hp: Axis::linear("hp", "", 0.0, 1.0),
            },
        };
        Self {
            path: PathBuf::from("synthetic"),
            bounds: Aabb::from_points(&points),
            points,
            meta: CloudMeta {
                mode,
                axes,
                point_count: None,
                source: None,
                stft: None,
                metrics: None,
                songs: Vec::new(),
                raw: serde_json::Value::Null,
            },
        }
    }
}
