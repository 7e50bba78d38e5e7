//! The point of view a frame is drawn from: the camera, the stretch from data to world space,
//! the size in pixels and whether the camera moves. No GPU: the passes turn it into uniforms
//! (`render::gpu::frame`), picking and labels project through it.

use glam::{Mat4, Vec3};

use crate::view::camera::Camera;

/// Everything about the point of view that a pass may need.
#[derive(Clone, Copy, Debug)]
pub struct FrameView {
    pub camera: Camera,
    /// World space from data space: scales the normalized cloud (a timeline is wider than tall).
    pub world_from_data: Mat4,
    pub width: u32,
    pub height: u32,
    /// Counts frames; seeds the volume's ray jitter.
    pub frame_index: u32,
    /// True while the camera moves: passes may trade quality for speed.
    pub moving: bool,
}

impl FrameView {
    pub fn aspect(&self) -> f32 {
        self.width as f32 / self.height.max(1) as f32
    }

    pub fn clip_from_data(&self) -> Mat4 {
        self.camera.view_projection(self.aspect()) * self.world_from_data
    }

    /// Pixel position (origin top left) of a data-space point, or None behind the camera.
    pub fn project(&self, data: Vec3) -> Option<glam::Vec2> {
        let clip = self.clip_from_data() * data.extend(1.0);
        if clip.w <= 1e-6 {
            return None;
        }
        let ndc = clip.truncate() / clip.w;
        Some(glam::Vec2::new(
            (ndc.x * 0.5 + 0.5) * self.width as f32,
            (0.5 - ndc.y * 0.5) * self.height as f32,
        ))
    }
}

impl FrameView {
    /// A view from `camera` at rest (frame 0, not moving).
    pub fn at_rest(camera: Camera, world_from_data: Mat4, width: u32, height: u32) -> Self {
        Self {
            camera,
            world_from_data,
            width,
            height,
            frame_index: 0,
            moving: false,
        }
    }

    /// A view at rest from `camera` moved to frame `world_box` (min, max in world space) at this
    /// size's aspect ratio.
    pub fn fitted(
        mut camera: Camera,
        world_from_data: Mat4,
        world_box: (Vec3, Vec3),
        width: u32,
        height: u32,
    ) -> Self {
        let (min, max) = world_box;
        camera.fit(min, max, width as f32 / height as f32);
        Self::at_rest(camera, world_from_data, width, height)
    }
}
