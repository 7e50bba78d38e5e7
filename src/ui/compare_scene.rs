//! The compare's scene prepared on a thread: the version beside A moved onto A's time and
//! matched in loudness (`compare_align::aligned_b`), both clouds moved onto the union of their
//! axes, and the axis labels. With a song of millions of points as A that is a copy of every
//! point of both, which used to hold the window each time the alignment came, a version was
//! nudged or "match loudness" was switched; the window now keeps drawing the scene it has (its
//! badge says so), and the frame the prepared clouds come in uploads them (`poll_compare`).
//! What waits for them is `state/compare_scene.rs`. The thread also makes the copies the
//! window keeps (the scene's and the read-outs') and fills both clouds' GPU point buffers, so
//! the frame the answer comes in only adds their bind groups: that frame used to copy and
//! upload both clouds, 195 ms with a 3.5 M-point A on lavapipe.

use std::sync::Arc;
use std::sync::mpsc::channel;
use std::time::Instant;

use crate::data::cloud::PointCloud;
use crate::data::compare::on_union_axes;
use crate::render::points::PointsGpu;
use crate::ui::compare_align::BMoves;
use crate::ui::labels;
use crate::ui::state::alignment::CompareAlignment;
use crate::ui::state::compare_scene::{Prepared, SceneBuild};
use crate::ui::state::compare_window::Listening;

/// What the badge over the compare says while its scene is prepared.
pub(super) const PREPARING: &str = "moving the versions onto one time and level…";

/// Starts preparing A (`a`) and `b` (the version `beside`, aligned by `alignment` and matched
/// in loudness when `matched`) on a thread, their point buffers made on `device`; `first`: the
/// first scene of this A.
pub(super) fn start(
    device: wgpu::Device,
    a: Arc<PointCloud>,
    b: Arc<PointCloud>,
    alignment: &CompareAlignment,
    beside: Listening,
    matched: bool,
    first: bool,
) -> SceneBuild {
    // What aligned_b reads of the alignment, taken here: the thread owns its copy.
    let moves = BMoves::of(alignment, beside, matched);
    let (sender, receiver) = channel();
    let spawned = std::thread::Builder::new()
        .name("compare-scene".into())
        .spawn(move || {
            let started = Instant::now();
            let b = moves.apply(&b);
            let prepared = on_union_axes(&a, &b)
                .map(|(a, b)| {
                    let labels = labels::axis_labels_for_box(
                        &a,
                        glam::Vec3::splat(-1.0),
                        glam::Vec3::splat(1.0),
                    );
                    let limit = PointsGpu::chunk_limit(&device);
                    let buffers =
                        [&a, &b].map(|cloud| PointsGpu::buffers(&device, &cloud.points, limit));
                    let shared = Arc::new((a.clone(), b.clone()));
                    Prepared {
                        clouds: (a, b),
                        shared,
                        buffers,
                        labels,
                        took: started.elapsed(),
                    }
                })
                .map_err(|e| e.to_string());
            let _ = sender.send(prepared);
        });
    // No thread: the receiver's sender is gone, which `SceneBuild::poll` tells as an error.
    if let Err(e) = spawned {
        log::warn!("no thread for the compare's scene: {e}");
    }
    SceneBuild::new(receiver, first)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::cloud::DataMode;
    use crate::data::synthetic::synthetic_song;
    use crate::render::compare::CompareScene;
    use crate::render::gpu::context::GpuContext;
    use crate::render::grid::voxelize::VoxelSettings;
    use crate::render::scene::Renderer;
    use std::time::Duration;

    /// The thread's answer is what the window built on its own thread before: A and B (not
    /// aligned yet: no comparison has come) moved onto their union axes, with that box's
    /// labels, the copy the window keeps, and GPU buffers that hold exactly those points.
    #[test]
    fn the_prepared_scene_is_the_union_of_a_and_b() {
        let gpu = GpuContext::new_headless().expect("a GPU adapter (lavapipe will do)");
        let a = Arc::new(PointCloud::synthetic(
            synthetic_song(5_000, 3),
            DataMode::Song,
        ));
        let b = Arc::new(PointCloud::synthetic(
            synthetic_song(2_000, 5),
            DataMode::Song,
        ));
        let build = start(
            gpu.device.clone(),
            a.clone(),
            b.clone(),
            &CompareAlignment::default(),
            Listening::B,
            false,
            true,
        );
        assert!(build.first);
        let deadline = Instant::now() + Duration::from_secs(60);
        let prepared = loop {
            if let Some(answer) = build.poll() {
                break answer.expect("prepared");
            }
            assert!(Instant::now() < deadline, "no answer from the thread");
            std::thread::sleep(Duration::from_millis(5));
        };
        let expected = on_union_axes(&a, &b).unwrap();
        assert!(prepared.clouds == expected, "the union of A and B");
        assert!(*prepared.shared == expected, "the window's copy");
        let labels = labels::axis_labels_for_box(
            &expected.0,
            glam::Vec3::splat(-1.0),
            glam::Vec3::splat(1.0),
        );
        assert_eq!(format!("{:?}", prepared.labels), format!("{labels:?}"));
        // The scene made from the thread's buffers builds the grids of one uploaded in the
        // frame (the GPU's points are read by the voxelizer).
        let renderer = Renderer::new(&gpu.device);
        let (clouds, buffers) = (prepared.clouds, prepared.buffers);
        let mut from_thread =
            CompareScene::from_buffers(&gpu.device, &renderer, clouds.0, clouds.1, buffers);
        let (a, b) = expected;
        let mut uploaded = CompareScene::from_union(&gpu.device, &renderer, a, b);
        let voxels = VoxelSettings::default();
        let mut differences = Vec::new();
        for scene in [&mut from_thread, &mut uploaded] {
            assert_eq!(scene.data_a.points.total, 5_000);
            assert_eq!(scene.data_b.points.total, 2_000);
            scene
                .ensure_grids(&gpu.device, &gpu.queue, &renderer, &voxels)
                .expect("grids");
            differences.push(scene.grids.as_ref().unwrap().difference_cpu.clone());
        }
        assert!(
            differences[0].iter().any(|d| *d != 0.0),
            "points in the grids"
        );
        assert!(differences[0] == differences[1], "the same grids");
    }
}
