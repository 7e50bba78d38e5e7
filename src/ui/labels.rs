//! Text about the cloud for the side panel (where it came from, its loudness metrics and what
//! streaming services do with it), and the axis labels painted over the window's 3D view: laid
//! out by `annotate::axes` (the same layout pictures draw), painted with egui's painter.

use eframe::egui::{self, Color32};

pub use crate::annotate::axes::{
    AxisLabels, Label, axis_labels, axis_labels_for_axes, axis_labels_for_box, axis_title,
};
use crate::data::cloud::PointCloud;
pub use crate::data::normalize::{
    STREAMING_SERVICES, StreamingService, TurnUp, normalization_gain,
};
use crate::render::colormap::Background;
use crate::view::frame_view::FrameView;

/// The translucent plate under the window's badges and labels on the dark background.
pub const LABEL_PLATE: Color32 = Color32::from_rgba_premultiplied(10, 11, 15, 190);

/// Paints labels projected through `view` into `rect` (the 3D view's place on screen, points).
pub fn paint(painter: &egui::Painter, rect: egui::Rect, view: &FrameView, labels: &AxisLabels) {
    paint_on(painter, rect, view, labels, Background::Dark);
}

/// As [`paint`], in the ink of `background` (dark ink on the light background).
pub fn paint_on(
    painter: &egui::Painter,
    rect: egui::Rect,
    view: &FrameView,
    labels: &AxisLabels,
    background: Background,
) {
    let shapes =
        crate::annotate::axes::layout(crate::ui::annotation::rect(rect), view, labels, background);
    crate::ui::annotation::paint(painter, &shapes);
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
    // EBU Mode's maxima, with the time a meter shows them (the window's end).
    let maxima = [
        (
            "max momentary (400 ms)",
            m.max_momentary_lufs,
            m.max_momentary_s,
        ),
        (
            "max short-term (3 s)",
            m.max_short_term_lufs,
            m.max_short_term_s,
        ),
    ];
    let mut next = lines
        .iter()
        .position(|l| l.starts_with("loudness range"))
        .or_else(|| lines.iter().position(|l| l.starts_with("integrated")))
        .map_or(0, |i| i + 1);
    for (name, value, at) in maxima {
        if let Some(v) = value {
            let when = at.map_or(String::new(), |t| {
                format!(" at {}", crate::playback::format_clock(t))
            });
            lines.insert(next, format!("{name}: {v:.1} LUFS{when}"));
            next += 1;
        }
    }
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
            max_momentary_lufs: Some(-5.94),
            max_momentary_s: Some(61.43),
            max_short_term_lufs: Some(-6.5),
            ..Metrics::default()
        };
        let lines = describe_metrics(&m);
        assert_eq!(
            lines,
            [
                "integrated loudness: -8.0 LUFS",
                "max momentary (400 ms): -5.9 LUFS at 1:01.4",
                "max short-term (3 s): -6.5 LUFS",
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
