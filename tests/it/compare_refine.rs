//! The A/B compare's halves drawn progressively (`ui/compare_refine.rs`): both halves' slices
//! recorded into one frame's encoder as the window does (one submission, one renderer), within
//! one shared budget, fill in over several frames and end as each half's single-pass frame.
//! Headless, on lavapipe where there is no GPU.

use crate::common::{self, view_of};

use loudscape::data::cloud::{DataMode, PointCloud};
use loudscape::data::synthetic::synthetic_song;
use loudscape::render::gpu::target::RenderTarget;
use loudscape::render::headless::render_image;
use loudscape::render::scene::{RenderSettings, Renderer, SceneData, ViewKind};
use loudscape::ui::compare_refine::CompareRefine;
use loudscape::ui::frame_cache::RenderKey;

#[test]
fn both_halves_fill_in_within_one_budget_and_end_as_their_single_pass_frames() {
    let gpu = common::gpu();
    let renderer = Renderer::new(&gpu.device);
    let clouds = [(60_000, 7), (15_000, 11)]
        .map(|(count, seed)| PointCloud::synthetic(synthetic_song(count, seed), DataMode::Song));
    let data = clouds
        .each_ref()
        .map(|cloud| SceneData::new(&gpu.device, &renderer, cloud));
    let totals = data.each_ref().map(|d| d.points.total);
    let mut view = view_of(&data[0], 320, 180);
    let settings = RenderSettings {
        view: ViewKind::Points,
        ..Default::default()
    };
    let singles = data
        .each_ref()
        .map(|d| render_image(&gpu, &renderer, Some(d), &view, &settings).expect("render"));
    let targets = [0, 1].map(|_| RenderTarget::new(&gpu.device, view.width, view.height));
    let mut compare = CompareRefine::default();
    compare.budget.budget = 10_000;
    assert!(compare.wants(0, totals) && compare.wants(1, totals));
    let keys = [0, 1].map(|side| RenderKey::new(&view, &settings, Some(side), 0));
    let mut frames = 0;
    let mut first_frame = None;
    loop {
        let mut encoder = gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
        let complete = [0, 1].map(|side| {
            compare.frame(
                side,
                (&gpu.device, &gpu.queue, &mut encoder, &renderer),
                &targets[side],
                &data[side],
                [&keys[0], &keys[1]],
                totals,
                &view,
                &settings,
            )
        });
        gpu.queue.submit([encoder.finish()]);
        frames += 1;
        view.frame_index += 1;
        if frames == 1 {
            assert_eq!(complete, [false, false], "both halves fill in over frames");
            assert!(compare.progress().is_some_and(|p| p > 0.0 && p < 1.0));
            first_frame = Some(
                targets
                    .each_ref()
                    .map(|t| t.read_rgba(&gpu.device, &gpu.queue).unwrap()),
            );
        }
        if complete == [true, true] {
            break;
        }
        assert!(frames < 100, "never completes");
    }
    // 75,000 points, at most about 10,000 a frame (the budget adapts to the frame time, at
    // least its floor): several frames, not one.
    assert!(frames > 1, "{frames} frames");
    assert_eq!(compare.progress(), None);
    for side in 0..2 {
        let last = targets[side]
            .read_rgba(&gpu.device, &gpu.queue)
            .expect("read");
        let (share, _) = common::difference(&singles[side], &last, 0);
        assert_eq!(
            share, 0.0,
            "half {side}: the complete picture differs in {share}"
        );
        // The first frame already shows the half (its slice and the sparse stand-in).
        let first = &first_frame.as_ref().unwrap()[side];
        assert!(
            common::coverage(first) > 0.5 * common::coverage(&singles[side]),
            "half {side}'s first frame is nearly empty"
        );
    }
}
