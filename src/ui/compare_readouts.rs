//! The A/B compare's hover read-outs: in side by side the point under the cursor and the other
//! song's nearest one, in the difference view the voxel under the cursor and both differences
//! there. Called by `compare_view.rs`; the side-by-side read-outs are worked out once for a
//! cursor spot and camera ([`CompareHover`]), as the single view's hover is, not in every frame
//! the halves fill in (a pick among every point of a song of millions, each frame).

use std::sync::{Arc, Weak};

use crate::data::cloud::PointCloud;
use crate::ui::state::compare_window::DifferenceCopy;
use crate::view::frame_view::FrameView;
use crate::view::pick::{self, Reading};

/// What the side-by-side read-outs were worked out for (besides the scene's clouds): the half,
/// the cursor's pixel, the camera and the view's size, and the letter beside A.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct CompareHoverKey {
    pub(super) side: usize,
    pub(super) px: glam::Vec2,
    pub(super) camera: crate::view::camera::Camera,
    pub(super) size: (u32, u32),
    pub(super) letter: char,
}

/// Read-outs kept with the scene and the key they were worked out for.
type KeptReadings = (
    Weak<(PointCloud, PointCloud)>,
    CompareHoverKey,
    Vec<Reading>,
);

/// The side-by-side read-outs last worked out, and for what: the scene's clouds (held weakly:
/// their points are freed with the scene, and no new scene takes their place's address while
/// held) and the key.
#[derive(Default)]
pub(in crate::ui) struct CompareHover {
    last: Option<KeptReadings>,
}

impl CompareHover {
    /// The read-outs for `key` over `clouds`: the kept ones when both are the last ones', else
    /// `compute`'s.
    pub(super) fn readings(
        &mut self,
        clouds: &Arc<(PointCloud, PointCloud)>,
        key: CompareHoverKey,
        compute: impl FnOnce() -> Vec<Reading>,
    ) -> Vec<Reading> {
        match &self.last {
            Some((scene, last, readings))
                if *last == key && std::ptr::eq(scene.as_ptr(), Arc::as_ptr(clouds)) =>
            {
                readings.clone()
            }
            _ => {
                let readings = compute();
                self.last = Some((Arc::downgrade(clouds), key, readings.clone()));
                readings
            }
        }
    }
}

/// Read-outs in side by side: the point under the cursor on its side, and on the other side
/// the point nearest the same time and frequency (the loudest of those within a voxel).
pub(super) fn compare_readings(
    clouds: &(PointCloud, PointCloud),
    letter: char,
    side: usize,
    view: &FrameView,
    px: glam::Vec2,
) -> Vec<Reading> {
    let both = [&clouds.0, &clouds.1];
    let here = both[side];
    let there = both[1 - side];
    let names = ["A".to_string(), letter.to_string()];
    let Some(index) = pick::pick_point(&here.points, view, px, 6.0, 0.0) else {
        return Vec::new();
    };
    let point = &here.points[index];
    let mut out = vec![Reading {
        name: names[side].clone(),
        value: here
            .path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default(),
    }];
    out.extend(pick::point_readings(&here.meta.axes, point));
    // The other song at the same time and frequency: its loudest point within 1/128 of the box.
    let near = there
        .points
        .iter()
        .filter(|q| {
            (q.position[0] - point.position[0]).abs() < 1.0 / 64.0
                && (q.position[2] - point.position[2]).abs() < 1.0 / 64.0
        })
        .max_by(|a, b| a.scalar.total_cmp(&b.scalar));
    let axes = &there.meta.axes;
    match near {
        Some(q) => {
            out.push(Reading {
                name: format!("{} level (loudest here)", names[1 - side]),
                value: axes
                    .y
                    .format_value(axes.y.value_at(f64::from(q.position[1]))),
            });
            out.push(Reading {
                name: format!("{} loudness (loudest here)", names[1 - side]),
                value: axes
                    .scalar
                    .format_value(axes.scalar.value_at_unit(f64::from(q.scalar))),
            });
        }
        None => out.push(Reading {
            name: names[1 - side].clone(),
            value: "nothing at this time and frequency".into(),
        }),
    }
    out
}

/// Read-outs in the difference view: the first tinted voxel along the ray, its place, and both
/// differences there.
pub(super) fn difference_readings(
    a: &PointCloud,
    copy: &DifferenceCopy,
    view: &FrameView,
    px: glam::Vec2,
) -> Vec<Reading> {
    let (origin, dir) = pick::cursor_ray(view, px);
    let Some(hit) = copy.shown.pick(origin, dir, 0.05) else {
        return Vec::new();
    };
    let dims = copy.shown.dims;
    let voxel = copy.shown.index(hit.voxel);
    let column = (hit.voxel.x + dims.x * hit.voxel.z) as usize;
    let mut out = pick::position_readings(&a.meta.axes, hit.position);
    out.push(Reading {
        name: "density B - A".into(),
        value: crate::ui::compare::format_signed(copy.difference[voxel]),
    });
    out.push(Reading {
        name: "level-weighted B - A".into(),
        value: crate::ui::compare::format_signed(copy.columns[column]),
    });
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::view::camera::Camera;

    /// A frame with the same cursor spot, camera and scene takes the kept read-outs; any of
    /// them changed works them out again.
    #[test]
    fn read_outs_are_worked_out_once_a_spot() {
        use crate::data::cloud::DataMode;
        use crate::data::synthetic::synthetic_song;
        let cloud = || PointCloud::synthetic(synthetic_song(10, 3), DataMode::Song);
        let scene = Arc::new((cloud(), cloud()));
        let key = CompareHoverKey {
            side: 0,
            px: glam::Vec2::new(10.0, 20.0),
            camera: Camera::default(),
            size: (640, 400),
            letter: 'B',
        };
        let mut hover = CompareHover::default();
        let mut computed = 0;
        let mut ask = |hover: &mut CompareHover, scene: &Arc<_>, key| {
            let found = hover.readings(scene, key, || {
                computed += 1;
                vec![Reading {
                    name: "A".into(),
                    value: computed.to_string(),
                }]
            });
            found[0].value.clone()
        };
        assert_eq!(ask(&mut hover, &scene, key), "1");
        assert_eq!(ask(&mut hover, &scene, key), "1", "the same spot: kept");
        let mut moved = key;
        moved.camera.orbit(5.0, 0.0, 400.0);
        assert_eq!(ask(&mut hover, &scene, moved), "2");
        let other_spot = CompareHoverKey {
            px: glam::Vec2::new(11.0, 20.0),
            ..moved
        };
        assert_eq!(ask(&mut hover, &scene, other_spot), "3");
        let other_half = CompareHoverKey {
            side: 1,
            ..other_spot
        };
        assert_eq!(ask(&mut hover, &scene, other_half), "4");
        // A new scene (the alignment came) with everything else the same.
        let rebuilt = Arc::new((cloud(), cloud()));
        assert_eq!(ask(&mut hover, &rebuilt, other_half), "5");
        assert_eq!(ask(&mut hover, &rebuilt, other_half), "5");
    }
}
