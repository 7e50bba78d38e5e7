//! Text over the 3D view: axis tick labels and axis titles in physical units.
//!
//! The window paints these with its egui painter each frame; the headless renderer runs egui
//! once offscreen and draws the same shapes into the render target, so PNGs carry the same labels.

use eframe::egui::{self, Align2, Color32, FontId, Rect};
use glam::Vec3;

use crate::data::axes::Axis;
use crate::data::cloud::PointCloud;
use crate::render::colormap::Background;
use crate::render::scene::SceneData;
use crate::view::frame_view::FrameView;

/// The translucent plate under each label on the dark background: its colour, mostly opaque.
pub const LABEL_PLATE: Color32 = Color32::from_rgba_premultiplied(10, 11, 15, 190);

/// The plate under a label on `background`: the paper's colour, mostly opaque, so the ink of
/// [`Background::ink`] stays readable over the cloud on either background.
pub fn label_plate(background: Background) -> Color32 {
    if background.is_light() {
        Color32::from_rgba_unmultiplied(255, 255, 255, 190)
    } else {
        LABEL_PLATE
    }
}

/// A tick label or an axis title, placed along one axis of the box.
#[derive(Clone, Debug)]
pub struct Label {
    /// 0, 1, 2 for x, y, z.
    pub axis: usize,
    /// Normalized position along the axis, -1 to 1.
    pub at: f32,
    pub text: String,
    pub title: bool,
}

/// The labels of a box: which edge carries them is chosen per frame, facing the camera.
#[derive(Clone, Debug, Default)]
pub struct AxisLabels {
    pub box_min: Vec3,
    pub box_max: Vec3,
    pub labels: Vec<Label>,
}

/// "time (s)", or just "hp" for a unitless axis.
pub fn axis_title(axis: &Axis, fallback: &str) -> String {
    let name = if axis.label.is_empty() {
        fallback
    } else {
        &axis.label
    };
    if axis.unit.is_empty() || axis.unit.eq_ignore_ascii_case(name) {
        name.to_string()
    } else if axis.unit == "s" && axis.ticks(8).iter().any(|t| t.label.contains(':')) {
        // The ticks read as a clock: "(s)" over "2:30" would say seconds where minutes are.
        format!("{name} (m:ss)")
    } else {
        format!("{name} ({})", axis.unit)
    }
}

/// Tick labels and axis titles for the box drawn by the scene.
/// (The axes as the view shows them: `data.axes`, z on the frequency axis shown.)
/// The level axis's title names its reference (dBFS RMS, or dB re FS sine) by the cloud's mode.
pub fn axis_labels(cloud: &PointCloud, data: &SceneData) -> AxisLabels {
    with_references(
        axis_labels_for_axes(&data.axes, data.box_min, data.box_max),
        cloud,
        &data.axes,
    )
}

/// Tick labels and axis titles for a box `[min, max]` in data space.
pub fn axis_labels_for_box(cloud: &PointCloud, min: Vec3, max: Vec3) -> AxisLabels {
    with_references(
        axis_labels_for_axes(&cloud.meta.axes, min, max),
        cloud,
        &cloud.meta.axes,
    )
}

/// The titles of `labels` with the level axis's reference for `cloud`'s mode
/// (`ui::legends::titled_with_reference`).
fn with_references(
    mut labels: AxisLabels,
    cloud: &PointCloud,
    axes: &crate::data::axes::Axes,
) -> AxisLabels {
    let units = [&axes.x.unit, &axes.y.unit, &axes.z.unit];
    for label in labels.labels.iter_mut().filter(|l| l.title) {
        let text = std::mem::take(&mut label.text);
        label.text = crate::ui::legends::titled_with_reference(
            cloud.meta.mode,
            label.axis,
            units[label.axis.min(2)],
            text,
        );
    }
    labels
}

/// Tick labels and axis titles of `axes` for a box `[min, max]` in data space.
pub fn axis_labels_for_axes(axes: &crate::data::axes::Axes, min: Vec3, max: Vec3) -> AxisLabels {
    let mut labels = Vec::new();
    for (index, (axis, fallback)) in [(&axes.x, "x"), (&axes.y, "y"), (&axes.z, "z")]
        .into_iter()
        .enumerate()
    {
        for tick in axis.ticks(8) {
            labels.push(Label {
                axis: index,
                at: tick.at,
                text: tick.label,
                title: false,
            });
        }
        labels.push(Label {
            axis: index,
            at: 0.0,
            text: axis_title(axis, fallback),
            title: true,
        });
    }
    AxisLabels {
        box_min: min,
        box_max: max,
        labels,
    }
}

/// The box edge an axis is labelled on, as the two fixed coordinates of the other axes:
/// x and z along the lowest edge on screen, y along the leftmost vertical edge.
fn label_edge(labels: &AxisLabels, view: &FrameView, axis: usize) -> Option<Vec3> {
    let (min, max) = (labels.box_min, labels.box_max);
    let mid = (min + max) * 0.5;
    let mut best: Option<(f32, Vec3)> = None;
    for corner in 0..4u32 {
        let mut point = mid;
        let (a, b) = match axis {
            0 => (1, 2),
            1 => (0, 2),
            _ => (0, 1),
        };
        point[a] = if corner & 1 == 0 { min[a] } else { max[a] };
        point[b] = if corner & 2 == 0 { min[b] } else { max[b] };
        let Some(pixel) = view.project(point) else {
            continue;
        };
        // Lowest on screen for x and z, leftmost for y.
        let score = if axis == 1 { -pixel.x } else { pixel.y };
        if best.is_none_or(|(s, _)| score > s) {
            best = Some((score, point));
        }
    }
    best.map(|(_, p)| p)
}

/// Paints labels projected through `view` into `rect` (the 3D view's place on screen, points).
pub fn paint(painter: &egui::Painter, rect: Rect, view: &FrameView, labels: &AxisLabels) {
    paint_on(painter, rect, view, labels, Background::Dark);
}

/// As [`paint`], in the ink of `background` (dark ink on the light background).
pub fn paint_on(
    painter: &egui::Painter,
    rect: Rect,
    view: &FrameView,
    labels: &AxisLabels,
    background: Background,
) {
    let scale = rect.width() / view.width.max(1) as f32;
    let edges: Vec<Option<Vec3>> = (0..3).map(|axis| label_edge(labels, view, axis)).collect();
    let mut placed: Vec<Rect> = Vec::new();
    // Titles first, so ticks make way for them.
    let ordered = labels
        .labels
        .iter()
        .filter(|l| l.title)
        .chain(labels.labels.iter().filter(|l| !l.title));
    for label in ordered {
        let Some(mut anchor) = edges[label.axis] else {
            continue;
        };
        let (lo, hi) = (labels.box_min[label.axis], labels.box_max[label.axis]);
        anchor[label.axis] = lo + (label.at + 1.0) * 0.5 * (hi - lo);
        let Some(pixel) = view.project(anchor) else {
            continue;
        };
        let (offset, align) = if label.axis == 1 {
            (egui::vec2(-10.0, 0.0), Align2::RIGHT_CENTER)
        } else {
            (egui::vec2(0.0, 8.0), Align2::CENTER_TOP)
        };
        let offset = if label.title { offset * 3.0 } else { offset };
        let pos = rect.min + egui::vec2(pixel.x, pixel.y) * scale + offset;
        if !rect.expand(40.0).contains(pos) {
            continue;
        }
        let [r, g, b] = background.ink(label.title);
        let (size, color) = (
            if label.title { 14.0 } else { 12.0 },
            Color32::from_rgb(r, g, b),
        );
        // Skip a label that would overlap one already placed (crowded ticks at some angles).
        let galley = painter.layout_no_wrap(label.text.clone(), FontId::proportional(size), color);
        let mut text_rect = align.anchor_size(pos, galley.size());
        if label.title {
            // A long title beside the picture's edge moves in rather than being cut off.
            let dx = (rect.left() + 2.0 - text_rect.left()).max(0.0)
                + (rect.right() - 2.0 - text_rect.right()).min(0.0);
            text_rect = text_rect.translate(egui::vec2(dx, 0.0));
        }
        if placed
            .iter()
            .any(|r: &Rect| r.expand(2.0).intersects(text_rect))
        {
            continue;
        }
        placed.push(text_rect);
        // A plate of the background's colour under the text keeps it readable over bright
        // points, surfaces and the volume (tick labels sat on the cloud at some angles and
        // vanished in it).
        painter.rect_filled(
            text_rect.expand2(egui::vec2(3.0, 1.0)),
            3.0,
            label_plate(background),
        );
        painter.galley(text_rect.min, galley, color);
    }
}

/// Lines describing a cloud for the side panel: where it came from and its loudness metrics.
pub fn describe_cloud(cloud: &PointCloud) -> Vec<String> {
    let meta = &cloud.meta;
    let mut lines = Vec::new();
    match meta.mode {
        crate::data::cloud::DataMode::Song => lines.push("Song".to_string()),
        crate::data::cloud::DataMode::Timeline => {
            lines.push(format!("Timeline of {} songs", meta.songs.len()))
        }
        crate::data::cloud::DataMode::Generic => {
            lines.push("Generic point cloud (no loudscape metadata)".into())
        }
    }
    if let Some(source) = &meta.source {
        if let Some(path) = &source.path {
            lines.push(format!("source: {path}"));
        }
        let mut parts = Vec::new();
        if let Some(d) = source.duration_s {
            parts.push(format!("{d:.1} s"));
        }
        if let Some(rate) = source.sample_rate {
            parts.push(format!("{rate} Hz"));
        }
        if let Some(ch) = source.channels {
            parts.push(format!("{ch} ch"));
        }
        if !parts.is_empty() {
            lines.push(parts.join(", "));
        }
    }
    if let Some(m) = &meta.metrics {
        lines.extend(describe_metrics(m));
    }
    lines
}

/// Loudness and dynamics metrics as "name: value unit" lines, leaving out the ones not
/// measured (files from older extractors have no DR or PSR).
pub fn describe_metrics(m: &crate::data::cloud::Metrics) -> Vec<String> {
    let rows = [
        ("integrated loudness", m.integrated_lufs, "LUFS"),
        ("loudness range (LRA)", m.lra_lu, "LU"),
        ("sample peak", m.sample_peak_dbfs, "dBFS"),
        ("true peak", m.true_peak_dbtp, "dBTP"),
        ("PLR", m.plr_db, "dB"),
        ("DR (TT meter)", m.dr_db, "dB"),
        ("PSR, median of 3 s", m.psr_median_db, "dB"),
        ("crest factor of 3 s, median", m.crest_3s_median_db, "dB"),
        ("crest factor of a frame, median", m.crest_median_db, "dB"),
        ("crest factor of a frame, 95th pct", m.crest_p95_db, "dB"),
    ];
    let mut lines: Vec<String> = rows
        .iter()
        .filter_map(|(name, value, unit)| value.map(|v| format!("{name}: {v:.1} {unit}")))
        .collect();
    if let (Some(low), Some(high)) = (m.psr_p10_db, m.psr_p90_db) {
        lines.push(format!("PSR, 10th-90th pct: {low:.1} to {high:.1} dB"));
    }
    if let Some(dc) = m.dc_offset.filter(|dc| *dc > 0.01) {
        lines.push(format!("DC offset removed: {dc:.3} of full scale"));
    }
    for service in &STREAMING_SERVICES {
        if let Some(gain) = normalization_gain(service, m.integrated_lufs, m.true_peak_dbtp) {
            lines.push(format!("{}: {}", service.name, describe_gain(gain)));
        }
    }
    lines
}

/// How a streaming service turns a song up when it is quieter than the target.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TurnUp {
    /// Only as far as the true peak stays at or below this ceiling (dBTP).
    PeakCeiling(f64),
    /// To the target whatever the peak (the service limits the peaks).
    Free,
    /// Never: the service only turns down.
    Never,
}

/// A playback normalization rule: `gain = target - integrated loudness`, positive gain
/// limited by [`TurnUp`]. Keep in sync with `preprocess/loudscape_extract/normalization.py`
/// (sources in docs/DYNAMICS.md, "Streaming normalization").
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StreamingService {
    pub name: &'static str,
    pub target_lufs: f64,
    pub turn_up: TurnUp,
}

pub const STREAMING_SERVICES: [StreamingService; 5] = [
    StreamingService {
        name: "Spotify (normal)",
        target_lufs: -14.0,
        turn_up: TurnUp::PeakCeiling(-1.0),
    },
    StreamingService {
        name: "Spotify (loud)",
        target_lufs: -11.0,
        turn_up: TurnUp::Free,
    },
    StreamingService {
        name: "Spotify (quiet)",
        target_lufs: -19.0,
        turn_up: TurnUp::PeakCeiling(-1.0),
    },
    StreamingService {
        name: "YouTube",
        target_lufs: -14.0,
        turn_up: TurnUp::Never,
    },
    StreamingService {
        name: "AES TD1008 (track)",
        target_lufs: -16.0,
        turn_up: TurnUp::PeakCeiling(-1.0),
    },
];

/// The playback gain in dB (negative: turned down) `service` applies to a song; None without
/// an integrated loudness, or when turning up needs a true peak the file does not give.
pub fn normalization_gain(
    service: &StreamingService,
    integrated_lufs: Option<f64>,
    true_peak_dbtp: Option<f64>,
) -> Option<f64> {
    let integrated = integrated_lufs.filter(|v| v.is_finite())?;
    let gain = service.target_lufs - integrated;
    if gain <= 0.0 {
        return Some(gain);
    }
    match service.turn_up {
        TurnUp::Free => Some(gain),
        TurnUp::Never => Some(0.0),
        TurnUp::PeakCeiling(ceiling) => {
            let peak = true_peak_dbtp.filter(|v| v.is_finite())?;
            Some(gain.min(ceiling - peak).max(0.0))
        }
    }
}

fn describe_gain(gain: f64) -> String {
    if gain <= -0.05 {
        format!("turned down {:.1} dB", -gain)
    } else if gain >= 0.05 {
        format!("turned up {gain:.1} dB")
    } else {
        "plays as mastered".to_string()
    }
}

#[cfg(test)]
mod metrics_tests {
    use super::describe_metrics;
    use crate::data::cloud::Metrics;

    #[test]
    fn the_dynamics_metrics_are_listed_with_units_and_missing_ones_left_out() {
        let m = Metrics {
            integrated_lufs: Some(-8.04),
            dr_db: Some(5.46),
            psr_median_db: Some(10.0),
            psr_p10_db: Some(8.5),
            psr_p90_db: Some(11.3),
            dc_offset: Some(0.315),
            ..Metrics::default()
        };
        let lines = describe_metrics(&m);
        assert_eq!(
            lines,
            [
                "integrated loudness: -8.0 LUFS",
                "DR (TT meter): 5.5 dB",
                "PSR, median of 3 s: 10.0 dB",
                "PSR, 10th-90th pct: 8.5 to 11.3 dB",
                "DC offset removed: 0.315 of full scale",
                "Spotify (normal): turned down 6.0 dB",
                "Spotify (loud): turned down 3.0 dB",
                "Spotify (quiet): turned down 11.0 dB",
                "YouTube: turned down 6.0 dB",
                "AES TD1008 (track): turned down 8.0 dB",
            ]
        );
        assert!(describe_metrics(&Metrics::default()).is_empty());
    }

    #[test]
    fn quiet_songs_are_turned_up_only_as_far_as_each_services_peak_rule_allows() {
        use super::{STREAMING_SERVICES, normalization_gain};
        let gain = |i: usize, lufs: f64, peak: Option<f64>| {
            normalization_gain(&STREAMING_SERVICES[i], Some(lufs), peak)
        };
        // Spotify's published example: -20 LUFS, true peak -5 dB: lifted to -16 LUFS only
        assert_eq!(gain(0, -20.0, Some(-5.0)), Some(4.0));
        assert_eq!(gain(0, -20.0, Some(-9.0)), Some(6.0));
        assert_eq!(gain(0, -20.0, Some(-0.5)), Some(0.0));
        assert_eq!(gain(0, -20.0, None), None);
        assert_eq!(gain(1, -20.0, Some(-0.5)), Some(9.0)); // loud: limiter, no peak rule
        assert_eq!(gain(3, -20.0, Some(-9.0)), Some(0.0)); // YouTube turns down only
        let m = Metrics {
            integrated_lufs: Some(-14.02),
            true_peak_dbtp: Some(-1.0),
            ..Metrics::default()
        };
        let lines = describe_metrics(&m);
        assert!(lines.contains(&"Spotify (normal): plays as mastered".to_string()));
        assert!(lines.contains(&"Spotify (loud): turned up 3.0 dB".to_string()));
    }
}

#[cfg(test)]
mod title_tests {
    use super::*;
    use crate::data::axes::Axis;

    #[test]
    fn a_clock_axis_is_titled_in_minutes_and_seconds() {
        let long = Axis::linear("time", "s", 0.0, 168.0);
        assert!(long.ticks(8).iter().any(|t| t.label.contains(':')));
        assert_eq!(axis_title(&long, "x"), "time (m:ss)");
        let short = Axis::linear("time", "s", 0.0, 30.0);
        assert_eq!(axis_title(&short, "x"), "time (s)");
        assert_eq!(axis_title(&Axis::linear("hp", "", 0.0, 1.0), "x"), "hp");
    }
}
