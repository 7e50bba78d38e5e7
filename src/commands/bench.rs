//! `loudscape bench`: timings of the passes on this machine's GPU, as medians of many runs.
//! Figures, not pass/fail: compare them with docs/PERFORMANCE.md.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Context;
use loudscape::render::gpu::context::GpuContext;
use loudscape::render::gpu::target::RenderTarget;
use loudscape::render::scene::{RenderSettings, Renderer, SceneData};
use loudscape::view::camera::Camera;
use loudscape::view::frame_view::FrameView;

#[derive(clap::Args, Debug)]
pub struct BenchArgs {
    /// The cloud (or audio file) to measure with (points and volume parts; a timeline gets its 224^3 grid).
    #[arg(default_value = super::args::DEMO_SONG)]
    pub input: PathBuf,
    /// Frame size as WIDTHxHEIGHT (points and volume frames).
    #[arg(long, default_value = "1280x720", value_parser = super::args::size_arg)]
    pub size: (u32, u32),
    /// Frames per measurement.
    #[arg(long, default_value_t = 60)]
    pub frames: usize,
    /// Timed runs per pass measurement (the median is reported).
    #[arg(long, default_value_t = 10)]
    pub runs: usize,
    /// Isovalue of the isosurface benchmarks.
    #[arg(long, default_value_t = 0.3)]
    pub iso: f32,
    /// Write the benchmark fields here as .npy files (for bench/bench_surface.py), and the
    /// volume's grid and view (for bench/peers_volume.py).
    #[arg(long)]
    pub fields_dir: Option<PathBuf>,
    /// Also write the volume benchmark's point clouds (raw float32, five per point) to this
    /// folder, for bench/bench_voxelize.py.
    #[arg(long)]
    pub export_points: Option<PathBuf>,
    /// Measure only these parts (comma-separated); all when omitted.
    #[arg(long, value_delimiter = ',', value_enum)]
    pub only: Vec<BenchPart>,
}

/// A part of the benchmark (`--only`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum BenchPart {
    /// Load, first frame and points frames of the input cloud.
    Points,
    /// The voxel grid and volume frames of the input cloud.
    Volume,
    /// The isosurface extractions on the benchmark fields.
    Surface,
}

/// The median and 90th percentile of `samples` (milliseconds).
pub fn summary(samples: &mut [f64]) -> (f64, f64) {
    samples.sort_by(f64::total_cmp);
    let at = |q: f64| samples[((samples.len() - 1) as f64 * q).round() as usize];
    (at(0.5), at(0.9))
}

/// Renders one frame and waits for the GPU, returning milliseconds.
fn timed_frame(
    gpu: &GpuContext,
    renderer: &Renderer,
    target: &RenderTarget,
    data: &SceneData,
    view: &FrameView,
    settings: &RenderSettings,
) -> anyhow::Result<f64> {
    let start = Instant::now();
    let mut encoder = gpu
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("bench::frame"),
        });
    renderer.render(&gpu.queue, &mut encoder, target, Some(data), view, settings);
    gpu.queue.submit([encoder.finish()]);
    gpu.device
        .poll(wgpu::PollType::wait_indefinitely())
        .context("waiting for the GPU")?;
    Ok(start.elapsed().as_secs_f64() * 1e3)
}

pub fn run(args: BenchArgs) -> anyhow::Result<()> {
    let wants = |part: BenchPart| args.only.is_empty() || args.only.contains(&part);
    let size = args.size;
    if let Some(dir) = &args.fields_dir
        && !dir.is_dir()
    {
        anyhow::bail!("{}: the folder does not exist", dir.display());
    }
    if wants(BenchPart::Points) {
        bench_points(&args)?;
    }
    if wants(BenchPart::Volume) {
        super::bench_volume::run(
            &args.input,
            size,
            args.runs,
            args.export_points.as_ref(),
            args.fields_dir.as_deref(),
        )?;
    }
    if wants(BenchPart::Surface) {
        let surfaces = super::bench_surface::run(args.runs, args.iso, args.fields_dir.as_deref())?;
        super::bench_surface::print_paper_comparison(&surfaces);
    }
    Ok(())
}

/// Load, first frame and points frame times on the song cloud.
fn bench_points(args: &BenchArgs) -> anyhow::Result<()> {
    let (width, height) = args.size;
    let process_start = Instant::now();
    let load_start = Instant::now();
    let cloud = super::args::load_cloud(&args.input)?;
    let load_ms = load_start.elapsed().as_secs_f64() * 1e3;
    let gpu = GpuContext::new_headless()?;
    let renderer = Renderer::new(&gpu.device);
    let data = SceneData::new(&gpu.device, &renderer, &cloud);
    let target = RenderTarget::new(&gpu.device, width, height);
    let mut view = FrameView::fitted(
        Camera::default(),
        data.world_from_data,
        data.world_box(),
        width,
        height,
    );
    let settings = RenderSettings::default();
    let first_ms = timed_frame(&gpu, &renderer, &target, &data, &view, &settings)?;
    let to_first_frame = process_start.elapsed().as_secs_f64() * 1e3;

    println!("adapter: {}", gpu.describe());
    println!(
        "cloud: {} ({} points), frame {width}x{height}",
        args.input.display(),
        cloud.points.len()
    );
    println!(
        "load: {load_ms:.1} ms; first frame: {first_ms:.1} ms; start to first frame: {to_first_frame:.1} ms"
    );

    for (label, moving) in [
        ("points, orbiting (level of detail)", true),
        ("points, at rest (every point)", false),
    ] {
        let mut samples = Vec::with_capacity(args.frames);
        for i in 0..args.frames.max(1) {
            view.camera.orbit(4.0, 0.0, height as f32);
            view.moving = moving;
            view.frame_index = i as u32;
            samples.push(timed_frame(
                &gpu, &renderer, &target, &data, &view, &settings,
            )?);
        }
        let (median, p90) = summary(&mut samples);
        println!(
            "{label}: median {median:.2} ms ({:.1} fps), p90 {p90:.2} ms over {} frames",
            1e3 / median,
            samples.len()
        );
    }
    Ok(())
}
