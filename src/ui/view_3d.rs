//! The 3D view of one frame, in named steps: its size (and a fit waiting for it), the camera
//! input, the pace (what a moving frame draws, the surface's level of detail, the frames motion
//! asks for), the hover and clicks, the draw (the scene's paint callback, or the compare's) and
//! the overlays painted over the scene (labels, legend, read-out, surface notices, busy badge).
//! The state each step updates owns its rules: `state/view_motion.rs` (camera, fit, motion,
//! moving budget) and `state/surface_status.rs` (the surface's level of detail).

use std::time::Instant;

use eframe::egui::{self, Color32};

use crate::render::scene::ViewKind;
use crate::ui::app::last_frame_ms;
use crate::ui::bridge::{ViewCallback, paint_callback};
use crate::ui::hover::paint_readings;
use crate::ui::labels;
use crate::ui::shortcuts::{self, Action};
use crate::ui::state::view_motion::{CameraInput, Drag, FitBox};
use crate::ui::state::{LoudscapeApp, Slot};
use crate::view::frame_view::FrameView;

/// Points between the two halves of the side-by-side view.
pub(super) const GAP: f32 = 4.0;

impl LoudscapeApp {
    /// The 3D view: the central panel's whole area.
    pub(super) fn view_3d(&mut self, ui: &mut egui::Ui) {
        let ctx = ui.ctx().clone();
        let rect = ui.available_rect_before_wrap();
        let response = ui.allocate_rect(rect, egui::Sense::click_and_drag());
        let (width, height) = self.size_view(&ctx, rect);
        let moving = self.camera_input(&ctx, &response, height);
        self.pace(&ctx, moving);
        let view = FrameView {
            camera: self.motion.camera(),
            world_from_data: self
                .active()
                .map_or(glam::Mat4::IDENTITY, |l| l.world_from_data),
            width,
            height,
            frame_index: self.clock.next_index(),
            moving,
        };
        self.last_view = Some(view);
        self.hover_and_click(&ctx, &response, rect, &view);
        let painter = ui.painter_at(rect);
        let hover = response.hover_pos();
        if self.draw(&painter, rect, &view, hover) {
            self.overlays(&painter, rect, &view, hover);
        }
    }

    /// What a fit frames: the active cloud's box, one step farther for a side-by-side half.
    pub(super) fn fit_target(&self) -> Option<FitBox> {
        let (min, max) = self.active()?.world_box;
        Some(FitBox {
            min,
            max,
            half: self.compare.as_ref().is_some_and(|c| c.side_by_side()),
        })
    }

    /// The view's size in pixels, a half's in a side-by-side compare (one camera for both);
    /// the camera is fitted to it when a fit waits or the size changed under a fitted camera.
    fn size_view(&mut self, ctx: &egui::Context, rect: egui::Rect) -> (u32, u32) {
        let ppp = ctx.pixels_per_point();
        let view_width = match &self.compare {
            Some(c) if c.side_by_side() && self.active == Slot::Song => (rect.width() - GAP) / 2.0,
            _ => rect.width(),
        };
        let width = (view_width * ppp).round().max(1.0) as u32;
        let height = (rect.height() * ppp).round().max(1.0) as u32;
        self.view_px = ((rect.width() * ppp).round().max(1.0) as u32, height);
        let target = self.fit_target();
        let heights = (rect.height(), ctx.content_rect().height());
        self.motion
            .size_view_within(width as f32 / height as f32, target, Some(heights));
        (width, height)
    }

    /// Drags orbit (primary) or pan (secondary, middle), the wheel zooms over the view, F fits
    /// and R resets; returns whether the view is moving.
    fn camera_input(
        &mut self,
        ctx: &egui::Context,
        response: &egui::Response,
        height: u32,
    ) -> bool {
        let delta = response.drag_delta() * ctx.pixels_per_point();
        let drag = if response.dragged_by(egui::PointerButton::Primary) {
            Some(Drag::Orbit(delta.x, delta.y))
        } else if response.dragged_by(egui::PointerButton::Secondary)
            || response.dragged_by(egui::PointerButton::Middle)
        {
            Some(Drag::Pan(delta.x, delta.y))
        } else {
            None
        };
        let scroll = if response.hovered() {
            ctx.input(|i| i.smooth_scroll_delta.y)
        } else {
            0.0
        };
        let input = CameraInput {
            drag,
            scroll,
            fit: shortcuts::pressed(ctx, Action::Fit),
            reset: shortcuts::pressed(ctx, Action::ResetView),
        };
        let target = self.fit_target();
        self.motion
            .input(&input, height as f32, target, Instant::now())
    }

    /// The frame's pace: while moving, the points' subset or the grid view's resolution follows
    /// the device; the surface's level of detail; another frame while moving and once more when
    /// the camera settles.
    fn pace(&mut self, ctx: &egui::Context, moving: bool) {
        let frame_ms = last_frame_ms(ctx);
        if moving {
            self.motion.pace(self.settings.view, frame_ms);
        }
        self.surface
            .choose_detail(self.settings.view == ViewKind::Surface, moving, frame_ms);
        if self.motion.wants_frame(moving) {
            ctx.request_repaint();
        }
    }

    /// What is under the cursor (at rest), and a click's seek or selection.
    fn hover_and_click(
        &mut self,
        ctx: &egui::Context,
        response: &egui::Response,
        rect: egui::Rect,
        view: &FrameView,
    ) {
        let ppp = ctx.pixels_per_point();
        let hover_px = response
            .hover_pos()
            .map(|p| glam::Vec2::new((p.x - rect.min.x) * ppp, (p.y - rect.min.y) * ppp));
        let song_before = self.hovered_song;
        self.update_hover(hover_px, view, view.moving);
        if self.hovered_song != song_before {
            // The side panel, drawn before the view, shows the new song next frame.
            ctx.request_repaint();
        }
        let compare_shown = self.compare.as_ref().is_some_and(|c| c.shown());
        if response.clicked() && !compare_shown {
            self.click();
        }
        if response.clicked() || response.secondary_clicked() {
            // What the click changed (the seek position, the selected song) shows at once.
            ctx.request_repaint();
        }
    }

    /// This frame's step of a switch to Volume (`state/volume_hold.rs`): its notice in the
    /// view's corner put up or taken away.
    pub(super) fn step_volume_hold(&mut self, ctx: &egui::Context) {
        if self.compare_covers_view() || self.active().is_none() {
            self.volume_hold.forget();
            return;
        }
        self.volume_hold.step(
            self.settings.view,
            self.busy.is_none(),
            self.refining.is_some(),
        );
        if self.volume_hold.pending() {
            ctx.request_repaint();
        }
    }

    /// The scene's paint callback with this frame's markers and moving budget (a moving frame
    /// of the Volume and Surface views at a reduced resolution), or the compare's when it is
    /// shown. Returns whether the scene was drawn (the compare paints its own overlays).
    fn draw(
        &mut self,
        painter: &egui::Painter,
        rect: egui::Rect,
        view: &FrameView,
        hover: Option<egui::Pos2>,
    ) -> bool {
        let mut settings = self.settings.clone();
        settings.markers = self.markers();
        if self.settings.view == ViewKind::Points {
            settings.points.max_points_moving = self.motion.moving_points();
        }
        if self.settings.view == ViewKind::Surface {
            settings.surface_detail = self.surface.detail();
        }
        let mut render_view = *view;
        if view.moving && self.settings.view != ViewKind::Points {
            let divisor = self.motion.moving_divisor(self.settings.view);
            render_view.width = view.width.div_ceil(divisor).max(1);
            render_view.height = view.height.div_ceil(divisor).max(1);
        }
        if self.paint_compare(painter, rect, view, &render_view, &settings, hover) {
            return false;
        }
        let hand = painter.ctx().input(|i| {
            i.pointer.delta() != egui::Vec2::ZERO
                || i.pointer.any_down()
                || i.events.iter().any(|e| {
                    matches!(
                        e,
                        egui::Event::Key { .. }
                            | egui::Event::MouseWheel { .. }
                            | egui::Event::PointerButton { .. }
                            | egui::Event::Zoom(_)
                            | egui::Event::Touch { .. }
                    )
                })
        });
        let callback = ViewCallback {
            view: render_view,
            settings,
            cloud_id: self.active().map(|l| l.id),
            refine_target: self.motion.refine_target(hand, Instant::now()),
        };
        painter.add(paint_callback(rect, callback));
        true
    }

    /// Over the scene: the axis labels, the legend of saved pictures, the read-out at rest, the
    /// surface's notices; the hint to drop a file when nothing is shown.
    fn overlays(
        &self,
        painter: &egui::Painter,
        rect: egui::Rect,
        view: &FrameView,
        hover: Option<egui::Pos2>,
    ) {
        let Some(loaded) = self.active() else {
            let text = if self.loading.is_empty() {
                "Drop a song or a loudscape .ply file here, or run: loudscape song.ogg [timeline.ply]"
            } else {
                "Loading…"
            };
            painter.text(
                rect.center(),
                egui::Align2::CENTER_CENTER,
                text,
                egui::FontId::proportional(18.0),
                Color32::from_gray(170),
            );
            return;
        };
        // The same labels and legend as saved pictures carry (name, colour key): those of the
        // points while they stand in for a surface or a volume (a song still extracted).
        let legend = shown_legend(&loaded.cloud, &self.settings, self.previewing());
        let labels = self.settings.show_box.then_some(&loaded.labels);
        crate::ui::legends::paint_with_labels(painter, rect, view, labels, &legend);
        // While the camera moves the read-out would describe where the cursor was.
        if let (Some((_, hover)), Some(pos), false) = (&self.hover, hover, view.moving) {
            paint_readings(painter, rect, pos, &hover.readings);
        }
        let surface = &self.surface;
        if self.settings.view == ViewKind::Surface && surface.empty && !surface.busy {
            // In the view, not only under the slider, whose tooltip covered it.
            painter.text(
                rect.center(),
                egui::Align2::CENTER_CENTER,
                format!(
                    "no surface at isovalue {:.2}: the density crosses it nowhere; lower it",
                    self.settings.surface.iso_value
                ),
                egui::FontId::proportional(16.0),
                crate::ui::style::WARNING,
            );
        }
        if surface.busy {
            busy_badge(painter, rect, "extracting surface…");
        } else if let Some(drawing) = self.volume_hold.corner(self.settings.view, self.refining) {
            busy_badge(painter, rect, &drawing);
        } else if let Some(done) = self.refining {
            let percent = (done * 100.0).floor();
            busy_badge(painter, rect, &format!("refining points… {percent:.0} %"));
        }
    }
}

/// The legend of what the view draws: the points' while a song's points stand in for its
/// surface or volume (`previewing`: it is still extracted, no grid is built meanwhile).
fn shown_legend(
    cloud: &crate::data::cloud::PointCloud,
    settings: &crate::render::scene::RenderSettings,
    previewing: bool,
) -> crate::annotate::legend::PictureLegend {
    if settings.view == ViewKind::Points || !previewing {
        return crate::ui::legends::picture_legend(cloud, settings);
    }
    let mut points = settings.clone();
    points.view = ViewKind::Points;
    let mut legend = crate::ui::legends::picture_legend(cloud, &points);
    legend.detail = "points until the whole song is in".into();
    legend
}

/// A spinner and `text` in the bottom-left corner of the 3D view, over a dark plate.
pub(super) fn busy_badge(painter: &egui::Painter, rect: egui::Rect, text: &str) {
    let font = egui::FontId::proportional(14.0);
    let galley = painter.layout_no_wrap(text.into(), font, Color32::from_gray(220));
    let spinner = 14.0;
    // Bottom left: the view's title and the colour key hold the top corners.
    let origin = egui::pos2(
        rect.min.x + 12.0,
        rect.max.y - 15.0 - galley.size().y.max(spinner),
    );
    let plate = egui::Rect::from_min_size(
        origin,
        egui::vec2(
            spinner + 8.0 + galley.size().x,
            galley.size().y.max(spinner),
        ),
    )
    .expand(5.0);
    painter.rect_filled(plate, 4.0, labels::LABEL_PLATE);
    // The spinner: an arc turning with time (egui's Spinner needs a Ui of its own).
    let time = painter.ctx().input(|i| i.time);
    let centre = origin + egui::vec2(spinner * 0.5, plate.height() * 0.5 - 5.0);
    let start = time * 4.0;
    let points: Vec<egui::Pos2> = (0..=20)
        .map(|i| {
            let angle = start + f64::from(i) / 20.0 * std::f64::consts::PI * 1.5;
            centre + spinner * 0.45 * egui::vec2(angle.cos() as f32, angle.sin() as f32)
        })
        .collect();
    painter.add(egui::Shape::line(
        points,
        egui::Stroke::new(2.0, Color32::from_rgb(230, 190, 110)),
    ));
    painter.galley(
        origin
            + egui::vec2(
                spinner + 8.0,
                (plate.height() - 10.0 - galley.size().y) * 0.5,
            ),
        galley,
        Color32::from_gray(220),
    );
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::cloud::{DataMode, PointCloud};
    use crate::render::scene::RenderSettings;

    #[test]
    fn points_standing_in_for_a_surface_are_named_as_points() {
        let cloud = PointCloud::synthetic(
            crate::data::synthetic::synthetic_song(1_000, 3),
            DataMode::Song,
        );
        let surface = RenderSettings {
            view: ViewKind::Surface,
            ..Default::default()
        };
        let standing_in = shown_legend(&cloud, &surface, true);
        let points = shown_legend(&cloud, &RenderSettings::default(), true);
        assert_eq!(standing_in.key, points.key, "the points' colour key");
        assert_eq!(standing_in.detail, "points until the whole song is in");
        let built = shown_legend(&cloud, &surface, false);
        assert_ne!(
            built.key, points.key,
            "the surface's own key once it is built"
        );
    }
}
