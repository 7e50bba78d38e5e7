//! What the window's offscreen target holds: the [`RenderKey`] of the last render (everything
//! a render of the scene depends on) and the [`FrameCache`] that compares a frame's key with it,
//! so frames that change only the panels, the hover read-out or a tooltip render no scene.
//! Used by the bridge (src/ui/bridge.rs) and the progressive points (src/ui/progressive.rs).

use crate::render::scene::RenderSettings;
use crate::view::frame_view::FrameView;

/// Everything a render of the scene depends on. Two frames with equal keys draw the same image
/// (the hover read-out, tooltips and panels are egui shapes over it, not part of it).
#[derive(Clone, Debug, PartialEq)]
pub struct RenderKey {
    pub camera: crate::view::camera::Camera,
    pub world_from_data: glam::Mat4,
    pub size: (u32, u32),
    pub moving: bool,
    pub settings: RenderSettings,
    pub cloud_id: Option<u64>,
    /// Bumped whenever a cloud's GPU data changes (upload, new grid, removal).
    pub revision: u64,
    /// Bumped whenever a cloud's points change on the GPU (upload, frequency axis, removal);
    /// `revision` unless the caller says ([`RenderKey::with_points_revision`]).
    pub points_revision: u64,
}

impl RenderKey {
    pub fn new(
        view: &FrameView,
        settings: &RenderSettings,
        cloud_id: Option<u64>,
        revision: u64,
    ) -> Self {
        Self {
            camera: view.camera,
            world_from_data: view.world_from_data,
            size: (view.width, view.height),
            moving: view.moving,
            settings: settings.clone(),
            cloud_id,
            revision,
            points_revision: revision,
        }
    }

    /// The key with the points' own revision (see [`FrameCache::points_revision`]).
    pub fn with_points_revision(mut self, points_revision: u64) -> Self {
        self.points_revision = points_revision;
        self
    }
}

/// The key of the last render and how many renders there were (the window shows the count's
/// rate; the tests check that a hover-only frame adds none).
#[derive(Debug, Default)]
pub struct FrameCache {
    last: Option<RenderKey>,
    /// Scene renders so far.
    pub renders: u64,
    /// GPU data revision: bumped by every change to a cloud's [`SceneData`].
    pub revision: u64,
    /// Points revision: bumped by every change to a cloud's points on the GPU (not by a grid
    /// or a surface built for another view, which leave the points as they are).
    pub points_revision: u64,
}

impl FrameCache {
    /// Whether a frame with `key` must render the scene (the target holds something else).
    /// Counts the render when it must.
    pub fn begin(&mut self, key: &RenderKey) -> bool {
        if self.last.as_ref() == Some(key) {
            return false;
        }
        self.renders += 1;
        true
    }

    /// Records what the target now holds; `complete` false when the render was one step of
    /// several (a slice of progressive points), so the next frame renders again.
    pub fn finish(&mut self, key: RenderKey, complete: bool) {
        self.last = complete.then_some(key);
    }

    /// The key of the scene the target holds complete (none while a progressive render is
    /// under way, or after an invalidation).
    pub fn holds(&self) -> Option<&RenderKey> {
        self.last.as_ref()
    }

    /// Forgets what the target holds (its size or contents changed outside a render).
    pub fn invalidate(&mut self) {
        self.last = None;
        self.revision += 1;
    }

    /// As [`FrameCache::invalidate`], the points changed too.
    pub fn invalidate_points(&mut self) {
        self.invalidate();
        self.points_revision += 1;
    }
}
