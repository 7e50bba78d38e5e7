//! The orbit camera: a turntable trackball around a target point.
//!
//! Left drag orbits (azimuth about the vertical axis, elevation above the horizon), right or
//! middle drag pans the target in the view plane, the wheel zooms along the view direction.
//! `fit` frames an axis-aligned box so the whole of it is in view, whatever the aspect ratio.
//! Angles are in degrees at the edges (command line, saved state) and radians inside.

use glam::{Mat4, Vec3};

/// Vertical field of view in degrees.
pub const FOV_Y_DEGREES: f32 = 35.0;
const MIN_DISTANCE: f32 = 0.05;
const MAX_DISTANCE: f32 = 200.0;
const MAX_ELEVATION: f32 = 89.0_f32 * std::f32::consts::PI / 180.0;

#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Camera {
    /// The point orbited around, in world space.
    pub target: Vec3,
    /// Angle about the world's vertical (+y) axis, radians; 0 looks along -z.
    pub azimuth: f32,
    /// Angle above the horizon, radians.
    pub elevation: f32,
    /// Distance from target to eye.
    pub distance: f32,
}

impl Default for Camera {
    fn default() -> Self {
        Self {
            target: Vec3::ZERO,
            azimuth: (-35.0_f32).to_radians(),
            elevation: 25.0_f32.to_radians(),
            distance: 4.0,
        }
    }
}

impl Camera {
    /// A camera from the command line's `AZ,EL,DIST` (degrees, degrees, world units).
    pub fn from_angles(azimuth_degrees: f32, elevation_degrees: f32, distance: f32) -> Self {
        let mut camera = Self {
            azimuth: azimuth_degrees.to_radians(),
            elevation: elevation_degrees.to_radians(),
            distance,
            ..Self::default()
        };
        camera.clamp();
        camera
    }

    /// Unit vector from the target toward the eye.
    pub fn back(&self) -> Vec3 {
        let (sin_az, cos_az) = self.azimuth.sin_cos();
        let (sin_el, cos_el) = self.elevation.sin_cos();
        Vec3::new(sin_az * cos_el, sin_el, cos_az * cos_el)
    }

    pub fn eye(&self) -> Vec3 {
        self.target + self.back() * self.distance
    }

    pub fn view(&self) -> Mat4 {
        Mat4::look_at_rh(self.eye(), self.target, Vec3::Y)
    }

    /// Near and far planes that keep a scene of the given radius around the target in view.
    fn clip_planes(&self) -> (f32, f32) {
        let near = (self.distance * 0.01).max(0.001);
        let far = self.distance * 4.0 + 20.0;
        (near, far)
    }

    pub fn projection(&self, aspect: f32) -> Mat4 {
        let (near, far) = self.clip_planes();
        Mat4::perspective_rh(FOV_Y_DEGREES.to_radians(), aspect.max(1e-3), near, far)
    }

    pub fn view_projection(&self, aspect: f32) -> Mat4 {
        self.projection(aspect) * self.view()
    }

    /// Orbits by a drag of `dx`, `dy` pixels in a view `height` pixels tall.
    pub fn orbit(&mut self, dx: f32, dy: f32, height: f32) {
        let radians_per_pixel = std::f32::consts::PI / height.max(1.0);
        self.azimuth -= dx * radians_per_pixel;
        self.elevation += dy * radians_per_pixel;
        self.clamp();
    }

    /// Pans the target so the point under the cursor follows a drag of `dx`, `dy` pixels.
    pub fn pan(&mut self, dx: f32, dy: f32, height: f32) {
        let world_per_pixel =
            2.0 * self.distance * (FOV_Y_DEGREES.to_radians() * 0.5).tan() / height.max(1.0);
        let back = self.back();
        let right = Vec3::Y.cross(back).normalize_or_zero();
        let up = back.cross(right);
        self.target += (-dx * right + dy * up) * world_per_pixel;
    }

    /// Zooms by `steps` wheel notches (positive moves closer).
    pub fn zoom(&mut self, steps: f32) {
        self.distance *= 0.9_f32.powf(steps);
        self.clamp();
    }

    /// Frames the box `[min, max]` so all of it is visible at the given aspect ratio, keeping the
    /// current viewing direction.
    pub fn fit(&mut self, min: Vec3, max: Vec3, aspect: f32) {
        let center = (min + max) * 0.5;
        let radius = ((max - min) * 0.5).length().max(1e-3);
        let half_fov_y = FOV_Y_DEGREES.to_radians() * 0.5;
        let half_fov_x = (half_fov_y.tan() * aspect.max(1e-3)).atan();
        let half_fov = half_fov_y.min(half_fov_x);
        self.target = center;
        self.distance = radius / half_fov.sin() * 1.02;
        self.clamp();
    }

    fn clamp(&mut self) {
        self.elevation = self.elevation.clamp(-MAX_ELEVATION, MAX_ELEVATION);
        self.distance = self.distance.clamp(MIN_DISTANCE, MAX_DISTANCE);
        self.azimuth = self.azimuth.rem_euclid(std::f32::consts::TAU);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fit_keeps_every_corner_in_view() {
        for aspect in [0.5_f32, 1.0, 16.0 / 9.0, 3.0] {
            let mut camera = Camera::default();
            let (min, max) = (Vec3::new(-2.5, -1.0, -1.0), Vec3::new(2.5, 1.0, 1.0));
            camera.fit(min, max, aspect);
            let view_proj = camera.view_projection(aspect);
            for i in 0..8 {
                let corner = Vec3::new(
                    if i & 1 == 0 { min.x } else { max.x },
                    if i & 2 == 0 { min.y } else { max.y },
                    if i & 4 == 0 { min.z } else { max.z },
                );
                let clip = view_proj.project_point3(corner);
                assert!(
                    clip.x.abs() <= 1.0 && clip.y.abs() <= 1.0,
                    "{aspect}: {clip}"
                );
                assert!((0.0..=1.0).contains(&clip.z), "{aspect}: depth {clip}");
            }
        }
    }

    #[test]
    fn orbit_and_zoom_stay_in_bounds() {
        let mut camera = Camera::default();
        camera.orbit(0.0, 1e6, 100.0);
        assert!(camera.elevation <= MAX_ELEVATION);
        camera.zoom(1e4);
        assert!(camera.distance >= MIN_DISTANCE);
        camera.zoom(-1e4);
        assert!(camera.distance <= MAX_DISTANCE);
    }

    #[test]
    fn pan_moves_target_in_view_plane() {
        let mut camera = Camera::default();
        let before = camera.target;
        camera.pan(10.0, 0.0, 100.0);
        let moved = camera.target - before;
        assert!(moved.length() > 0.0);
        assert!(moved.dot(camera.back()).abs() < 1e-5);
    }
}
