//! The status area under the 3D view: the one place for what the app is telling the user,
//! always in sight whatever the side panel's scroll. It shows the work under way (each load
//! with its stage, share done and Cancel; work that blocks the window; B of a compare loading)
//! and the lines of [`Messages`](crate::ui::state::messages::Messages): errors, warnings and
//! confirmations, each with a × to dismiss it. It takes no room when there is nothing to say.

use std::sync::atomic::Ordering;
use std::time::Instant;

use eframe::egui::{self, RichText};

use crate::ui::open::file_name;
use crate::ui::state::LoudscapeApp;
use crate::ui::state::messages::Kind;

impl LoudscapeApp {
    /// Whether the status area has anything to show.
    fn status_shown(&self, now: Instant) -> bool {
        !self.loading.is_empty()
            || self.busy.is_some()
            || self.video_export.running.is_some()
            || self.compare.as_ref().is_some_and(|c| c.receiver.is_some())
            || self.messages.shown(now).next().is_some()
    }

    /// The status area: a panel at the bottom of the window's right part, under the 3D view
    /// (added after the side panel, so the side panel's scroll never hides it).
    pub(super) fn status_area(&mut self, ui: &mut egui::Ui) {
        let now = Instant::now();
        if let Some(fade) = self.messages.next_fade(now) {
            ui.ctx().request_repaint_after(fade);
        }
        if !self.status_shown(now) {
            return;
        }
        egui::Panel::bottom("messages")
            .frame(crate::ui::style::panel_frame(ui.style()))
            .show(ui, |ui| {
                ui.add_space(2.0);
                if let Some(busy) = &self.busy {
                    ui.horizontal(|ui| {
                        ui.spinner();
                        ui.label(busy);
                    });
                }
                self.loading_progress(ui);
                self.video_export_progress(ui);
                if let Some(state) = &self.compare
                    && state.receiver.is_some()
                {
                    ui.horizontal(|ui| {
                        ui.spinner();
                        ui.label(format!("loading B: {}", state.path.display()));
                    });
                }
                let mut dismiss = None;
                let shown: Vec<_> = self
                    .messages
                    .shown(now)
                    .map(|(i, m)| (i, m.kind, m.text.clone()))
                    .collect();
                let several = shown.len() > 1;
                let window_height = ui.ctx().content_rect().height();
                egui::ScrollArea::vertical()
                    .max_height(status_max_height(window_height))
                    .stick_to_bottom(true)
                    .show(ui, |ui| {
                        for (index, kind, text) in shown {
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
                                    egui::Label::new(
                                        RichText::new(format!("{prefix}{text}")).color(colour),
                                    )
                                    .wrap(),
                                );
                            });
                        }
                    });
                if several && ui.small_button("dismiss all").clicked() {
                    self.messages.clear();
                }
                if let Some(index) = dismiss {
                    self.messages.dismiss(index);
                }
                ui.add_space(2.0);
            });
    }

    /// One row a load: the file, the extractor's stage and share done, and Cancel.
    fn loading_progress(&self, ui: &mut egui::Ui) {
        for loading in &self.loading {
            let progress = loading.shared.progress.lock().ok().and_then(|p| p.clone());
            let cancelled = loading.shared.cancel.load(Ordering::Relaxed);
            ui.horizontal_wrapped(|ui| {
                ui.spinner();
                ui.label(RichText::new(file_name(&loading.path)).strong());
                match (&progress, cancelled) {
                    (_, true) => {
                        ui.label("cancelling…");
                    }
                    (Some(progress), false) => {
                        ui.add(
                            egui::ProgressBar::new(progress.fraction)
                                .text(format!(
                                    "{} {:.0}%",
                                    progress.stage,
                                    progress.fraction * 100.0
                                ))
                                .desired_width(240.0),
                        );
                        if ui
                            .small_button("Cancel")
                            .on_hover_text("stop the extractor")
                            .clicked()
                        {
                            loading.shared.cancel.store(true, Ordering::Relaxed);
                        }
                    }
                    (None, false) => {
                        ui.label("loading…");
                    }
                }
                if let Some(preview) = &loading.preview {
                    // The song's points so far are on screen (`slots.rs`).
                    let mut text = format!("{} points so far", points_text(preview.points));
                    if self.settings.view != crate::render::scene::ViewKind::Points {
                        text.push_str(", drawn as points until the whole cloud is in");
                    }
                    ui.label(RichText::new(text).small().weak());
                }
            });
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
    #[test]
    fn point_counts_read_short() {
        assert_eq!(super::points_text(950), "950");
        assert_eq!(super::points_text(12_345), "12.3 k");
        assert_eq!(super::points_text(4_560_000), "4.56 M");
    }
}
