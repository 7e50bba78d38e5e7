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
use crate::ui::state::loading::{Loading, PreviewShown};
use crate::ui::state::{Loaded, LoudscapeApp, Slot};

impl LoudscapeApp {
    pub(super) fn start_loading(&mut self, path: PathBuf) {
        let (sender, receiver) = channel();
        let thread_path = path.clone();
        // A song extracted again keeps its old cloud on screen: no points while extracting.
        let shared = crate::ui::state::loading::Shared {
            preview: self.song.as_ref().is_none_or(|l| l.cloud.path != path),
            ..Default::default()
        };
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
        self.loading.push(Loading::new(path, receiver, shared));
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

    /// Moves finished loads into their slots and uploads them; shows the points so far of the
    /// songs still being extracted.
    pub(super) fn poll_loading(&mut self, ctx: &egui::Context, frame: &eframe::Frame) {
        let mut finished = Vec::new();
        self.loading
            .retain_mut(|loading| match loading.receiver.try_recv() {
                Ok(result) => {
                    finished.push((loading.path.clone(), result, loading.preview.take()));
                    false
                }
                Err(std::sync::mpsc::TryRecvError::Empty) => true,
                Err(std::sync::mpsc::TryRecvError::Disconnected) => {
                    let result = Err("the loader stopped".into());
                    finished.push((loading.path.clone(), result, loading.preview.take()));
                    false
                }
            });
        if !self.loading.is_empty() {
            ctx.request_repaint_after(Duration::from_millis(50));
        }
        let Some(render_state) = frame.wgpu_render_state() else {
            return;
        };
        for (path, result, preview) in finished {
            // The growing cloud of this song, if it is still the one in its slot.
            let preview = preview.filter(|p| self.song.as_ref().is_some_and(|l| l.id == p.id));
            match result {
                Ok(cloud) => {
                    self.opened(&path, &cloud);
                    let how = self.arrival(&path, Slot::for_mode(cloud.meta.mode));
                    // What the extractor found wrong in the input, in sight (also in the
                    // side panel under the metrics).
                    let file = path.file_name().map_or_else(
                        || path.display().to_string(),
                        |n| n.to_string_lossy().into(),
                    );
                    for warning in cloud.warnings() {
                        let about = warning.path.as_deref().unwrap_or(&file);
                        self.messages
                            .warn_about(&cloud.path, format!("{about}: {}", warning.message));
                    }
                    match preview {
                        Some(shown) => {
                            eprintln!(
                                "loudscape: {}: the whole cloud ({} points) replaces the {} \
                                 points shown while extracting",
                                path.display(),
                                cloud.points.len(),
                                shown.points
                            );
                            self.install_as(render_state, cloud, Install::Grown);
                        }
                        None => self.install_as(render_state, cloud, how),
                    }
                }
                Err(message) => {
                    if let Some(shown) = preview {
                        self.drop_preview(render_state, shown);
                    }
                    self.first_shown_failed(&path);
                    if message.contains(&path.display().to_string()) {
                        self.messages.error(message);
                    } else {
                        self.messages
                            .error(format!("{}: {message}", path.display()));
                    }
                }
            }
        }
        self.show_previews(render_state);
    }

    /// The newest points so far of each song being extracted, in the Song slot: the first
    /// ones replace what the slot showed (fitting the camera as any new cloud does: the axes
    /// are the final cloud's), later ones only grow it. A song extracted again with new
    /// settings keeps its old cloud on screen until the new one is whole.
    fn show_previews(&mut self, render_state: &egui_wgpu::RenderState) {
        for index in 0..self.loading.len() {
            let loading = &self.loading[index];
            let Some(cloud) = loading
                .shared
                .partial
                .lock()
                .ok()
                .and_then(|mut p| p.take())
            else {
                continue;
            };
            let grown = loading.preview.as_ref().map(|p| p.id);
            let shown = self.song.as_ref();
            if let Some(id) = grown {
                if shown.is_none_or(|l| l.id != id) {
                    // Something else was opened over it: the whole cloud comes as any other.
                    self.loading[index].preview = None;
                    continue;
                }
            } else if shown.is_some_and(|l| l.cloud.path == cloud.path) {
                continue;
            }
            let points = cloud.points.len();
            let replaced = match grown {
                Some(_) => None,
                None => self
                    .song
                    .as_ref()
                    .map(|l| (l.cloud.clone(), self.motion.camera())),
            };
            let how = if grown.is_some() {
                Install::Grown
            } else if self.first_shown.would_show(&loading.path, Slot::Song) {
                Install::New
            } else {
                // Of files opened together, another is shown first: its whole cloud comes
                // unseen.
                continue;
            };
            self.install_as(render_state, cloud, how);
            let id = self.next_id - 1;
            let loading = &mut self.loading[index];
            match &mut loading.preview {
                Some(preview) => {
                    preview.id = id;
                    preview.points = points;
                }
                None => {
                    eprintln!(
                        "loudscape: {}: first points shown while extracting: {points} points, \
                         {:.2} s after opening",
                        loading.path.display(),
                        loading.started.elapsed().as_secs_f32()
                    );
                    loading.preview = Some(PreviewShown {
                        id,
                        points,
                        replaced,
                    });
                }
            }
        }
    }

    /// Takes the points of a failed or cancelled extraction off the screen, and shows again
    /// what they replaced, with its camera.
    fn drop_preview(&mut self, render_state: &egui_wgpu::RenderState, shown: PreviewShown) {
        if let Some(old) = self.song.take() {
            ViewResources::write(render_state, |r| r.remove(old.id));
        }
        self.hover = None;
        match shown.replaced {
            Some((cloud, camera)) => {
                self.install(render_state, Arc::unwrap_or_clone(cloud));
                self.motion.restore(camera, 0);
            }
            None => {
                if self.timeline.is_some() {
                    self.motion.switch_slot(self.active, Slot::Timeline);
                    self.active = Slot::Timeline;
                }
            }
        }
    }

    /// Whether the Song slot shows the points of a song still being extracted.
    pub(super) fn previewing(&self) -> bool {
        self.song.as_ref().is_some_and(|l| {
            self.loading
                .iter()
                .any(|loading| loading.preview.as_ref().is_some_and(|p| p.id == l.id))
        })
    }

    /// How the loaded cloud of `path`, in `slot`, is installed: of files opened together, the
    /// one decided comes in sight (with the remembered camera if that is its slot's, else
    /// fitted), the others unseen.
    pub(super) fn arrival(&mut self, path: &std::path::Path, slot: Slot) -> Install {
        let restoring = self.first_shown.restoring();
        if !self.first_shown.arrived(path, slot) {
            return Install::Unseen;
        }
        if restoring.is_some_and(|r| r != slot) {
            self.motion.abandon_restore();
        }
        Install::New
    }

    pub(super) fn install(&mut self, render_state: &egui_wgpu::RenderState, cloud: PointCloud) {
        self.install_as(render_state, cloud, Install::New);
    }

    /// Shows `cloud` in place of its slot's (the same file, shifted to a level as heard): the
    /// slot in sight stays the one in sight, and a cloud waiting unseen stays unseen.
    pub(super) fn replace(&mut self, render_state: &egui_wgpu::RenderState, cloud: PointCloud) {
        if self.active == Slot::for_mode(cloud.meta.mode) {
            self.install_as(render_state, cloud, Install::New);
        } else {
            self.install_as(render_state, cloud, Install::Unseen);
            self.motion.forget_kept_load();
        }
    }

    /// Shows `cloud` in its slot. [`Install::Grown`] replaces the growing cloud of the same
    /// song: the camera, the active slot and the audio stay as they are.
    fn install_as(
        &mut self,
        render_state: &egui_wgpu::RenderState,
        cloud: PointCloud,
        how: Install,
    ) {
        let slot = Slot::for_mode(cloud.meta.mode);
        let id = self.next_id;
        self.next_id += 1;
        let mut same_audio = false;
        if let Some(old) = self.slot(slot) {
            if how == Install::New && old.cloud.path == cloud.path {
                // A re-extraction: the old cloud was shown until now.
                eprintln!(
                    "loudscape: {}: the new cloud ({} points) replaces the one shown ({} points)",
                    cloud.path.display(),
                    cloud.points.len(),
                    old.cloud.points.len()
                );
            }
            let source = |c: &PointCloud| c.meta.source.as_ref().and_then(|s| s.open_path());
            same_audio = source(&old.cloud).is_some() && source(&old.cloud) == source(&cloud);
            ViewResources::write(render_state, |r| r.remove(old.id));
        }
        ViewResources::write(render_state, |r| r.upload(id, &cloud));
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
            // The growing cloud of a song already loaded its audio (the same source).
            if !(how == Install::Grown && same_audio) {
                self.audio.load_for(&loaded.cloud);
            }
        } else {
            self.selected_song = None;
            self.hovered_song = None;
        }
        self.hover = None;
        match slot {
            Slot::Song => self.song = Some(loaded),
            Slot::Timeline => self.timeline = Some(loaded),
        }
        self.show_installed(slot, how);
    }

    /// A cloud was installed in `slot`: which slot is in sight, and the camera.
    pub(super) fn show_installed(&mut self, slot: Slot, how: Install) {
        if how == Install::Grown {
            // Fitted once, to the axes the growing cloud already had.
            return;
        }
        if how == Install::Unseen {
            // Another of the files opened together is shown first (`first_shown.rs`).
            if self.active == slot {
                self.active = slot.other();
            }
            return;
        }
        // A new cloud in this slot starts from its own fitted camera, not another slot's.
        self.motion.cloud_installed(self.active, slot);
        self.active = slot;
    }

    /// Builds the active cloud's voxel grid when the view needs one (only when the cloud or the
    /// grid settings changed), and reads it back once for hovering.
    pub(super) fn fetch_grid(&mut self, frame: &eframe::Frame) {
        // The compare draws its own grids in place of the Song slot's view.
        if self.settings.view == ViewKind::Points || self.compare_covers_view() {
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
        let previewing = self.active == Slot::Song && self.previewing();
        let slot = match self.active {
            Slot::Song => self.song.as_mut(),
            Slot::Timeline => self.timeline.as_mut(),
        };
        let Some(loaded) = slot else {
            return;
        };
        if previewing {
            // The points so far stand in (the scene draws points until a grid is built): a
            // grid blocks the window while it is built, and one of part of the song would
            // change with every new block; the whole cloud's comes once it is in.
            if std::mem::take(&mut self.busy_shown) {
                self.busy = None;
            }
            return;
        }
        // Building a grid blocks the window for a while on slow devices: say so first, and
        // build on the next frame, once the notice is on screen.
        let needs_build = ViewResources::read(render_state, |r| {
            !r.grid_matches(loaded.id, &loaded.cloud, &voxels)
        })
        .unwrap_or(false);
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
        // The build and the read-back for picking under one lock.
        let failure = ViewResources::write(render_state, |r| {
            let mut failure = None;
            match r.ensure_grid(loaded.id, &loaded.cloud, &voxels) {
                Ok(true) => loaded.cpu_grid = None,
                Ok(false) => {}
                Err(message) => failure = Some(message),
            }
            if loaded.cpu_grid.is_none() && r.has_grid(loaded.id) {
                loaded.cpu_grid = r.read_grid(loaded.id);
            }
            failure
        })
        .flatten();
        if let Some(message) = failure {
            self.messages.error(message);
        }
    }
}

/// How [`LoudscapeApp::install_as`] shows a cloud.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Install {
    /// A cloud new to its slot: the camera is fitted (or the remembered one kept), its audio
    /// loaded.
    New,
    /// A cloud new to its slot that is not shown: another of the files opened together is
    /// shown first, or the level as heard was applied to the slot not in sight.
    Unseen,
    /// More of the song the slot shows while it is extracted, or its whole cloud at the end:
    /// the camera and the audio stay.
    Grown,
}
