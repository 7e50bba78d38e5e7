//! The status area, an overlay at the bottom right of the 3D view: the one place for what the
//! app is telling the user, always in sight whatever the side panel's scroll, and never taking
//! room from the view (its size, and so the picture's framing, stays). It shows the work under
//! way (each load with its stage, share done and Cancel, B of a compare as A; work that blocks
//! the window) and the lines of [`Messages`](crate::ui::state::messages::Messages) about what
//! is shown: the latest, with a × to dismiss it, and the count of all with a button that opens
//! the list.

use std::sync::atomic::Ordering;

use eframe::egui::{self, RichText};

use crate::ui::open::file_name;
use crate::ui::state::LoudscapeApp;
use crate::ui::state::loading::Shared;
use crate::ui::state::messages::Kind;

impl LoudscapeApp {
    /// The cloud file shown (whose own messages are shown).
    fn shown_cloud(&self) -> Option<&std::path::Path> {
        self.active().map(|l| l.cloud.path.as_path())
    }

    /// Whether the status area has anything to show.
    fn status_shown(&self) -> bool {
        !self.loading.is_empty()
            || self.busy.is_some()
            || self.video_export.running.is_some()
            || self.compare.as_ref().is_some_and(|c| c.loading())
            || self.messages.shown(self.shown_cloud()).next().is_some()
    }

    /// The status area: an overlay at the bottom right of the 3D view (call it with the view's
    /// part of the window left, before the central panel), so it never changes the view's size
    /// and the side panel's scroll never hides it. The work under way, then the messages: the
    /// latest line and, when there are more, their count, a button that opens the whole list.
    pub(super) fn status_area(&mut self, ui: &mut egui::Ui) {
        if !self.status_shown() {
            return;
        }
        let view = ui.available_rect_before_wrap();
        let width = (view.width() - 24.0).clamp(120.0, 640.0);
        let window_height = ui.ctx().content_rect().height();
        let frame = egui::Frame::new()
            .fill(ui.visuals().panel_fill.gamma_multiply(0.94))
            .stroke(ui.visuals().window_stroke)
            .corner_radius(4.0)
            .inner_margin(6.0);
        let id = egui::Id::unique("status-overlay");
        let before = ui.ctx().memory(|m| m.area_rect(id)).map(|r| r.size());
        let shown = egui::Area::new(id)
            .order(egui::Order::Foreground)
            // At once, at full colour: a warning fading in was half-drawn in the first frames
            // (and in a screenshot taken then).
            .fade_in(false)
            .pivot(egui::Align2::RIGHT_BOTTOM)
            .fixed_pos(view.right_bottom() - egui::vec2(8.0, 8.0))
            .constrain_to(view)
            .show(ui.ctx(), |ui| {
                ui.set_max_width(width);
                frame.show(ui, |ui| {
                    ui.set_max_width(width);
                    if let Some(busy) = &self.busy {
                        ui.horizontal(|ui| {
                            ui.spinner();
                            ui.label(busy);
                        });
                    }
                    self.loading_progress(ui);
                    self.video_export_progress(ui);
                    self.message_lines(ui, window_height);
                });
            });
        // The area is placed (bottom right) and clipped by last frame's size: in the frame its
        // content grows (the list opened, a line more) it would hang past the view's bottom,
        // cut, and the window paints no other frame until something changes. Lay it out again.
        if before.is_some_and(|size| size != shown.response.rect.size()) {
            ui.ctx().request_discard("the status area changed size");
            ui.ctx().request_repaint();
        }
    }

    /// The messages of the status area: closed, the latest line and the count of all with the
    /// button that opens the list; open, every line (scrolled past a fifth of the window).
    fn message_lines(&mut self, ui: &mut egui::Ui, window_height: f32) {
        let shown_cloud = self.shown_cloud().map(|p| p.to_path_buf());
        let shown_cloud = shown_cloud.as_deref();
        let shown: Vec<_> = self
            .messages
            .shown(shown_cloud)
            .map(|(i, m)| (i, m.kind, m.text.clone()))
            .collect();
        let Some(latest) = shown.last().cloned() else {
            return;
        };
        let count = self.messages.count(shown_cloud);
        let mut dismiss = None;
        let mut line = |ui: &mut egui::Ui, (index, kind, text): (usize, Kind, String)| {
            ui.horizontal(|ui| {
                if ui.small_button("×").on_hover_text("dismiss").clicked() {
                    dismiss = Some(index);
                }
                let (prefix, colour) = match kind {
                    Kind::Error => ("error: ", crate::ui::style::ERROR),
                    Kind::Warning => ("warning: ", crate::ui::style::WARNING),
                    Kind::Info => ("", ui.visuals().text_color()),
                };
                ui.add(
                    egui::Label::new(RichText::new(format!("{prefix}{text}")).color(colour)).wrap(),
                );
            });
        };
        let open = self.messages.is_open() && count.is_some();
        if open {
            // Its height does not depend on the room the area had last frame (min and max).
            let height = status_max_height(window_height);
            egui::ScrollArea::vertical()
                .max_height(height)
                .min_scrolled_height(height)
                .stick_to_bottom(true)
                .show(ui, |ui| {
                    for entry in shown {
                        line(ui, entry);
                    }
                });
        } else {
            line(ui, latest);
        }
        let mut clear = false;
        if let Some(count) = count {
            ui.horizontal(|ui| {
                let label = if open {
                    "hide the list".to_string()
                } else {
                    format!("{count}: show all")
                };
                if ui
                    .small_button(label)
                    .on_hover_text("every message about what is shown")
                    .clicked()
                {
                    self.messages.set_open(!open);
                }
                if open && ui.small_button("dismiss all").clicked() {
                    clear = true;
                }
            });
        }
        if clear {
            self.messages.clear(shown_cloud);
        } else if let Some(index) = dismiss {
            self.messages.dismiss(index);
        }
    }

    /// The rows of the loads under way: each load of A, then B of a compare, with the same
    /// stage, share done and Cancel (B is extracted as A is).
    pub(super) fn progress_rows(&self) -> Vec<ProgressRow<'_>> {
        let mut rows: Vec<ProgressRow<'_>> = self
            .loading
            .iter()
            .map(|loading| {
                let mut row = ProgressRow::new(file_name(&loading.path), &loading.shared);
                if let Some(preview) = &loading.preview {
                    // The song's points so far are on screen (`slots.rs`).
                    let mut text = format!("{} points so far", points_text(preview.points));
                    if self.settings.view != crate::render::scene::ViewKind::Points {
                        text.push_str(", drawn as points until the whole cloud is in");
                    }
                    row.note = Some(text);
                }
                row
            })
            .collect();
        if let Some(state) = &self.compare {
            for (i, version) in state.versions.iter().enumerate() {
                if version.receiver.is_some() {
                    rows.push(ProgressRow::new(
                        format!(
                            "{}: {}",
                            crate::ui::state::compare_window::Listening(i + 1).letter(),
                            file_name(&version.path)
                        ),
                        &version.shared,
                    ));
                }
            }
        }
        rows
    }

    /// One row a load: the file, the extractor's stage and share done, and Cancel.
    fn loading_progress(&self, ui: &mut egui::Ui) {
        for row in self.progress_rows() {
            ui.horizontal_wrapped(|ui| {
                ui.spinner();
                ui.label(RichText::new(&row.name).strong());
                match row.stage() {
                    Stage::Cancelling => {
                        ui.label("cancelling…");
                    }
                    Stage::Progress(fraction, text) => {
                        ui.add(
                            egui::ProgressBar::new(fraction)
                                .text(text)
                                .desired_width(240.0),
                        );
                        if ui
                            .small_button("Cancel")
                            .on_hover_text("stop the extractor")
                            .clicked()
                        {
                            row.shared.cancel.store(true, Ordering::Relaxed);
                        }
                    }
                    Stage::Loading => {
                        ui.label("loading…");
                    }
                }
                if let Some(note) = &row.note {
                    ui.label(RichText::new(note).small().weak());
                }
            });
        }
    }
}

/// A load's row in the status area.
pub(super) struct ProgressRow<'a> {
    /// The file (`B: file` for B of a compare).
    pub(super) name: String,
    /// Its thread's progress and Cancel.
    pub(super) shared: &'a Shared,
    /// A note after the bar (a song's points so far).
    pub(super) note: Option<String>,
}

/// Where a load stands, as its row says it.
#[derive(Clone, Debug, PartialEq)]
pub(super) enum Stage {
    Cancelling,
    /// The share done and the bar's text (`stage N%`).
    Progress(f32, String),
    /// Opening a cloud file (no stages).
    Loading,
}

impl<'a> ProgressRow<'a> {
    fn new(name: String, shared: &'a Shared) -> Self {
        Self {
            name,
            shared,
            note: None,
        }
    }

    pub(super) fn stage(&self) -> Stage {
        if self.shared.cancel.load(Ordering::Relaxed) {
            return Stage::Cancelling;
        }
        match self.shared.progress.lock().ok().and_then(|p| p.clone()) {
            Some(progress) => Stage::Progress(
                progress.fraction,
                format!("{} {:.0}%", progress.stage, progress.fraction * 100.0),
            ),
            None => Stage::Loading,
        }
    }
}

/// A count of points as the status area says it: `950`, `12.3 k`, `4.56 M`.
fn points_text(points: usize) -> String {
    match points {
        0..1_000 => points.to_string(),
        1_000..1_000_000 => format!("{:.1} k", points as f64 / 1e3),
        _ => format!("{:.2} M", points as f64 / 1e6),
    }
}

/// The status area's most height in a window `window_height` points high (it scrolls past it):
/// 110 points, a fifth of a short window.
pub(super) fn status_max_height(window_height: f32) -> f32 {
    (window_height * 0.2).clamp(40.0, 110.0)
}

#[cfg(test)]
mod tests {
    use std::path::PathBuf;

    use super::*;
    use crate::ui::app::WindowOptions;
    use crate::ui::state::compare_window::CompareState;

    /// Each version of a compare shows its stage, share done and Cancel as A does (a spinner
    /// alone before).
    #[test]
    fn loading_b_has_a_row_like_a_load_of_a() {
        let mut app = LoudscapeApp::new(
            WindowOptions {
                screenshot: Some(std::env::temp_dir().join("loudscape-unit-never-written.png")),
                ..Default::default()
            },
            None,
        );
        assert!(app.progress_rows().is_empty());
        let mut state = CompareState::new(PathBuf::from("music/b.ogg"));
        let (_sender, receiver) = std::sync::mpsc::channel();
        state.start_loading(crate::ui::state::compare_window::Listening::B, |_| receiver);
        state.add(PathBuf::from("music/c.ogg")).unwrap();
        let (_sender_c, receiver) = std::sync::mpsc::channel();
        state.start_loading(crate::ui::state::compare_window::Listening(2), |_| receiver);
        app.compare = Some(state);
        let rows = app.progress_rows();
        assert_eq!(rows.len(), 2);
        assert_eq!(rows[0].name, "B: b.ogg");
        assert_eq!(rows[1].name, "C: c.ogg");
        assert_eq!(rows[0].stage(), Stage::Loading);
        let shared = app.compare.as_ref().unwrap().versions[0].shared.clone();
        *shared.progress.lock().unwrap() = Some(crate::extract::Progress {
            stage: "spectrogram".into(),
            fraction: 0.42,
        });
        let rows = app.progress_rows();
        assert_eq!(
            rows[0].stage(),
            Stage::Progress(0.42, "spectrogram 42%".into())
        );
        // Its Cancel reaches B's thread (the same flag the extractor watches).
        rows[0].shared.cancel.store(true, Ordering::Relaxed);
        assert!(
            app.compare.as_ref().unwrap().versions[0]
                .shared
                .cancel
                .load(Ordering::Relaxed)
        );
        assert_eq!(app.progress_rows()[0].stage(), Stage::Cancelling);
    }

    fn app() -> LoudscapeApp {
        LoudscapeApp::new(
            WindowOptions {
                screenshot: Some(std::env::temp_dir().join("loudscape-unit-never-written.png")),
                ..Default::default()
            },
            None,
        )
    }

    /// A text drawn: its text, clip rect and rect.
    type Drawn = (String, egui::Rect, egui::Rect);

    /// One frame of the side panel, a loudness strip `strip` points high (if any), the status
    /// area and the central panel: the central panel's rect (the 3D view's) and the texts drawn.
    fn frame_with(
        app: &mut LoudscapeApp,
        ctx: &egui::Context,
        strip: Option<f32>,
    ) -> (egui::Rect, Vec<Drawn>) {
        let size = egui::vec2(1000.0, 700.0);
        let mut view = egui::Rect::NOTHING;
        let mut output = ctx.run_ui(
            egui::RawInput {
                screen_rect: Some(egui::Rect::from_min_size(egui::Pos2::ZERO, size)),
                ..Default::default()
            },
            |ui| {
                egui::Panel::left("controls")
                    .exact_size(270.0)
                    .show(ui, |ui| ui.label("controls"));
                if let Some(height) = strip {
                    egui::Panel::bottom("strip")
                        .exact_size(height)
                        .show(ui, |ui| ui.label("strip"));
                }
                app.status_area(ui);
                egui::CentralPanel::default().show(ui, |ui| view = ui.max_rect());
            },
        );
        output.textures_delta.clear();
        let texts = output
            .shapes
            .iter()
            .filter_map(|clipped| match &clipped.shape {
                egui::Shape::Text(text) => Some((
                    text.galley.text().to_string(),
                    clipped.clip_rect,
                    clipped.shape.visual_bounding_rect(),
                )),
                _ => None,
            })
            .collect();
        (view, texts)
    }

    /// [`frame_with`] without a strip, the texts alone.
    fn frame(app: &mut LoudscapeApp, ctx: &egui::Context) -> (egui::Rect, Vec<String>) {
        let (view, texts) = frame_with(app, ctx, None);
        (view, texts.into_iter().map(|(text, ..)| text).collect())
    }

    /// Messages come and go over the view, not under it: the view keeps its size (the picture
    /// jumped when a line appeared), and several collapse to the latest and a count.
    #[test]
    fn messages_never_change_the_views_size_and_collapse_to_a_count() {
        let mut app = app();
        let ctx = egui::Context::default();
        let (empty, _) = frame(&mut app, &ctx);
        app.messages.warn("first.flac: clipped");
        app.messages.warn("second.flac: clipped");
        app.messages.error("third.flac: not audio");
        let mut texts = Vec::new();
        for _ in 0..3 {
            let (view, drawn) = frame(&mut app, &ctx);
            assert_eq!(view, empty, "a message took room from the view");
            texts = drawn;
        }
        let has = |texts: &[String], start: &str| texts.iter().any(|t| t.starts_with(start));
        assert!(
            has(&texts, "error: third.flac"),
            "the latest line: {texts:?}"
        );
        assert!(!has(&texts, "warning: first.flac"), "collapsed: {texts:?}");
        assert!(has(&texts, "1 error, 2 warnings"), "{texts:?}");
        app.messages.set_open(true);
        for _ in 0..3 {
            let (view, drawn) = frame(&mut app, &ctx);
            assert_eq!(view, empty, "the open list took room from the view");
            texts = drawn;
        }
        assert!(
            has(&texts, "warning: first.flac") && has(&texts, "warning: second.flac"),
            "the open list: {texts:?}"
        );
    }

    /// The list opened stays whole in the view, its buttons included, from the frame of the
    /// click: that frame placed it by the closed box's size, past the view's bottom, its
    /// buttons under the loudness strip, and the window painted nothing after it.
    #[test]
    fn the_open_list_stays_inside_the_view() {
        let mut app = app();
        let ctx = egui::Context::default();
        for i in 0..4 {
            app.messages.warn(format!(
                "song{i}.ogg: clipped: 14292 run(s) of 3 or more consecutive samples at or beyond \
                 full scale (229236 samples in runs, the first at 0.796 s)"
            ));
        }
        // Closed for a few frames, then opened: the frame of the click is the one a user sees
        // (the window paints no other until something changes).
        let mut texts = Vec::new();
        let mut view = egui::Rect::NOTHING;
        for opened in [false, false, false, true] {
            app.messages.set_open(opened);
            (view, texts) = frame_with(&mut app, &ctx, Some(120.0));
        }
        let view_bottom = view.bottom();
        let buttons: Vec<_> = texts
            .iter()
            .filter(|(text, ..)| ["hide the list", "dismiss all"].contains(&text.as_str()))
            .map(|&(_, clip, rect)| (clip, rect))
            .collect();
        assert_eq!(buttons.len(), 2, "both buttons drawn: {texts:?}");
        for (clip, rect) in buttons {
            assert!(
                rect.bottom() <= view_bottom && clip.contains_rect(rect),
                "a button of the list at {rect:?} (clipped to {clip:?}) is not whole above the \
                 strip at {view_bottom}"
            );
        }
    }

    #[test]
    fn point_counts_read_short() {
        assert_eq!(super::points_text(950), "950");
        assert_eq!(super::points_text(12_345), "12.3 k");
        assert_eq!(super::points_text(4_560_000), "4.56 M");
    }
}
