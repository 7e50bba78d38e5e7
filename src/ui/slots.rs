//! The window's two data slots (Song, Timeline): loading a file on a thread, installing it on
//! the GPU, and building its voxel grid when a view needs one.

use std::path::PathBuf;
use std::sync::Arc;
use std::sync::mpsc::channel;
use std::time::Duration;

use eframe::egui;
use eframe::egui_wgpu;

use crate::data::cloud::PointCloud;
use crate::render::scene::{ViewKind, world_from_data};
use crate::ui::bridge::ViewResources;
use crate::ui::labels;
use crate::ui::state::loading::Loading;
use crate::ui::state::{Loaded, LoudscapeApp, Slot};

impl LoudscapeApp {
    pub(super) fn start_loading(&mut self, path: PathBuf) {
        let (sender, receiver) = channel();
        let thread_path = path.clone();
        let shared = crate::ui::state::loading::Shared::default();
        let thread_shared = shared.clone();
        // Audio is extracted with the side panel's settings (`extract_settings.rs`).
        let settings = self.open.extract.next.clone();
        if crate::ui::extract_settings::named_like_audio(&path) {
            self.open.extract.shown = Some((path.clone(), settings.clone()));
        }
        std::thread::spawn(move || {
            let result = crate::ui::open::open_path(&thread_path, &settings, &thread_shared);
            let _ = sender.send(result);
        });
        self.loading.push(Loading {
            path,
            receiver,
            shared,
        });
    }

    pub(super) fn slot(&self, slot: Slot) -> Option<&Loaded> {
        match slot {
            Slot::Song => self.song.as_ref(),
            Slot::Timeline => self.timeline.as_ref(),
        }
    }

    pub(super) fn active(&self) -> Option<&Loaded> {
        self.slot(self.active)
    }

    /// Moves finished loads into their slots and uploads them.
    pub(super) fn poll_loading(&mut self, ctx: &egui::Context, frame: &eframe::Frame) {
        let mut finished = Vec::new();
        self.loading
            .retain(|loading| match loading.receiver.try_recv() {
                Ok(result) => {
                    finished.push((loading.path.clone(), result));
                    false
                }
                Err(std::sync::mpsc::TryRecvError::Empty) => true,
                Err(std::sync::mpsc::TryRecvError::Disconnected) => {
                    finished.push((loading.path.clone(), Err("the loader stopped".into())));
                    false
                }
            });
        if !self.loading.is_empty() {
            ctx.request_repaint_after(Duration::from_millis(50));
        }
        let Some(render_state) = frame.wgpu_render_state() else {
            return;
        };
        for (path, result) in finished {
            match result {
                Ok(cloud) => {
                    self.opened(&path, &cloud.path);
                    // What the extractor found wrong in the input, in sight (also in the
                    // side panel under the metrics).
                    let file = path.file_name().map_or_else(
                        || path.display().to_string(),
                        |n| n.to_string_lossy().into(),
                    );
                    for warning in cloud.warnings() {
                        let about = warning.path.as_deref().unwrap_or(&file);
                        self.messages.warn(format!("{about}: {}", warning.message));
                    }
                    self.install(render_state, cloud);
                }
                Err(message) => {
                    if message.contains(&path.display().to_string()) {
                        self.messages.error(message);
                    } else {
                        self.messages
                            .error(format!("{}: {message}", path.display()));
                    }
                }
            }
        }
    }

    pub(super) fn install(&mut self, render_state: &egui_wgpu::RenderState, cloud: PointCloud) {
        let slot = Slot::for_mode(cloud.meta.mode);
        let id = self.next_id;
        self.next_id += 1;
        if let Some(old) = self.slot(slot) {
            if old.cloud.path == cloud.path {
                // A re-extraction: the old cloud was shown until now.
                eprintln!(
                    "loudscape: {}: the new cloud ({} points) replaces the one shown ({} points)",
                    cloud.path.display(),
                    cloud.points.len(),
                    old.cloud.points.len()
                );
            }
            ViewResources::remove(render_state, old.id);
        }
        ViewResources::upload(render_state, id, &cloud);
        let (box_min, box_max) = crate::render::scene::data_box();
        let world_from_data = world_from_data(cloud.meta.mode);
        let labels = labels::axis_labels_for_box(&cloud, box_min, box_max);
        let loaded = Loaded {
            id,
            point_size: crate::render::points::PointStyle::size_for(cloud.points.len()),
            cloud: Arc::new(cloud),
            labels,
            world_from_data,
            world_box: crate::render::scene::world_box(world_from_data, box_min, box_max),
            cpu_grid: None,
            freq_axis: Default::default(),
            freq: None,
            view_points: None,
            view_points_pending: None,
        };
        if slot == Slot::Song {
            let remembered = self
                .audio_for
                .iter()
                .find(|(cloud, _)| {
                    std::path::absolute(&loaded.cloud.path).is_ok_and(|p| &p == cloud)
                })
                .map(|(_, audio)| audio.clone());
            self.audio.load_for(&loaded.cloud, remembered);
        } else {
            self.selected_song = None;
            self.hovered_song = None;
        }
        self.hover = None;
        match slot {
            Slot::Song => self.song = Some(loaded),
            Slot::Timeline => self.timeline = Some(loaded),
        }
        // A new cloud in this slot starts from its own fitted camera, not another slot's.
        self.motion.cloud_installed(self.active, slot);
        self.active = slot;
    }

    /// Builds the active cloud's voxel grid when the view needs one (only when the cloud or the
    /// grid settings changed), and reads it back once for hovering.
    pub(super) fn fetch_grid(&mut self, frame: &eframe::Frame) {
        if self.settings.view == ViewKind::Points {
            // A build announced before the switch to Points is not coming.
            if std::mem::take(&mut self.busy_shown) {
                self.busy = None;
            }
            return;
        }
        let Some(render_state) = frame.wgpu_render_state() else {
            return;
        };
        let voxels = self.settings.voxels;
        let slot = match self.active {
            Slot::Song => self.song.as_mut(),
            Slot::Timeline => self.timeline.as_mut(),
        };
        let Some(loaded) = slot else {
            return;
        };
        // Building a grid blocks the window for a while on slow devices: say so first, and
        // build on the next frame, once the notice is on screen.
        let needs_build =
            !ViewResources::grid_matches(render_state, loaded.id, &loaded.cloud, &voxels);
        if needs_build && !self.busy_shown {
            self.busy = Some("building the voxel grid…".into());
            self.busy_shown = true;
            self.needs_repaint = true;
            return;
        }
        // Its own notice only (the compare's may be on screen).
        if std::mem::take(&mut self.busy_shown) {
            self.busy = None;
        }
        let mut failure = None;
        match ViewResources::ensure_grid(render_state, loaded.id, &loaded.cloud, &voxels) {
            Ok(true) => loaded.cpu_grid = None,
            Ok(false) => {}
            Err(message) => failure = Some(message),
        }
        if loaded.cpu_grid.is_none() && ViewResources::has_grid(render_state, loaded.id) {
            loaded.cpu_grid = ViewResources::read_grid(render_state, loaded.id);
        }
        if let Some(message) = failure {
            self.messages.error(message);
        }
    }
}
