//! The window's two screenshot paths: "Save PNG" (the 3D view's picture at the 3D view's or a
//! chosen size, labels included) and the scripted `--screenshot` of the whole window (egui's
//! own, for tests), which closes the window once saved. Save PNG writes only to a `.png` name (a
//! video's name in the field saves nothing and says why) and never over a file this window did
//! not save in this run: a file already there that it did not make is kept, the PNG goes to
//! `name-2.png` beside it, and the status line says so (`state/written.rs`).
//!
//! The frame of the click draws no whole picture of a single cloud. At the view's size, in the
//! Points, Surface and Volume views, the save takes the view's own picture once it is complete
//! (`ViewResources::shown_picture`), waiting while the view fills in, moves or waits for a
//! surface (`state/save_wait.rs`, "saving … (waiting for the view to fill in)"). At a chosen
//! size it draws its own picture a slice of points or a band of the volume a frame
//! (`ui/save_slices.rs`). The A/B compare goes the same two ways, both halves at once
//! (`ui/compare_save.rs`). Either way the read-back is submitted and a thread waits for the
//! copy, draws the labels and writes the PNG (`state/picture_save.rs`), the status saying
//! "saving …" and then "saved …", so a large picture or a cloud of millions of points never
//! holds the window. One save at a time: a click while one is under way saves nothing and says
//! why.

use std::path::{Path, PathBuf};
use std::sync::atomic::Ordering;

use eframe::egui::{self, RichText};

use crate::picture::{PendingPicture, Wait};
use crate::ui::bridge::CompareResources;
use crate::ui::bridge::ViewResources;
use crate::ui::compare_shot::{CompareView, submit_compare_image};
use crate::ui::state::compare_window::CompareLayout;
use crate::ui::state::picture_save::{COPIED, PictureSave, RENDERED, SLICED};
use crate::ui::state::save_wait::{SaveWait, Sliced, WaitStep};
use crate::ui::state::written;
use crate::ui::state::{LoudscapeApp, Slot};

impl LoudscapeApp {
    pub(super) fn handle_screenshot(&mut self, ctx: &egui::Context) {
        let has_data = self.active().is_some();
        // B of a compare and work announced as blocking are waited for too.
        let waiting = self.timeline_listing()
            || !self.scripted_presses.is_empty()
            || self.reextracting()
            || self.previewing()
            || self.busy.is_some()
            || self.volume_hold.pending()
            || self.video_exporting()
            || self.saving_picture()
            || self.compare.as_ref().is_some_and(|c| c.settling());
        let Some(state) = self.screenshot.as_mut() else {
            return;
        };
        if state.done.load(Ordering::SeqCst) {
            ctx.send_viewport_cmd(egui::ViewportCommand::Close);
            return;
        }
        if waiting {
            // Wait for the tags of a timeline, the scripted key presses and a re-extraction.
            ctx.request_repaint();
            return;
        }
        if !has_data && self.loading.is_empty() && !self.messages.has_errors() {
            // Nothing to wait for: take the empty window.
        } else if !has_data {
            if self.messages.has_errors() {
                // Loading failed; still take the picture so the test sees the message.
            } else {
                ctx.request_repaint();
                return;
            }
        }
        state.frames_shown += 1;
        if state.frames_shown >= 3 && !state.requested {
            state.requested = true;
            let path = state.path.clone();
            let done = state.done.clone();
            let repaint = ctx.clone();
            ctx.request_screenshot(move |image| {
                if let Err(e) = save_color_image(&image, &path) {
                    eprintln!("loudscape: error: {}: {e}", path.display());
                }
                done.store(true, Ordering::SeqCst);
                repaint.request_repaint();
            });
        }
        ctx.request_repaint();
    }

    pub(super) fn screenshot_controls(&mut self, ui: &mut egui::Ui) {
        ui.label(RichText::new("Screenshot").strong());
        ui.horizontal_wrapped(|ui| {
            if ui
                .add_enabled(self.active().is_some(), egui::Button::new("Save PNG"))
                .on_hover_text(
                    "Ctrl+S (Cmd+S): the 3D view as a PNG, at the view's size or the size \
                     chosen here",
                )
                .on_disabled_hover_text("open a song or a cloud first")
                .clicked()
            {
                self.save_shot.requested = true;
            }
            ui.checkbox(&mut self.save_shot.custom_size, "size")
                .on_hover_text("save at a chosen size instead of the 3D view's");
        });
        if self.save_shot.custom_size {
            ui.horizontal_wrapped(|ui| {
                ui.add(egui::DragValue::new(&mut self.save_shot.size[0]).range(16..=8192));
                ui.label("×");
                ui.add(egui::DragValue::new(&mut self.save_shot.size[1]).range(16..=8192));
                ui.label("px");
            });
        }
        ui.add(
            egui::TextEdit::singleline(&mut self.save_shot.path)
                .hint_text("loudscape-<time>.png")
                .desired_width(ui.available_width().min(230.0)),
        )
        .on_hover_text(
            "where Save PNG writes: a .png name; a file this window did not save is kept, and \
             the picture goes to name-2.png beside it",
        );
        ui.add_space(4.0);
        ui.label(RichText::new("Video").strong());
        self.video_controls(ui);
    }

    /// Renders the current view offscreen (window size or the chosen size) and saves it.
    pub(super) fn save_screenshot(&mut self, ctx: &egui::Context, frame: &eframe::Frame) {
        let (Some(render_state), Some(mut view)) = (frame.wgpu_render_state(), self.last_view)
        else {
            return;
        };
        if self.active().is_none() {
            return;
        }
        let under_way = (self.save_shot.saving.as_ref().map(|s| &s.path)).or(self
            .save_shot
            .waiting
            .as_ref()
            .map(|w| &w.path));
        if let Some(path) = under_way {
            self.messages.error(format!(
                "Save PNG: still saving {}: nothing else saved until it is written",
                path.display()
            ));
            return;
        }
        if self.save_shot.custom_size {
            view.width = self.save_shot.size[0].max(1);
            view.height = self.save_shot.size[1].max(1);
        }
        // Ctrl+S and Save PNG ask where (native dialog, which asks before replacing a file)
        // unless the field names a file; where no dialog can open, the timestamped name in the
        // current folder. Only a .png name, and not over a file this window did not save.
        let mut no_dialog = false;
        let dialog_chose = self.open.save_to.clone();
        let wanted = if let Some(chosen) = self.open.save_to.take() {
            chosen
        } else if self.save_shot.path.trim().is_empty() {
            let name = crate::ui::screenshot::timestamped_name(std::time::SystemTime::now());
            if self.ask_where_to_save(&name) {
                return;
            }
            no_dialog = true;
            name
        } else {
            PathBuf::from(self.save_shot.path.trim())
        };
        let Ok(wanted) = written::of_kind(&wanted, "png") else {
            self.messages.error(format!(
                "Save PNG: {} is not a .png name: nothing saved (Save PNG writes PNG pictures; \
                 a video's name goes in the Video field)",
                wanted.display()
            ));
            return;
        };
        // The dialog asked before replacing the name it gave; a name it did not give (".png"
        // added) was not asked about.
        let (path, renamed) = if dialog_chose.as_ref() == Some(&wanted) {
            (wanted.clone(), false)
        } else {
            written::target(&wanted, &self.save_shot.made)
        };
        let mut notes = String::new();
        if renamed {
            notes += &format!(
                "; {} exists and this window did not save it, so it is kept",
                wanted.display()
            );
        }
        if no_dialog {
            notes += &format!("; {}", crate::ui::open::NO_DIALOG);
        }
        let Some(loaded) = self.active() else {
            return;
        };
        let what = self.compare_shown_as();
        let mut settings = self.settings.clone();
        settings.markers = self.markers();
        if what.is_none() {
            // At the view's size: the view's own picture once it is complete, waited for
            // while it fills in; at a chosen size: drawn for the save a slice a frame. Nothing
            // drawn whole for the picture in this frame either way.
            let mut wait = SaveWait::new(path.clone(), notes, loaded.id);
            if self.save_shot.custom_size {
                wait.sliced = Some(Box::new(Sliced::new(&render_state.device, view, settings)));
            }
            let sliced = wait.sliced.is_some();
            self.save_shot.waiting = Some(wait);
            self.step_save_wait(ctx, frame);
            if self.save_shot.waiting.is_some() {
                let shown = std::path::absolute(&path).unwrap_or(path);
                self.messages.info(format!(
                    "saving {}… ({})",
                    shown.display(),
                    if sliced {
                        "drawing it a part a frame"
                    } else {
                        "waiting for the view to fill in"
                    }
                ));
            }
            return;
        }
        // The compare the view shows (both halves, or the difference picture), labelled:
        // the view's own once complete, or drawn for the save over frames.
        if let Some(what) = what {
            let wait = SaveWait::new(path, notes, loaded.id);
            let size = self
                .save_shot
                .custom_size
                .then_some((view.width, view.height));
            self.start_compare_save(ctx, frame, wait, what, &view, size, settings);
        }
    }

    /// Once a frame while a save waits for the view (`state/save_wait.rs`), and in the frame
    /// of the click: the view's picture copied once it holds it complete, and its save
    /// started; else the wait goes on (the view fills in, moves or waits for a surface), or,
    /// the view still without giving it, the picture is rendered. Another cloud or the
    /// compare shown meanwhile ends the wait with nothing saved.
    pub(super) fn step_save_wait(&mut self, ctx: &egui::Context, frame: &eframe::Frame) {
        let Some(wait) = self.save_shot.waiting.as_mut() else {
            return;
        };
        if wait.compare.is_some() {
            self.step_compare_wait(ctx, frame);
            return;
        }
        let Some(render_state) = frame.wgpu_render_state() else {
            return;
        };
        if let Some(sliced) = wait.sliced.as_mut() {
            let id = wait.cloud;
            let loaded = self.song.iter().chain(&self.timeline).find(|l| l.id == id);
            let drawn = match loaded {
                Some(loaded) => {
                    crate::ui::save_slices::draw_next(render_state, sliced, id, &loaded.cloud)
                }
                None => Some((
                    Err(format!(
                        "Save PNG: the cloud was closed before {} was drawn: nothing saved",
                        wait.path.display()
                    )),
                    RENDERED,
                )),
            };
            match drawn {
                None => ctx.request_repaint(),
                Some((drawn, how)) => self.finish_wait(ctx, render_state, drawn, how),
            }
            return;
        }
        let Some(view) = self.last_view else {
            return;
        };
        let Some(wait) = self.save_shot.waiting.as_ref() else {
            return;
        };
        let same_cloud = self.active().is_some_and(|l| l.id == wait.cloud);
        let Some(loaded) = self
            .active()
            .filter(|_| same_cloud && self.compare_shown_as().is_none())
        else {
            if let Some(wait) = self.save_shot.waiting.take() {
                self.messages.error(format!(
                    "Save PNG: the view showed something else before it filled in: nothing \
                     saved to {}",
                    wait.path.display()
                ));
            }
            return;
        };
        let mut settings = self.settings.clone();
        settings.markers = self.markers();
        let settling = self.refining.is_some()
            || view.moving
            || self.surface.busy
            || self.volume_hold.pending()
            || self.busy.is_some();
        let shown =
            ViewResources::shown_picture(render_state, loaded.id, &loaded.cloud, &view, &settings);
        let (submitted, how) = match shown {
            Some(shown) => (shown.map_err(|e| e.to_string()), COPIED),
            None => {
                let step = self.save_shot.waiting.as_mut().map(|w| w.step(settling));
                if step != Some(WaitStep::Render) {
                    ctx.request_repaint();
                    return;
                }
                let Some(loaded) = self.active() else {
                    return;
                };
                let rendered = ViewResources::screenshot(
                    render_state,
                    loaded.id,
                    &loaded.cloud,
                    &view,
                    &settings,
                );
                (rendered.map_err(|e| e.to_string()), RENDERED)
            }
        };
        self.finish_wait(ctx, render_state, submitted, how);
    }

    /// The waiting save's picture is submitted (`how` it was made): its thread starts.
    pub(super) fn finish_wait(
        &mut self,
        ctx: &egui::Context,
        render_state: &eframe::egui_wgpu::RenderState,
        submitted: Result<PendingPicture, String>,
        how: &'static str,
    ) {
        let Some(wait) = self.save_shot.waiting.take() else {
            return;
        };
        match submitted {
            Ok(picture) => {
                let waited = Some((wait.since, wait.frames, how));
                self.start_save(ctx, render_state, wait.path, wait.notes, picture, waited);
            }
            Err(e) => self.messages.error(e),
        }
    }

    /// Once a frame: a save waiting for the view, a frame more.
    pub(super) fn poll_save_wait(&mut self, ctx: &egui::Context, frame: &eframe::Frame) {
        let Some(wait) = self.save_shot.waiting.as_mut() else {
            return;
        };
        wait.frame_drawn();
        self.step_save_wait(ctx, frame);
    }

    /// Starts the thread that reads `picture` back, draws its labels and writes it to `path`
    /// ("saving …"). `waited`: when the save waited for the view, since when, the frames
    /// drawn meanwhile and whether the picture is the view's own.
    fn start_save(
        &mut self,
        ctx: &egui::Context,
        render_state: &eframe::egui_wgpu::RenderState,
        path: PathBuf,
        notes: String,
        picture: PendingPicture,
        waited: Option<(std::time::Instant, u32, &'static str)>,
    ) {
        // The full path: a bare name lands in the folder the window was started from.
        let shown = std::path::absolute(&path).unwrap_or_else(|_| path.clone());
        self.messages.info(format!("saving {}…", shown.display()));
        let device = render_state.device.clone();
        let queue = render_state.queue.clone();
        let to = path.clone();
        let mut save = PictureSave::start(path, notes, move || {
            let size = picture.size();
            let image = picture
                .finish(&device, Wait::Polling(queue))
                .map_err(|e| format!("{}: {e}", to.display()))?;
            crate::ui::screenshot::save_png(&image, &to).map_err(|e| e.to_string())?;
            Ok(size)
        });
        if let Some((since, frames, how)) = waited {
            save = save.waited_since(since, frames);
            save.how = how;
        }
        self.save_shot.saving = Some(save);
        ctx.request_repaint();
    }

    /// Notes whether the view held its scene complete after the last frame (no refinement
    /// under way), for the scripted `when-drawn` press.
    pub(super) fn note_view_drawn(&mut self, frame: &eframe::Frame) {
        let holds = frame
            .wgpu_render_state()
            .and_then(|render_state| {
                ViewResources::read(render_state, |r| r.cache.holds().is_some())
            })
            .unwrap_or(false);
        self.save_shot.view_drawn = holds && self.refining.is_none() && self.active().is_some();
    }

    /// Once a frame: the window asked to close while a Save PNG is under way (waiting for the
    /// view to fill in, or being written) stays open until the PNG is written, the view going
    /// on filling in and the status saying so, then closes. A second close request closes at
    /// once, saying nothing was saved. (Dropping the waiting save would write nothing: the
    /// picture the user asked for, lost.)
    pub(super) fn close_after_save(&mut self, ctx: &egui::Context) {
        let asked = ctx.input(|i| i.viewport().close_requested());
        let pending = self.saving_picture();
        if asked && pending && !self.save_shot.closing {
            ctx.send_viewport_cmd(egui::ViewportCommand::CancelClose);
            self.save_shot.closing = true;
            let path = self
                .save_shot
                .waiting
                .as_ref()
                .map(|w| w.path.clone())
                .or_else(|| self.save_shot.saving.as_ref().map(|s| s.path.clone()))
                .unwrap_or_default();
            let shown = std::path::absolute(&path).unwrap_or(path);
            self.messages.info(format!(
                "closing once {} is saved (close again to quit without it)",
                shown.display()
            ));
            ctx.request_repaint();
        } else if asked && pending {
            if let Some(wait) = self.save_shot.waiting.take() {
                let shown = std::path::absolute(&wait.path).unwrap_or(wait.path);
                self.messages.error(format!(
                    "Save PNG: the window closed before the view filled in: nothing saved to {}",
                    shown.display()
                ));
            }
        } else if self.save_shot.closing && !pending {
            self.save_shot.closing = false;
            ctx.send_viewport_cmd(egui::ViewportCommand::Close);
        }
    }

    /// Whether a Save PNG waits for the view or is being read back or written.
    pub(super) fn saving_picture(&self) -> bool {
        self.save_shot.saving.is_some() || self.save_shot.waiting.is_some()
    }

    /// Once a frame: the Save PNG under way, told when it is done ("saved …").
    pub(super) fn poll_picture_save(&mut self, ctx: &egui::Context) {
        let Some(save) = self.save_shot.saving.as_mut() else {
            return;
        };
        let Some(finished) = save.poll() else {
            ctx.request_repaint_after(std::time::Duration::from_millis(30));
            return;
        };
        let Some(save) = self.save_shot.saving.take() else {
            return;
        };
        match finished.saved {
            Ok((width, height)) => {
                self.save_shot.made.record(&save.path);
                let shown = std::path::absolute(&save.path).unwrap_or(save.path.clone());
                self.messages.info(format!(
                    "saved {} ({}×{}){}",
                    shown.display(),
                    width,
                    height,
                    save.notes
                ));
                // A log line, as loads are told: tests read the frames.
                eprintln!(
                    "picture: saved in {:.0} ms on a thread ({}{}), while the window drew {} \
                     frames",
                    finished.took.as_secs_f64() * 1000.0,
                    save.how,
                    match (save.waited, save.how) {
                        (0, _) => String::new(),
                        (n, SLICED) => format!("; waited {n} frames for the slices"),
                        (n, _) => format!("; waited {n} frames for the view to fill in"),
                    },
                    finished.frames
                );
            }
            Err(e) => self.messages.error(e),
        }
        ctx.request_repaint();
    }

    /// The scripted `--press shot-size=WxH` of tests: Save PNG at that size; `shot-path=PATH`
    /// types PATH into the Screenshot field.
    pub(super) fn scripted_shot_size(&mut self, name: &str) -> bool {
        if let Some(path) = name.strip_prefix("shot-path=") {
            self.save_shot.path = path.to_string();
            return true;
        }
        let Some((w, h)) = name
            .strip_prefix("shot-size=")
            .and_then(|size| size.split_once('x'))
        else {
            return false;
        };
        if let (Ok(w), Ok(h)) = (w.parse::<u32>(), h.parse::<u32>()) {
            self.save_shot.custom_size = true;
            self.save_shot.size = [w.clamp(16, 8192), h.clamp(16, 8192)];
        }
        true
    }

    /// How the view shows the compare now, if it does.
    pub(super) fn compare_shown_as(&self) -> Option<CompareView> {
        let state = self.compare.as_ref().filter(|c| c.shown())?;
        if self.active != Slot::Song {
            return None;
        }
        match state.layout {
            CompareLayout::SideBySide => Some(CompareView::SideBySide(self.settings.view)),
            CompareLayout::Difference => Some(CompareView::Difference(state.measure)),
            CompareLayout::Off => None,
        }
    }
}

/// The compare rendered offscreen from the window's compare scene, as `loudscape render A
/// --compare B` draws it (titles, labels and colour keys included): a compare save whose view
/// stays still without giving its picture. Never with grids still to build: that is the
/// view's work, in the background.
pub(super) fn compare_screenshot(
    render_state: &eframe::egui_wgpu::RenderState,
    what: CompareView,
    camera: crate::view::camera::Camera,
    size: (u32, u32),
    settings: &crate::render::scene::RenderSettings,
) -> anyhow::Result<PendingPicture> {
    CompareResources::write(render_state, |compare, view| {
        let scene = compare
            .scene
            .as_mut()
            .ok_or_else(|| anyhow::anyhow!("the compare is not ready yet"))?;
        let needs_grids = what != CompareView::SideBySide(crate::render::scene::ViewKind::Points);
        if needs_grids && !scene.grids_built_for(&settings.voxels) {
            anyhow::bail!("the compare's grids are not built yet");
        }
        let gpu = crate::render::gpu::context::GpuContext {
            adapter: render_state.adapter.clone(),
            device: render_state.device.clone(),
            queue: render_state.queue.clone(),
        };
        submit_compare_image(
            &gpu,
            &view.renderer,
            scene,
            what,
            Some(camera),
            size,
            settings,
            settings.show_box,
            None,
            None,
        )
    })
    .unwrap_or_else(|| Err(anyhow::anyhow!("the compare is not ready yet")))
}

pub(super) fn save_color_image(image: &egui::ColorImage, path: &Path) -> anyhow::Result<()> {
    let [w, h] = image.size;
    let mut rgba = Vec::with_capacity(w * h * 4);
    for pixel in &image.pixels {
        rgba.extend_from_slice(&pixel.to_array());
    }
    let img = image::RgbaImage::from_raw(w as u32, h as u32, rgba)
        .ok_or_else(|| anyhow::anyhow!("screenshot has the wrong size"))?;
    Ok(crate::ui::screenshot::save_png(&img, path)?)
}
