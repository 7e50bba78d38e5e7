//! What is under the cursor in the 3D view: picking on hover (only when the cursor or the view
//! changed), clicks (seek a song, select a timeline song), the markers drawn for them and the
//! read-out next to the cursor.

use eframe::egui::{self, Color32};

use crate::render::markers::MarkerBox;
use crate::render::scene::ViewKind;
use crate::ui::state::{Hover, HoverKey, LoudscapeApp, Slot};
use crate::view::frame_view::FrameView;
use crate::view::pick::{self, Reading, VOLUME_PICK_DENSITY};

impl LoudscapeApp {
    /// The playhead plane, the loop range and the hovered or selected timeline song.
    pub(super) fn markers(&self) -> Vec<MarkerBox> {
        let mut markers = Vec::new();
        let Some(loaded) = self.active() else {
            return markers;
        };
        let axis = &loaded.cloud.meta.axes.x;
        match self.active {
            Slot::Song => {
                if let Some((a, b)) = self.audio.loop_shown() {
                    markers.push(MarkerBox::x_span(
                        crate::playback::time_to_x(axis, a),
                        crate::playback::time_to_x(axis, b),
                        [0.95, 0.8, 0.3, 0.06],
                        [0.95, 0.8, 0.3, 0.5],
                    ));
                }
                if let Some(t) = self.audio.time_s() {
                    markers.push(MarkerBox::playhead(crate::playback::time_to_x(axis, t)));
                }
            }
            Slot::Timeline => {
                let songs = &loaded.cloud.meta.songs;
                for (index, alpha) in [(self.selected_song, 0.16), (self.hovered_song, 0.09)] {
                    let Some(song) = index.and_then(|i| songs.get(i)) else {
                        continue;
                    };
                    if let (Some(a), Some(b)) = (song.x_min, song.x_max) {
                        markers.push(MarkerBox::x_span(
                            a as f32,
                            b as f32,
                            [1.0, 1.0, 1.0, alpha],
                            [1.0, 1.0, 1.0, 0.7],
                        ));
                    }
                }
            }
        }
        markers
    }

    /// Recomputes what is under the cursor when the cursor or the view changed.
    pub(super) fn update_hover(&mut self, px: Option<glam::Vec2>, view: &FrameView, moving: bool) {
        let (Some(px), false) = (px, moving) else {
            if px.is_none() {
                self.hover = None;
                self.hovered_song = None;
            }
            return;
        };
        let Some(loaded) = self.active() else {
            self.hover = None;
            return;
        };
        let key = HoverKey {
            px,
            camera: view.camera,
            size: (view.width, view.height),
            view: self.settings.view,
            cloud_id: loaded.id,
            min_scalar: self.settings.points.min_scalar,
            freq_axis: loaded.freq_axis,
        };
        if self.hover.as_ref().is_some_and(|(k, _)| k == &key) {
            return;
        }
        let cloud = loaded.cloud.clone();
        let axes = &cloud.meta.axes;
        // On a remapped frequency axis (freq_axis.rs) the view's positions are the remapped
        // points and its z reads through the view's axis; a point still reads its stored bin.
        let view_axes = loaded.freq.as_ref().map(|m| m.view_axes(axes));
        let shown_axes = view_axes.as_ref().unwrap_or(axes);
        let shown_points: Option<&[crate::data::cloud::Point]> = match &loaded.freq {
            None => Some(&cloud.points),
            Some(_) => loaded.view_points.as_deref().map(Vec::as_slice),
        };
        let (origin, dir) = pick::cursor_ray(view, px);
        let mut hover = Hover::default();
        // The points of a song being extracted stand in for its surface and volume.
        let shown_view = match self.active == Slot::Song && self.previewing() {
            true => ViewKind::Points,
            false => self.settings.view,
        };
        match shown_view {
            ViewKind::Points => {
                let ppp_radius = 5.0;
                if let Some(i) = shown_points.and_then(|points| {
                    pick::pick_point(
                        points,
                        view,
                        px,
                        ppp_radius,
                        self.settings.points.min_scalar,
                    )
                }) {
                    hover.readings = pick::point_readings(axes, &cloud.points[i]);
                    hover.x = Some(cloud.points[i].position[0]);
                }
            }
            ViewKind::Surface | ViewKind::Volume => {
                let threshold = if self.settings.view == ViewKind::Surface {
                    self.settings.surface.iso_value
                } else {
                    VOLUME_PICK_DENSITY
                };
                (hover.readings, hover.x) = pick::grid_readout(
                    loaded.cpu_grid.as_ref(),
                    shown_axes,
                    origin,
                    dir,
                    threshold,
                );
            }
        }
        if hover.x.is_none() {
            (hover.readings, hover.x) = pick::box_readout(shown_axes, origin, dir);
        }
        self.hovered_song = match (self.active, hover.x) {
            (Slot::Timeline, Some(x)) => pick::song_at(&cloud.meta.songs, x),
            _ => None,
        };
        // The year from the song spans, not the axis's linear map (see timeline_year); a
        // song's level is a bin level.
        pick::name_readings(
            &mut hover.readings,
            axes,
            cloud.meta.mode,
            &cloud.meta.songs,
            hover.x,
        );
        if let Some(song) = self.hovered_song.and_then(|i| cloud.meta.songs.get(i)) {
            hover.readings.insert(
                0,
                Reading {
                    name: "song".into(),
                    value: song_title(song),
                },
            );
            if let Some((name, value)) = crate::ui::normalize::gain_reading(song) {
                hover.readings.insert(1, Reading { name, value });
            }
        }
        self.hover = Some((key, hover));
    }

    /// A click on the data: seek there (Song) or select the song (Timeline).
    pub(super) fn click(&mut self) {
        let Some(x) = self.hover.as_ref().and_then(|(_, h)| h.x) else {
            return;
        };
        match self.active {
            Slot::Song => {
                if let Some(loaded) = self.song.as_ref() {
                    let t = crate::playback::x_to_time(&loaded.cloud.meta.axes.x, x);
                    self.audio.seek(t);
                }
            }
            Slot::Timeline => self.selected_song = self.hovered_song,
        }
    }
}

/// "Title — Artist (1984)".
pub(super) fn song_title(song: &crate::data::cloud::SongInfo) -> String {
    // An untagged song reads as its file name ("untitled" only where none is recorded).
    let file_name = || {
        song.open_path()
            .and_then(|p| p.file_name().map(|n| n.to_string_lossy().into_owned()))
    };
    let mut text = if !song.title.trim().is_empty() {
        song.title.clone()
    } else {
        file_name().unwrap_or_else(|| "untitled".to_string())
    };
    if !song.artist.is_empty() {
        text.push_str(&format!(" — {}", song.artist));
    }
    if let Some(year) = song.year {
        text.push_str(&format!(" ({year})"));
    }
    text
}

/// The read-out next to the cursor.
pub(super) fn paint_readings(
    painter: &egui::Painter,
    rect: egui::Rect,
    pos: egui::Pos2,
    readings: &[Reading],
) {
    if readings.is_empty() {
        return;
    }
    let text = readings
        .iter()
        .map(|r| format!("{}: {}", r.name, r.value))
        .collect::<Vec<_>>()
        .join("\n");
    let (min, galley) = readout_layout(rect, pos, |wrap| {
        // A song's title in visual order (a Hebrew title right to left, its year in order).
        let mut job = super::style::bidi_job(
            &text,
            egui::FontId::monospace(12.0),
            Color32::from_gray(230),
        );
        job.wrap.max_width = wrap;
        painter.layout_job(job)
    });
    let size = galley.size() + egui::vec2(12.0, 8.0);
    let frame = egui::Rect::from_min_size(min, size);
    painter.rect_filled(frame, 4.0, Color32::from_black_alpha(200));
    painter.galley(min + egui::vec2(6.0, 4.0), galley, Color32::from_gray(230));
}

/// Where the read-out box goes: right of and below the cursor, flipped to the other side where
/// it would leave the view, and always inside the view: a line longer than the view (a long
/// song title) wraps at its width instead of running off it. `layout(wrap_width)` lays the text
/// out; returns the box's top-left corner and the laid-out text.
fn readout_layout(
    rect: egui::Rect,
    pos: egui::Pos2,
    layout: impl Fn(f32) -> std::sync::Arc<egui::Galley>,
) -> (egui::Pos2, std::sync::Arc<egui::Galley>) {
    const PAD: egui::Vec2 = egui::vec2(12.0, 8.0);
    const EDGE: f32 = 4.0;
    let galley = layout((rect.width() - PAD.x - 2.0 * EDGE).max(40.0));
    let size = galley.size() + PAD;
    let mut min = pos + egui::vec2(16.0, 12.0);
    if min.x + size.x > rect.right() {
        min.x = pos.x - 16.0 - size.x;
    }
    if min.y + size.y > rect.bottom() {
        min.y = pos.y - 12.0 - size.y;
    }
    min.x = min.x.max(rect.left() + EDGE);
    min.y = min.y.max(rect.top() + EDGE);
    (min, galley)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A read-out longer than the view (a 10,000-song timeline's long title, the cursor near the
    /// view's left edge) stays inside the view, wrapped, and so does a short one at any corner.
    #[test]
    fn the_readout_box_stays_inside_the_view() {
        let ctx = egui::Context::default();
        let view = egui::Rect::from_min_size(egui::pos2(270.0, 0.0), egui::vec2(400.0, 300.0));
        let long = format!(
            "song: {}",
            "A Song Title Of Ordinary Length, Part 01653 ".repeat(3)
        );
        let mut output = ctx.run_ui(Default::default(), |ui| {
            let painter = egui::Painter::new(ui.ctx().clone(), egui::LayerId::background(), view);
            for text in [long.as_str(), "time: 0:01.0\nlevel: -12.0 dB"] {
                for pos in [
                    view.left_top(),
                    view.right_top(),
                    view.left_bottom(),
                    view.right_bottom(),
                    view.center(),
                    egui::pos2(300.0, 150.0),
                ] {
                    let (min, galley) = readout_layout(view, pos, |wrap| {
                        painter.layout(
                            text.to_string(),
                            egui::FontId::monospace(12.0),
                            Color32::WHITE,
                            wrap,
                        )
                    });
                    let frame =
                        egui::Rect::from_min_size(min, galley.size() + egui::vec2(12.0, 8.0));
                    assert!(
                        frame.left() >= view.left() && frame.right() <= view.right() + 0.5,
                        "{text:.20}… at {pos:?}: {frame:?} leaves {view:?} sideways"
                    );
                    assert!(frame.top() >= view.top(), "{frame:?} above {view:?}");
                }
            }
        });
        output.textures_delta.clear();
    }

    #[test]
    fn an_untagged_song_reads_as_its_file_name() {
        let song: crate::data::cloud::SongInfo = serde_json::from_value(serde_json::json!({
            "title": "", "artist": "", "year": 1999, "path": "/music/demo/b-side.flac"
        }))
        .unwrap();
        assert_eq!(song_title(&song), "b-side.flac (1999)");
        let tagged: crate::data::cloud::SongInfo = serde_json::from_value(serde_json::json!({
            "title": "Tune", "artist": "Band", "year": 2001, "path": "/music/x.ogg"
        }))
        .unwrap();
        assert_eq!(song_title(&tagged), "Tune — Band (2001)");
        let nothing: crate::data::cloud::SongInfo =
            serde_json::from_value(serde_json::json!({ "title": "" })).unwrap();
        assert_eq!(song_title(&nothing), "untitled");
    }
}
