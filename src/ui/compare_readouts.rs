//! The A/B compare's hover read-outs: in side by side the point under the cursor and the other
//! song's nearest one, in the difference view the voxel under the cursor and both differences
//! there. Called by `compare_window.rs`.

use crate::data::cloud::PointCloud;
use crate::ui::state::compare_window::DifferenceCopy;
use crate::view::frame_view::FrameView;
use crate::view::pick::{self, Reading};

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
