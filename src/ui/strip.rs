//! The loudness strip under the 3D view in Song mode: momentary (400 ms) and short-term (3 s)
//! BS.1770 loudness on a LUFS axis, PSR on a dB axis, the true-peak overs marked along the top,
//! and the playhead, all over the song's time. Clicking or dragging on it seeks. It reads the
//! metadata's `loudness` object once per cloud ([`crate::data::cloud::loudness_curves`]) and
//! draws with egui's painter; songs without curves (older files) show no strip.

use eframe::egui::{self, Align2, Color32, FontId, Pos2, Rect, Sense, Shape, Stroke, Vec2};

use crate::data::cloud::{LoudnessCurves, PointCloud, loudness_curves};
use crate::playback::format_clock;

/// Height of the strip in points.
pub const STRIP_HEIGHT: f32 = 118.0;
const LEFT: f32 = 52.0;
const RIGHT: f32 = 46.0;
const OVERS_BAND: f32 = 7.0;
/// PSR axis, dB (0 at the bottom).
pub const PSR_RANGE_DB: (f32, f32) = (0.0, 24.0);

const MOMENTARY: Color32 = Color32::from_rgb(110, 140, 190);
const SHORT_TERM: Color32 = Color32::from_rgb(120, 200, 255);
const PSR: Color32 = Color32::from_rgb(255, 170, 60);
const OVER_0: Color32 = Color32::from_rgb(235, 60, 60);
const OVER_1: Color32 = Color32::from_rgb(240, 200, 70);

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

/// What the strip keeps: the parsed curves of the current Song cloud.
#[derive(Default)]
pub struct LoudnessStrip {
    cloud_id: Option<u64>,
    curves: Option<LoudnessCurves>,
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
            Pos2::new(rect.left() + LEFT, rect.top() + OVERS_BAND + 3.0),
            Pos2::new(rect.right() - RIGHT, rect.bottom() - 14.0),
        )
    }

    /// Draws the strip at the full width of `ui`, the playhead at `playhead_s`; returns the
    /// time to seek to when the strip was clicked or dragged.
    pub fn show(&self, ui: &mut egui::Ui, playhead_s: f64) -> Option<f64> {
        let curves = self.curves.as_ref()?;
        let (rect, response) = ui.allocate_exact_size(
            Vec2::new(ui.available_width(), STRIP_HEIGHT),
            Sense::click_and_drag(),
        );
        let painter = ui.painter_at(rect);
        self.paint(&painter, rect, Some(playhead_s));
        let plot = Self::plot_rect(rect);
        let duration = self.duration_s;
        let small = FontId::proportional(10.0);
        if let Some(pos) = response.hover_pos() {
            let t = time_of_x(pos.x, plot.left(), plot.right(), duration);
            let index = ((t - curves.short_term_start_s) * curves.rate_hz).round();
            let at = |values: &[Option<f32>]| {
                (index >= 0.0)
                    .then(|| values.get(index as usize).copied().flatten())
                    .flatten()
            };
            let mut text = format_clock(t);
            if let Some(v) = at(&curves.short_term_lufs) {
                text.push_str(&format!("  short-term {v:.1} LUFS"));
            }
            if let Some(v) = at(&curves.psr_db) {
                text.push_str(&format!("  PSR {v:.1} dB"));
            }
            painter.text(
                Pos2::new(plot.right() - 4.0, plot.top() + 2.0),
                Align2::RIGHT_TOP,
                text,
                small,
                Color32::from_gray(220),
            );
        }
        let seek = (response.clicked() || response.dragged())
            .then(|| response.interact_pointer_pos())
            .flatten()
            .map(|p| time_of_x(p.x, plot.left(), plot.right(), duration));
        if seek.is_some() {
            ui.ctx().request_repaint();
        }
        seek
    }

    /// Paints the strip into `rect` with `painter`: background, axes, legend, overs, curves and
    /// (when given) the playhead.
    pub fn paint(&self, painter: &egui::Painter, rect: Rect, playhead_s: Option<f64>) {
        let Some(curves) = self.curves.as_ref() else {
            return;
        };
        painter.rect_filled(rect, 0.0, Color32::from_gray(18));
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
        let small = FontId::proportional(10.0);
        let grid = Stroke::new(1.0, Color32::from_gray(45));
        let mut level = high;
        while level >= low {
            let y = y_lufs(level);
            painter.line_segment(
                [Pos2::new(plot.left(), y), Pos2::new(plot.right(), y)],
                grid,
            );
            painter.text(
                Pos2::new(plot.left() - 4.0, y),
                Align2::RIGHT_CENTER,
                format!("{level:.0}"),
                small.clone(),
                Color32::from_gray(170),
            );
            level -= 10.0;
        }
        for psr in [0.0f32, 6.0, 12.0, 18.0, 24.0] {
            painter.text(
                Pos2::new(plot.right() + 4.0, y_psr(psr)),
                Align2::LEFT_CENTER,
                format!("{psr:.0}"),
                small.clone(),
                PSR,
            );
        }
        painter.text(
            Pos2::new(rect.left() + 3.0, rect.bottom() - 2.0),
            Align2::LEFT_BOTTOM,
            "LUFS",
            small.clone(),
            Color32::from_gray(170),
        );
        painter.text(
            Pos2::new(rect.right() - 3.0, rect.bottom() - 2.0),
            Align2::RIGHT_BOTTOM,
            "PSR dB",
            small.clone(),
            PSR,
        );
        let legend = [
            ("momentary 400 ms", MOMENTARY),
            ("short-term 3 s", SHORT_TERM),
            ("PSR", PSR),
            ("true peak > 0 dBTP", OVER_0),
            ("> -1 dBTP", OVER_1),
        ];
        let mut at = plot.left() + 4.0;
        for (text, colour) in legend {
            let galley = painter.layout_no_wrap(text.to_string(), small.clone(), colour);
            let width = galley.size().x;
            painter.galley(Pos2::new(at, rect.bottom() - 13.0), galley, colour);
            at += width + 14.0;
        }
        // Overs along the top: -1 dBTP first, 0 dBTP over it; at least one pixel wide.
        for (overs, colour) in [(&curves.overs_1dbtp, OVER_1), (&curves.overs_0dbtp, OVER_0)] {
            for &(a, b) in overs {
                let (xa, xb) = (x(a), x(b).max(x(a) + 1.0));
                painter.rect_filled(
                    Rect::from_min_max(
                        Pos2::new(xa, rect.top() + 1.0),
                        Pos2::new(xb, rect.top() + OVERS_BAND),
                    ),
                    0.0,
                    colour,
                );
                if colour == OVER_0 {
                    painter.line_segment(
                        [Pos2::new(xa, plot.top()), Pos2::new(xa, plot.bottom())],
                        Stroke::new(1.0, OVER_0.gamma_multiply(0.35)),
                    );
                }
            }
        }
        let width_px = plot.width().max(1.0);
        let line =
            |values: &[Option<f32>], start_s: f64, y: &dyn Fn(f32) -> f32, stroke: Stroke| {
                // At most about two values a pixel; a gap (silence) breaks the line.
                let stride = ((values.len() as f32 / (2.0 * width_px)).ceil() as usize).max(1);
                let mut run: Vec<Pos2> = Vec::new();
                let flush = |run: &mut Vec<Pos2>| {
                    if run.len() >= 2 {
                        painter.add(Shape::line(std::mem::take(run), stroke));
                    }
                    run.clear();
                };
                for (i, v) in values.iter().enumerate().step_by(stride) {
                    match v {
                        Some(v) if v.is_finite() => {
                            run.push(Pos2::new(x(curves.time_of(start_s, i)), y(*v)));
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
            Stroke::new(1.0, MOMENTARY),
        );
        line(
            &curves.psr_db,
            curves.short_term_start_s,
            &y_psr,
            Stroke::new(1.5, PSR),
        );
        line(
            &curves.short_term_lufs,
            curves.short_term_start_s,
            &y_lufs,
            Stroke::new(2.0, SHORT_TERM),
        );
        if let Some(playhead_s) = playhead_s {
            let head = x(playhead_s);
            painter.line_segment(
                [Pos2::new(head, rect.top()), Pos2::new(head, plot.bottom())],
                Stroke::new(1.5, Color32::WHITE),
            );
        }
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
