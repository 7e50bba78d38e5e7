//! Two clouds on one set of axes, so equal loudness looks equal (issue 17's A/B compare).
//!
//! Each cloud's coordinates are normalized to its own axes: a song's level axis runs from its
//! floor to its loudest bin, so a copy 6 dB louder has exactly the same normalized points and
//! only different axis ends. [`on_union_axes`] puts both clouds on the union of both ranges
//! (per axis: the smaller minimum, the larger maximum, the same scale), moving every point by
//! `union.normalized_of(own.value_at(coordinate))`; the scalar and hp are moved the same way
//! between their own axes and the union's. The file's tick marks are moved with the points and
//! kept where they still fall on the axis.

use crate::data::axes::{Axes, Axis, AxisScale, Tick};
use crate::data::cloud::{Aabb, PointCloud};

/// Why two clouds cannot share axes.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum CompareError {
    #[error("{b}: a {mode_b} cloud cannot be compared with {a}, a {mode_a} cloud")]
    Mode {
        a: String,
        b: String,
        mode_a: String,
        mode_b: String,
    },
    #[error(
        "{b}: its {axis} axis is {scale_b} and that of {a} is {scale_a}; they cannot share one"
    )]
    Scale {
        a: String,
        b: String,
        axis: &'static str,
        scale_a: &'static str,
        scale_b: &'static str,
    },
    #[error("{file}: its {axis} axis cannot map values: {reason}")]
    Axis {
        file: String,
        axis: &'static str,
        reason: String,
    },
}

fn scale_name(scale: AxisScale) -> &'static str {
    match scale {
        AxisScale::Linear => "linear",
        AxisScale::Log => "logarithmic",
        AxisScale::Mel => "mel",
    }
}

/// The union of two axes of one scale: the smaller minimum and the larger maximum, A's label
/// and unit, and A's file ticks (or B's) moved onto it.
pub fn union_axis(a: &Axis, b: &Axis) -> Axis {
    let (lo_a, hi_a) = (a.min.min(a.max), a.min.max(a.max));
    let (lo_b, hi_b) = (b.min.min(b.max), b.min.max(b.max));
    let mut union = Axis {
        label: a.label.clone(),
        unit: a.unit.clone(),
        min: lo_a.min(lo_b),
        max: hi_a.max(hi_b),
        scale: a.scale,
        ticks: None,
    };
    // Keep the direction of A's axis (min above max is allowed by the format).
    if a.min > a.max {
        std::mem::swap(&mut union.min, &mut union.max);
    }
    let source = if a.ticks.is_some() { a } else { b };
    if let Some(ticks) = &source.ticks {
        let moved: Vec<Tick> = ticks
            .iter()
            .filter_map(|t| {
                let at = union.normalized_of(source.value_at(f64::from(t.at)));
                (at.is_finite() && (-1.0..=1.0).contains(&at)).then(|| Tick {
                    at: at as f32,
                    label: t.label.clone(),
                })
            })
            .collect();
        union.ticks = Some(moved);
    }
    union
}

/// Moves a normalized coordinate from `from` to `to`.
pub fn move_coordinate(from: &Axis, to: &Axis, coordinate: f32) -> f32 {
    if from == to {
        return coordinate;
    }
    to.normalized_of(from.value_at(f64::from(coordinate))) as f32
}

/// Moves a [0, 1] coordinate (scalar, hp) from `from` to `to`, clamped to [0, 1].
fn move_unit(from: &Axis, to: &Axis, unit: f32) -> f32 {
    if from == to {
        return unit;
    }
    (to.unit_of(from.value_at_unit(f64::from(unit))) as f32).clamp(0.0, 1.0)
}

fn name(cloud: &PointCloud) -> String {
    cloud.path.display().to_string()
}

/// The union of both clouds' axes, or why there is none.
pub fn union_axes(a: &PointCloud, b: &PointCloud) -> Result<Axes, CompareError> {
    if a.meta.mode != b.meta.mode {
        return Err(CompareError::Mode {
            a: name(a),
            b: name(b),
            mode_a: format!("{:?}", a.meta.mode).to_lowercase(),
            mode_b: format!("{:?}", b.meta.mode).to_lowercase(),
        });
    }
    let (axes_a, axes_b) = (&a.meta.axes, &b.meta.axes);
    for ((axis, one), (_, other)) in axes_a.named().into_iter().zip(axes_b.named()) {
        for (cloud, axis_of) in [(a, one), (b, other)] {
            if let Some(reason) = axis_of.problem() {
                return Err(CompareError::Axis {
                    file: name(cloud),
                    axis,
                    reason,
                });
            }
        }
        if one.scale != other.scale {
            return Err(CompareError::Scale {
                a: name(a),
                b: name(b),
                axis,
                scale_a: scale_name(one.scale),
                scale_b: scale_name(other.scale),
            });
        }
    }
    Ok(Axes {
        x: union_axis(&axes_a.x, &axes_b.x),
        y: union_axis(&axes_a.y, &axes_b.y),
        z: union_axis(&axes_a.z, &axes_b.z),
        scalar: union_axis(&axes_a.scalar, &axes_b.scalar),
        hp: union_axis(&axes_a.hp, &axes_b.hp),
    })
}

/// `cloud` moved onto `axes` (its points, bounds and axes; the rest of its metadata kept).
pub fn moved_onto(cloud: &PointCloud, axes: &Axes) -> PointCloud {
    let own = &cloud.meta.axes;
    let mut moved = cloud.clone();
    let mut min = glam::Vec3::splat(f32::INFINITY);
    let mut max = glam::Vec3::splat(f32::NEG_INFINITY);
    for p in &mut moved.points {
        p.position = [
            move_coordinate(&own.x, &axes.x, p.position[0]),
            move_coordinate(&own.y, &axes.y, p.position[1]),
            move_coordinate(&own.z, &axes.z, p.position[2]),
        ];
        p.scalar = move_unit(&own.scalar, &axes.scalar, p.scalar);
        p.hp = move_unit(&own.hp, &axes.hp, p.hp);
        let q = glam::Vec3::from(p.position);
        min = min.min(q);
        max = max.max(q);
    }
    if !moved.points.is_empty() {
        moved.bounds = Aabb { min, max };
    }
    moved.meta.axes = axes.clone();
    moved
}

/// B's cloud with its time axis moved onto A's time: the music at B's `t` plays at A's
/// `t - offset_s` (`offset_s` > 0: B starts later, as `Alignment::offset_s` says), so after
/// [`on_union_axes`] the same moment of the music sits at the same x in both. Only the axis ends
/// move (every point keeps its normalized coordinate); the file's time ticks, which name B's
/// own seconds, are dropped. A cloud whose x axis is not time in seconds is returned as it is.
pub fn aligned_in_time(b: &PointCloud, offset_s: f64) -> PointCloud {
    let mut aligned = b.clone();
    align_in_time(&mut aligned, offset_s);
    aligned
}

/// [`aligned_in_time`] in place: B's axis ends moved, its points neither copied nor touched.
pub fn align_in_time(b: &mut PointCloud, offset_s: f64) {
    let x = &mut b.meta.axes.x;
    if offset_s == 0.0 || x.unit != "s" || x.scale != AxisScale::Linear {
        return;
    }
    x.min -= offset_s;
    x.max -= offset_s;
    x.ticks = None;
}

/// B's cloud moved onto A's time by a time map (an alignment of several segments: a cut, an
/// added intro, another edit): each point at B's time `t` moves to A's time `first_time(t)`
/// (`Alignment::first_time`, its own segment's offset), and the time axis becomes the span of
/// the mapped times. Unlike [`align_in_time`] the points move, since one offset cannot say a
/// cut; the time ticks, which name B's own seconds, are dropped. A cloud whose x axis is not
/// time in seconds is left as it is.
pub fn align_by_map(b: &mut PointCloud, first_time: impl Fn(f64) -> f64) {
    let own = b.meta.axes.x.clone();
    if own.unit != "s" || own.scale != AxisScale::Linear || own.is_degenerate() {
        return;
    }
    let times: Vec<f64> = b
        .points
        .iter()
        .map(|p| first_time(own.value_at(f64::from(p.position[0]))))
        .collect();
    let (mut lo, mut hi) = (first_time(own.min), first_time(own.max));
    for &t in &times {
        lo = lo.min(t);
        hi = hi.max(t);
    }
    if hi <= lo {
        return;
    }
    let mut axis = own;
    axis.min = lo;
    axis.max = hi;
    axis.ticks = None;
    let (mut x_min, mut x_max) = (f32::INFINITY, f32::NEG_INFINITY);
    for (p, t) in b.points.iter_mut().zip(times) {
        let x = axis.normalized_of(t) as f32;
        p.position[0] = x;
        x_min = x_min.min(x);
        x_max = x_max.max(x);
    }
    if !b.points.is_empty() {
        b.bounds.min.x = x_min;
        b.bounds.max.x = x_max;
    }
    b.meta.axes.x = axis;
}

/// B's levels moved by `gain_db` (the matching gain that brings B to A's loudness): its y and
/// scalar axes, where they are levels in dB, shifted by the gain, so after [`on_union_axes`]
/// what differs is dynamics and spectral balance, not loudness (the difference view's
/// "matched" reading; docs/COMPARE.md). Only the axis ends move, in place (the points are
/// neither copied nor touched); the level ticks, which name B's own levels, are dropped.
pub fn match_in_level(b: &mut PointCloud, gain_db: f64) {
    if gain_db == 0.0 {
        return;
    }
    let axes = &mut b.meta.axes;
    for axis in [&mut axes.y, &mut axes.scalar] {
        if axis.unit == "dB" && axis.scale == AxisScale::Linear {
            axis.min += gain_db;
            axis.max += gain_db;
            axis.ticks = None;
        }
    }
}

/// The legend's words for B's alignment and matching: "B aligned +0.731 s, -3.8 dB to match
/// A", the parts that apply ("B aligned +0.731 s"), or None when neither was done.
pub fn aligned_words(offset_s: Option<f64>, gain_db: Option<f64>) -> Option<String> {
    let mut parts = Vec::new();
    if let Some(offset) = offset_s {
        parts.push(format!("aligned {offset:+.3} s"));
    }
    if let Some(gain) = gain_db {
        parts.push(format!("{gain:+.1} dB to match A"));
    }
    (!parts.is_empty()).then(|| format!("B {}", parts.join(", ")))
}

/// Both clouds on the union of their axes: `(A, B)`.
pub fn on_union_axes(
    a: &PointCloud,
    b: &PointCloud,
) -> Result<(PointCloud, PointCloud), CompareError> {
    let axes = union_axes(a, b)?;
    Ok((moved_onto(a, &axes), moved_onto(b, &axes)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn union_of_shifted_level_axes_moves_points_by_the_shift() {
        let a = Axis::linear("level", "dB", -65.0, -5.0);
        let b = Axis::linear("level", "dB", -59.0, 1.0);
        let u = union_axis(&a, &b);
        assert_eq!((u.min, u.max), (-65.0, 1.0));
        // The same normalized coordinate is 6 dB higher on B.
        let ya = move_coordinate(&a, &u, 0.0);
        let yb = move_coordinate(&b, &u, 0.0);
        let db = (u.value_at(f64::from(yb)) - u.value_at(f64::from(ya))) as f32;
        assert!((db - 6.0).abs() < 1e-4, "{db}");
    }

    /// A point cloud of "music" whose points are A's, each `delay_s` later in time: B is A
    /// delayed, with its own time axis starting at 0 as a file's does.
    fn delayed_copy(a: &PointCloud, delay_s: f64) -> PointCloud {
        let mut b = a.clone();
        let x = &a.meta.axes.x;
        b.meta.axes.x.max = x.max + delay_s;
        for p in &mut b.points {
            let t = x.value_at(f64::from(p.position[0])) + delay_s;
            p.position[0] = b.meta.axes.x.normalized_of(t) as f32;
        }
        b
    }

    /// The largest distance between a point of A and the same point of B, in A's seconds.
    fn largest_time_gap(a: &PointCloud, b: &PointCloud) -> f64 {
        let x = &a.meta.axes.x;
        a.points
            .iter()
            .zip(&b.points)
            .map(|(p, q)| {
                (x.value_at(f64::from(p.position[0])) - x.value_at(f64::from(q.position[0]))).abs()
            })
            .fold(0.0, f64::max)
    }

    /// B has 2 s of silence inserted at A's 10 s and starts 0.5 s later: one offset leaves
    /// half of it 2 s off; the time map (its two segments) puts every point on A's.
    #[test]
    fn a_copy_with_an_edit_aligned_by_its_time_map_lies_on_a() {
        let a = PointCloud::synthetic(
            crate::data::synthetic::synthetic_song(20_000, 7),
            crate::data::cloud::DataMode::Song,
        );
        let x = &a.meta.axes.x;
        let cut = x.value_at(0.0);
        let mut b = a.clone();
        b.meta.axes.x.max = x.max + 2.5;
        for p in &mut b.points {
            let t = x.value_at(f64::from(p.position[0]));
            let later = if t < cut { 0.5 } else { 2.5 };
            p.position[0] = b.meta.axes.x.normalized_of(t + later) as f32;
        }
        let (a_one, b_one) = on_union_axes(&a, &aligned_in_time(&b, 0.5)).unwrap();
        let one_offset = largest_time_gap(&a_one, &b_one);
        assert!((one_offset - 2.0).abs() < 1e-3, "{one_offset}");
        let mut mapped = b.clone();
        align_by_map(
            &mut mapped,
            |t| {
                if t < cut + 1.5 { t - 0.5 } else { t - 2.5 }
            },
        );
        assert_eq!(mapped.meta.axes.x.ticks, None);
        assert!(mapped.bounds.min.x >= -1.0 && mapped.bounds.max.x <= 1.0);
        let (a_map, b_map) = on_union_axes(&a, &mapped).unwrap();
        let gap = largest_time_gap(&a_map, &b_map);
        assert!(gap < 1e-3, "{gap}");
    }

    #[test]
    fn a_delayed_copy_aligned_by_its_offset_lies_on_a() {
        let a = PointCloud::synthetic(
            crate::data::synthetic::synthetic_song(20_000, 7),
            crate::data::cloud::DataMode::Song,
        );
        let b = delayed_copy(&a, 0.5);
        let (a_plain, b_plain) = on_union_axes(&a, &b).unwrap();
        let before = largest_time_gap(&a_plain, &b_plain);
        assert!(
            (before - 0.5).abs() < 1e-3,
            "unaligned, B is 0.5 s late: {before}"
        );
        let (a_moved, b_moved) = on_union_axes(&a, &aligned_in_time(&b, 0.5)).unwrap();
        let after = largest_time_gap(&a_moved, &b_moved);
        assert!(
            after < 1e-4,
            "aligned, the same music at the same time: {after} s apart"
        );
        // The difference of the two clouds is nothing: the same counts in every cell.
        let cells = |c: &PointCloud| {
            let mut counts = std::collections::BTreeMap::new();
            for p in &c.points {
                let cell = p.position.map(|v| ((v + 1.0) * 32.0).floor() as i32);
                *counts.entry(cell).or_insert(0usize) += 1;
            }
            counts
        };
        let (ca, cb) = (cells(&a_moved), cells(&b_moved));
        let moved: usize = ca
            .iter()
            .map(|(cell, n)| n.abs_diff(*cb.get(cell).unwrap_or(&0)))
            .sum();
        assert!(
            moved * 200 < a.points.len(),
            "{moved} of {} points in another cell",
            a.points.len()
        );
        assert_eq!(aligned_in_time(&b, 0.0).meta.axes, b.meta.axes);
    }

    #[test]
    fn only_a_time_axis_in_seconds_is_aligned() {
        let timeline = PointCloud::synthetic(Vec::new(), crate::data::cloud::DataMode::Timeline);
        assert_eq!(
            aligned_in_time(&timeline, 0.5).meta.axes,
            timeline.meta.axes
        );
    }

    #[test]
    fn a_louder_copy_matched_by_its_gain_lies_on_a() {
        let a = PointCloud::synthetic(
            crate::data::synthetic::synthetic_song(5_000, 3),
            crate::data::cloud::DataMode::Song,
        );
        // B: the same points, 4 dB louder (its level and loudness axes 4 dB higher).
        let mut b = a.clone();
        for axis in [&mut b.meta.axes.y, &mut b.meta.axes.scalar] {
            axis.min += 4.0;
            axis.max += 4.0;
        }
        let gap = |a: &PointCloud, b: &PointCloud| {
            a.points
                .iter()
                .zip(&b.points)
                .map(|(p, q)| {
                    (p.position[1] - q.position[1])
                        .abs()
                        .max((p.scalar - q.scalar).abs())
                })
                .fold(0.0f32, f32::max)
        };
        let (a_plain, b_plain) = on_union_axes(&a, &b).unwrap();
        assert!(gap(&a_plain, &b_plain) > 0.05, "B louder, higher up");
        let mut matched = b.clone();
        match_in_level(&mut matched, -4.0);
        let (a_moved, b_moved) = on_union_axes(&a, &matched).unwrap();
        assert!(
            gap(&a_moved, &b_moved) < 1e-5,
            "matched: {}",
            gap(&a_moved, &b_moved)
        );
    }

    #[test]
    fn the_legend_says_what_was_aligned_and_matched() {
        assert_eq!(
            aligned_words(Some(0.731), Some(-3.8)).as_deref(),
            Some("B aligned +0.731 s, -3.8 dB to match A")
        );
        assert_eq!(
            aligned_words(None, Some(2.0)).as_deref(),
            Some("B +2.0 dB to match A")
        );
        assert_eq!(aligned_words(None, None), None);
    }

    #[test]
    fn file_ticks_move_with_the_axis() {
        let mut a = Axis::linear("frequency", "Hz", 0.0, 10000.0);
        a.ticks = Some(vec![Tick {
            at: 0.0,
            label: "5 kHz".into(),
        }]);
        let b = Axis::linear("frequency", "Hz", 0.0, 20000.0);
        let u = union_axis(&a, &b);
        let ticks = u.ticks.unwrap();
        assert_eq!(ticks.len(), 1);
        assert!((ticks[0].at + 0.5).abs() < 1e-6);
    }
}
