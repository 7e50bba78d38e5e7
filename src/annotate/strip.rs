//! The loudness strip under the 3D view in Song mode, as plain data: momentary (400 ms) and
//! short-term (3 s) BS.1770 loudness on a LUFS axis, PSR on a dB axis, the true-peak overs
//! marked along the top, the song's maximum momentary and short-term loudness (a dot and a
//! label where each occurs, from the metrics), and the playhead, all over the song's time. It reads the metadata's
//! `loudness` object once per cloud ([`crate::data::cloud::loudness_curves`]); songs without
//! curves (older files) have no strip. The window paints [`LoudnessStrip::layout`] with egui
//! (and seeks on clicks, `ui::strip`); a video draws it on the CPU.

use super::{Anchor, Annotation, Rect, Rgba, Shape, Text};
use crate::data::cloud::{LoudnessCurves, Metrics, PointCloud, loudness_curves};

/// Height of the strip in points.
pub const STRIP_HEIGHT: f32 = 118.0;
const LEFT: f32 = 52.0;
const RIGHT: f32 = 46.0;
const OVERS_BAND: f32 = 7.0;
/// PSR axis, dB (0 at the bottom).
pub const PSR_RANGE_DB: (f32, f32) = (0.0, 24.0);

const MOMENTARY: Rgba = [110, 140, 190, 255];
const SHORT_TERM: Rgba = [120, 200, 255, 255];
const PSR: Rgba = [255, 170, 60, 255];
const OVER_0: Rgba = [235, 60, 60, 255];
const OVER_1: Rgba = [240, 200, 70, 255];
const AXIS_TEXT: Rgba = [170, 170, 170, 255];
/// Font size of the strip's text, points.
pub const SMALL: f32 = 10.0;

/// The x of time `t` on a strip whose time axis runs from `left` (0 s) to `right`
/// (`duration_s`), clamped to the strip.
pub fn x_of_time(t: f64, left: f32, right: f32, duration_s: f64) -> f32 {
    if duration_s <= 0.0 {
        return left;
    }
    let u = (t / duration_s).clamp(0.0, 1.0) as f32;
    left + u * (right - left)
}

/// The time under `x` (the inverse of [`x_of_time`]), clamped to `[0, duration_s]`.
pub fn time_of_x(x: f32, left: f32, right: f32, duration_s: f64) -> f64 {
    if right <= left {
        return 0.0;
    }
    let u = ((x - left) / (right - left)).clamp(0.0, 1.0);
    f64::from(u) * duration_s.max(0.0)
}

/// The LUFS axis: 0 LUFS at the top, the bottom 10 LU steps below the quietest short-term
/// value above -70 LUFS (the gate), with 3 LU to spare, never below -70.
pub fn lufs_range(curves: &LoudnessCurves) -> (f32, f32) {
    let quietest = curves
        .short_term_lufs
        .iter()
        .chain(&curves.momentary_lufs)
        .flatten()
        .copied()
        .filter(|v| v.is_finite() && *v > -70.0)
        .fold(f32::INFINITY, f32::min);
    let low = if quietest.is_finite() {
        (((quietest - 3.0) / 10.0).floor() * 10.0).max(-70.0)
    } else {
        -60.0
    };
    (low.min(-10.0), 0.0)
}

/// One EBU Mode maximum the strip marks: its loudness and where its window lies.
#[derive(Clone, Debug, PartialEq)]
pub struct LoudnessMaximum {
    /// `"max M"` or `"max S"`.
    pub label: &'static str,
    pub lufs: f32,
    /// The centre of the loudest window, seconds (the metrics give its end, when a meter
    /// shows it; the curves are drawn at window centres).
    pub centre_s: f64,
}

/// The maxima of `metrics` (`max_momentary_*`, `max_short_term_*`) that the file has.
pub fn loudness_maxima(metrics: &Metrics) -> Vec<LoudnessMaximum> {
    [
        (
            "max M",
            metrics.max_momentary_lufs,
            metrics.max_momentary_s,
            0.4,
        ),
        (
            "max S",
            metrics.max_short_term_lufs,
            metrics.max_short_term_s,
            3.0,
        ),
    ]
    .into_iter()
    .filter_map(|(label, lufs, end_s, window_s)| {
        let (lufs, end_s) = (lufs?, end_s?);
        (lufs.is_finite() && end_s.is_finite()).then(|| LoudnessMaximum {
            label,
            lufs: lufs as f32,
            centre_s: (end_s - window_s / 2.0).max(0.0),
        })
    })
    .collect()
}

/// What the strip keeps: the parsed curves of the current Song cloud.
#[derive(Default)]
pub struct LoudnessStrip {
    cloud_id: Option<u64>,
    curves: Option<LoudnessCurves>,
    maxima: Vec<LoudnessMaximum>,
    duration_s: f64,
}

impl LoudnessStrip {
    /// Reads the curves of cloud `id` when it is not the one read last.
    pub fn sync(&mut self, id: u64, cloud: &PointCloud) {
        if self.cloud_id == Some(id) {
            return;
        }
        self.cloud_id = Some(id);
        self.curves = loudness_curves(&cloud.meta.raw);
        self.maxima = cloud
            .meta
            .metrics
            .as_ref()
            .map(loudness_maxima)
            .unwrap_or_default();
        let recorded = cloud
            .meta
            .source
            .as_ref()
            .and_then(|s| s.duration_s)
            .filter(|d| d.is_finite() && *d > 0.0);
        self.duration_s = match (&self.curves, recorded) {
            (_, Some(d)) => d,
            (Some(c), None) => c.end_s(),
            (None, None) => 0.0,
        };
    }

    pub fn has_curves(&self) -> bool {
        self.curves.is_some()
    }

    /// The strip of `cloud` on its own (a video draws it under the view); `None` when the
    /// cloud carries no loudness curves.
    pub fn for_cloud(cloud: &PointCloud) -> Option<Self> {
        let mut strip = Self::default();
        strip.sync(u64::MAX, cloud);
        strip.has_curves().then_some(strip)
    }

    /// The song's length the strip's time axis spans, seconds.
    pub fn duration_s(&self) -> f64 {
        self.duration_s
    }

    /// The plot area of a strip drawn in `rect` (the time axis runs across it).
    pub fn plot_rect(rect: Rect) -> Rect {
        Rect::from_min_max(
            [rect.left() + LEFT, rect.top() + OVERS_BAND + 3.0],
            [rect.right() - RIGHT, rect.bottom() - 14.0],
        )
    }

    /// The curves, when the cloud has them.
    pub fn curves(&self) -> Option<&LoudnessCurves> {
        self.curves.as_ref()
    }

    /// The strip in `rect`: background, axes, legend, overs, curves and (when given) the
    /// playhead; empty without curves.
    pub fn layout(&self, rect: Rect, playhead_s: Option<f64>) -> Annotation {
        let mut out = Annotation::default();
        let Some(curves) = self.curves.as_ref() else {
            return out;
        };
        out.fill(rect, 0.0, [18, 18, 18, 255]);
        let plot = Self::plot_rect(rect);
        let duration = self.duration_s;
        let x = |t: f64| x_of_time(t, plot.left(), plot.right(), duration);
        let (low, high) = lufs_range(curves);
        let y_lufs =
            |v: f32| plot.bottom() - (v.clamp(low, high) - low) / (high - low) * plot.height();
        let (psr_low, psr_high) = PSR_RANGE_DB;
        let y_psr = |v: f32| {
            plot.bottom()
                - (v.clamp(psr_low, psr_high) - psr_low) / (psr_high - psr_low) * plot.height()
        };
        let grid: Rgba = [45, 45, 45, 255];
        let mut level = high;
        while level >= low {
            let y = y_lufs(level);
            out.line([plot.left(), y], [plot.right(), y], 1.0, grid);
            out.text(Text::new(
                format!("{level:.0}"),
                [plot.left() - 4.0, y],
                Anchor::RIGHT_CENTER,
                SMALL,
                AXIS_TEXT,
            ));
            level -= 10.0;
        }
        for psr in [0.0f32, 6.0, 12.0, 18.0, 24.0] {
            out.text(Text::new(
                format!("{psr:.0}"),
                [plot.right() + 4.0, y_psr(psr)],
                Anchor::LEFT_CENTER,
                SMALL,
                PSR,
            ));
        }
        out.text(Text::new(
            "LUFS",
            [rect.left() + 3.0, rect.bottom() - 2.0],
            Anchor::LEFT_BOTTOM,
            SMALL,
            AXIS_TEXT,
        ));
        out.text(Text::new(
            "PSR dB",
            [rect.right() - 3.0, rect.bottom() - 2.0],
            Anchor::RIGHT_BOTTOM,
            SMALL,
            PSR,
        ));
        let legend = [
            ("momentary 400 ms", MOMENTARY),
            ("short-term 3 s", SHORT_TERM),
            ("PSR", PSR),
            ("true peak > 0 dBTP", OVER_0),
            ("> -1 dBTP", OVER_1),
        ];
        let mut at = plot.left() + 4.0;
        for (text, colour) in legend {
            let placed = out.text(Text::new(
                text,
                [at, rect.bottom() - 13.0],
                Anchor::LEFT_TOP,
                SMALL,
                colour,
            ));
            at += placed.width() + 14.0;
        }
        // Overs along the top: -1 dBTP first, 0 dBTP over it; at least one pixel wide.
        for (overs, colour) in [(&curves.overs_1dbtp, OVER_1), (&curves.overs_0dbtp, OVER_0)] {
            for &(a, b) in overs {
                let (xa, xb) = (x(a), x(b).max(x(a) + 1.0));
                out.fill(
                    Rect::from_min_max([xa, rect.top() + 1.0], [xb, rect.top() + OVERS_BAND]),
                    0.0,
                    colour,
                );
                if colour == OVER_0 {
                    let faint = [OVER_0[0], OVER_0[1], OVER_0[2], 89];
                    out.line([xa, plot.top()], [xa, plot.bottom()], 1.0, faint);
                }
            }
        }
        let width_px = plot.width().max(1.0);
        let mut line = |values: &[Option<f32>],
                        start_s: f64,
                        y: &dyn Fn(f32) -> f32,
                        (width, colour): (f32, Rgba)| {
            // At most about two values a pixel; a gap (silence) breaks the line.
            let stride = ((values.len() as f32 / (2.0 * width_px)).ceil() as usize).max(1);
            let mut run: Vec<[f32; 2]> = Vec::new();
            let mut flush = |run: &mut Vec<[f32; 2]>| {
                if run.len() >= 2 {
                    out.push(Shape::Line {
                        points: std::mem::take(run),
                        width,
                        colour,
                    });
                }
                run.clear();
            };
            for (i, v) in values.iter().enumerate().step_by(stride) {
                match v {
                    Some(v) if v.is_finite() => {
                        run.push([x(curves.time_of(start_s, i)), y(*v)]);
                    }
                    _ => flush(&mut run),
                }
            }
            flush(&mut run);
        };
        line(
            &curves.momentary_lufs,
            curves.momentary_start_s,
            &y_lufs,
            (1.0, MOMENTARY),
        );
        line(
            &curves.psr_db,
            curves.short_term_start_s,
            &y_psr,
            (1.5, PSR),
        );
        line(
            &curves.short_term_lufs,
            curves.short_term_start_s,
            &y_lufs,
            (2.0, SHORT_TERM),
        );
        // The maxima: a dot ringed in the background colour where the loudest window is
        // centred, on its level; the label beside it (to its left in the strip's right
        // quarter), momentary above the dot and short-term below, so the two never overlap.
        for maximum in &self.maxima {
            let momentary = maximum.label == "max M";
            let colour = if momentary { MOMENTARY } else { SHORT_TERM };
            let at = [x(maximum.centre_s), y_lufs(maximum.lufs)];
            let dot = |r: f32| Rect::from_min_max([at[0] - r, at[1] - r], [at[0] + r, at[1] + r]);
            out.fill(dot(4.5), 4.5, [18, 18, 18, 255]);
            out.fill(dot(3.0), 3.0, colour);
            let right = at[0] > plot.left() + 0.75 * plot.width();
            let anchor = match (right, momentary) {
                (false, true) => Anchor::LEFT_BOTTOM,
                (false, false) => Anchor::LEFT_TOP,
                (true, true) => Anchor::RIGHT_BOTTOM,
                (true, false) => Anchor::RIGHT_TOP,
            };
            let dx = if right { -5.0 } else { 5.0 };
            let dy = if momentary { -2.0 } else { 2.0 };
            out.text(Text::new(
                format!("{} {:.1}", maximum.label, maximum.lufs),
                [at[0] + dx, at[1] + dy],
                anchor,
                SMALL,
                colour,
            ));
        }
        if let Some(playhead_s) = playhead_s {
            let head = x(playhead_s);
            out.line([head, rect.top()], [head, plot.bottom()], 1.5, [255; 4]);
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn time_and_x_map_both_ways_and_clamp_to_the_strip() {
        let (left, right, duration) = (100.0, 900.0, 200.0);
        assert_eq!(x_of_time(0.0, left, right, duration), 100.0);
        assert_eq!(x_of_time(200.0, left, right, duration), 900.0);
        assert_eq!(x_of_time(50.0, left, right, duration), 300.0);
        assert_eq!(x_of_time(-5.0, left, right, duration), 100.0);
        assert_eq!(x_of_time(500.0, left, right, duration), 900.0);
        for t in [0.0, 12.5, 99.9, 200.0] {
            let back = time_of_x(x_of_time(t, left, right, duration), left, right, duration);
            assert!((back - t).abs() < 1e-3, "{t} -> {back}");
        }
        assert_eq!(time_of_x(50.0, left, right, duration), 0.0);
        assert_eq!(time_of_x(1000.0, left, right, duration), 200.0);
        assert_eq!(time_of_x(500.0, left, left, duration), 0.0);
        assert_eq!(x_of_time(10.0, left, right, 0.0), left);
    }

    #[test]
    fn the_maxima_are_marked_at_their_window_centres() {
        let metrics = Metrics {
            max_momentary_lufs: Some(-9.04),
            max_momentary_s: Some(50.4),
            max_short_term_lufs: Some(-12.0),
            max_short_term_s: None, // not in the file: not marked
            ..Metrics::default()
        };
        let maxima = loudness_maxima(&metrics);
        assert_eq!(maxima.len(), 1);
        assert_eq!(maxima[0].label, "max M");
        assert!((maxima[0].centre_s - 50.2).abs() < 1e-9);
        assert!(loudness_maxima(&Metrics::default()).is_empty());

        let strip = LoudnessStrip {
            cloud_id: Some(1),
            curves: Some(LoudnessCurves {
                rate_hz: 10.0,
                momentary_lufs: vec![Some(-20.0); 1000],
                short_term_lufs: vec![Some(-20.0); 1000],
                ..LoudnessCurves::default()
            }),
            maxima,
            duration_s: 100.0,
        };
        let rect = Rect::from_min_max([0.0, 0.0], [1098.0, STRIP_HEIGHT]);
        let out = strip.layout(rect, None);
        let label = out
            .texts()
            .find(|t| t.text == "max M -9.0")
            .expect("the maximum's label");
        let plot = LoudnessStrip::plot_rect(rect);
        let x = x_of_time(50.2, plot.left(), plot.right(), 100.0);
        // Left-anchored 5 points right of the dot (text boxes sit on whole points).
        assert!(
            (label.rect.left() - (x + 5.0)).abs() <= 1.0,
            "label at {:?}",
            label.rect
        );
        let dot = out.shapes.iter().any(|s| {
            matches!(s, Shape::Fill { rect, colour, .. }
                if *colour == MOMENTARY && (rect.center()[0] - x).abs() < 1e-3)
        });
        assert!(dot, "a dot at the maximum's time");
    }

    #[test]
    fn the_lufs_axis_reaches_below_the_quietest_window() {
        let curves = LoudnessCurves {
            rate_hz: 10.0,
            short_term_lufs: vec![Some(-9.0), None, Some(-23.5)],
            momentary_lufs: vec![Some(-80.0)], // below the gate: ignored
            ..LoudnessCurves::default()
        };
        assert_eq!(lufs_range(&curves), (-30.0, 0.0));
        assert_eq!(lufs_range(&LoudnessCurves::default()), (-60.0, 0.0));
    }
}
