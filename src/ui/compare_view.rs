//! The A/B compare in the 3D view: side by side (two viewports, one camera) or the difference
//! grid, each drawn by the bridge's compare callback (`bridge/compare.rs`), with its axis
//! labels, titles and colour keys, and the hover read-outs of A and B (`compare_readouts.rs`).

use eframe::egui;

use crate::render::scene::RenderSettings;
use crate::ui::bridge::{CompareCallback, paint_callback};
use crate::ui::compare::paint_difference;
use crate::ui::compare_readouts::{CompareHoverKey, compare_readings, difference_readings};
use crate::ui::compare_shot::difference_settings;
use crate::ui::hover::paint_readings;
use crate::ui::labels;
use crate::ui::state::compare_window::{CompareLayout, CompareState, Listening};
use crate::ui::state::{LoudscapeApp, Slot};
use crate::ui::view_3d::{GAP, busy_badge};
use crate::view::frame_view::FrameView;

impl LoudscapeApp {
    /// Draws the compare into `rect` when it is shown (then the normal view is not drawn) and
    /// its hover read-outs. `view` is one half's view in side by side, the whole in difference.
    pub(super) fn paint_compare(
        &mut self,
        painter: &egui::Painter,
        rect: egui::Rect,
        view: &FrameView,
        render_view: &FrameView,
        settings: &RenderSettings,
        hover: Option<egui::Pos2>,
    ) -> bool {
        if self.active != Slot::Song {
            return false;
        }
        let Some(state) = self.compare.as_ref() else {
            return false;
        };
        if !state.shown() {
            return false;
        }
        let Some(clouds) = state.clouds.clone() else {
            return false;
        };
        let names = [&clouds.0, &clouds.1].map(|c| {
            c.path
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default()
        });
        // The letter of the version beside A in the scene drawn (B, C...).
        let (beside, matched) = state
            .built_for
            .map_or((Listening::B, false), |(_, version, matched)| {
                (version, matched)
            });
        let letter = beside.letter();
        let ppp = painter.ctx().pixels_per_point();
        let mut readings = None;
        match state.layout {
            CompareLayout::SideBySide => {
                let half = (rect.width() - GAP) / 2.0;
                let rects = [
                    egui::Rect::from_min_size(rect.min, egui::vec2(half, rect.height())),
                    egui::Rect::from_min_size(
                        rect.min + egui::vec2(half + GAP, 0.0),
                        egui::vec2(half, rect.height()),
                    ),
                ];
                // The points stand in until the grids come (the pictures held are kept).
                let drawn = state.halves_settings(settings);
                for (side, half_rect) in rects.into_iter().enumerate() {
                    painter.add(paint_callback(
                        half_rect,
                        CompareCallback {
                            side,
                            view: *render_view,
                            settings: drawn.clone(),
                        },
                    ));
                    // Its title and the colour key of what it draws, as saved pictures carry.
                    let cloud = if side == 0 { &clouds.0 } else { &clouds.1 };
                    let title = format!("{}: {}", ['A', letter][side], names[side]);
                    let legend = crate::picture::compare::half_legend(cloud, settings, &title);
                    let labels = state.labels.as_ref().filter(|_| self.settings.show_box);
                    crate::ui::legends::paint_with_labels(
                        painter, half_rect, view, labels, &legend,
                    );
                }
                if let Some(pos) = hover
                    && !view.moving
                {
                    let side = usize::from(pos.x >= rects[1].min.x);
                    let px = glam::Vec2::new(
                        (pos.x - rects[side].min.x) * ppp,
                        (pos.y - rects[side].min.y) * ppp,
                    );
                    let key = CompareHoverKey {
                        side,
                        px,
                        camera: view.camera,
                        size: (view.width, view.height),
                        letter,
                    };
                    let found = self.compare_hover.readings(&clouds, key, || {
                        compare_readings(&clouds, letter, side, view, px)
                    });
                    readings = Some((pos, found));
                }
            }
            CompareLayout::Difference => {
                painter.add(paint_callback(
                    rect,
                    CompareCallback {
                        side: 2,
                        view: *render_view,
                        settings: difference_settings(settings),
                    },
                ));
                if let Some(labels) = &state.labels
                    && self.settings.show_box
                {
                    labels::paint(painter, rect, view, labels);
                }
                paint_difference(
                    painter,
                    rect,
                    &difference_title(state, beside, matched, &names),
                    state.difference.as_ref().map(|c| (c.measure, c.range)),
                );
                if let Some(copy) = &state.difference
                    && let Some(pos) = hover
                    && !view.moving
                {
                    let px =
                        glam::Vec2::new((pos.x - rect.min.x) * ppp, (pos.y - rect.min.y) * ppp);
                    readings = Some((pos, difference_readings(&clouds.0, copy, view, px)));
                }
            }
            CompareLayout::Off => {}
        }
        if let Some((pos, lines)) = readings {
            paint_readings(painter, rect, pos, &lines);
        }
        // What the halves wait for, as the normal view shows it.
        if let Some(waiting) = state.badge(self.surface.busy, self.busy.as_deref()) {
            busy_badge(painter, rect, waiting);
        } else if state.scene_build.is_some() {
            busy_badge(painter, rect, crate::ui::compare_scene::PREPARING);
        } else if let Some(done) = self.refining {
            // The halves' points filling in at rest (`ui/compare_refine.rs`).
            let percent = (done * 100.0).floor();
            busy_badge(painter, rect, &format!("refining points… {percent:.0} %"));
        }
        true
    }
}

/// The difference's title: "C - A: c.wav against a.wav", and for the "matched" measure what
/// was matched: "C - A matched (C -3.8 dB to match A): ...".
fn difference_title(
    state: &CompareState,
    version: Listening,
    matched: bool,
    names: &[String; 2],
) -> String {
    let letter = version.letter();
    let words = state
        .alignment
        .match_words(version)
        .filter(|_| matched)
        .map_or_else(String::new, |words| format!(" matched ({words})"));
    format!("{letter} - A{words}: {} against {}", names[1], names[0])
}
