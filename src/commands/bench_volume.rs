//! The voxelization and volume part of `loudscape bench`: median GPU times of building grids
//! and of drawing one volume frame (shaded and unshaded, the fast march beside the full one it
//! must look like). GPU timestamp queries where the adapter has them, otherwise the wall time of
//! submit-and-wait. With `--fields-dir`, also the song's density grid (`volume_density.npy`) and
//! the frame's camera, box and step (`volume_view.json`), so bench/peers_volume.py can draw the
//! same frame with VTK.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Context;
use loudscape::data::cloud::{DataMode, Point, PointCloud};
use loudscape::data::synthetic::synthetic_song;
use loudscape::render::gpu::context::GpuContext;
use loudscape::render::gpu::target::RenderTarget;
use loudscape::render::gpu::timing::Timestamps;
use loudscape::render::grid::voxelize::{MAX_PASSES, VoxelizeJob, VoxelizeRequest};
use loudscape::render::scene::{RenderSettings, Renderer, SceneData, ViewKind};
use loudscape::render::volume::progressive::{INITIAL_ROWS, ProgressiveVolume, TARGET_FRAME};
use loudscape::render::volume::{BASE_OPACITY, VolumeSettings};
use loudscape::render::volume_grids::VolumeGridsPass;
use loudscape::view::camera::{Camera, FOV_Y_DEGREES};
use loudscape::view::frame_view::FrameView;

/// Points of the synthetic stand-in for a song when data/demo_song.ply is absent.
pub const SYNTHETIC_SONG_POINTS: usize = 700_000;
pub const LARGE_CLOUD_POINTS: usize = 2_000_000;

/// Times GPU work: timestamps around the recorded work where supported, else wall time.
pub struct GpuTimer {
    queries: Option<Timestamps>,
}

impl GpuTimer {
    pub fn new(gpu: &GpuContext) -> Self {
        let queries = Timestamps::new(
            &gpu.device,
            &gpu.queue,
            "bench::timestamps",
            2,
            wgpu::Features::TIMESTAMP_QUERY | wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS,
        );
        Self { queries }
    }

    pub fn method(&self) -> &'static str {
        if self.queries.is_some() {
            "GPU timestamp queries"
        } else {
            "submit-and-wait wall time (no timestamp queries on this adapter)"
        }
    }

    /// Milliseconds of the work `record` adds to one encoder.
    pub fn time(
        &self,
        gpu: &GpuContext,
        record: impl FnOnce(&mut wgpu::CommandEncoder),
    ) -> anyhow::Result<f64> {
        let mut encoder = gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("bench::timed"),
            });
        if let Some(queries) = &self.queries {
            encoder.write_timestamp(&queries.set, 0);
        }
        record(&mut encoder);
        if let Some(queries) = &self.queries {
            encoder.write_timestamp(&queries.set, 1);
            queries.resolve(&mut encoder, 2);
        }
        let start = Instant::now();
        gpu.queue.submit([encoder.finish()]);
        gpu.device
            .poll(wgpu::PollType::wait_indefinitely())
            .context("waiting for the GPU")?;
        let wall = start.elapsed().as_secs_f64() * 1e3;
        match &self.queries {
            Some(queries) => {
                let ticks = queries.read_ticks(&gpu.device)?;
                Ok(queries.ms(ticks[0], ticks[1]))
            }
            None => Ok(wall),
        }
    }
}

pub fn median(mut values: Vec<f64>) -> f64 {
    values.sort_by(f64::total_cmp);
    let n = values.len();
    if n == 0 {
        return f64::NAN;
    }
    if n % 2 == 1 {
        values[n / 2]
    } else {
        (values[n / 2 - 1] + values[n / 2]) * 0.5
    }
}

/// The song to measure: `input` (the command's INPUT), or a synthetic song when INPUT is the
/// default demo file and that is absent (a checkout without data/).
fn song_cloud(input: &Path) -> anyhow::Result<(PointCloud, String)> {
    if input == Path::new(super::args::DEMO_SONG) && !input.exists() {
        eprintln!(
            "bench: {} is absent; using a synthetic song instead",
            input.display()
        );
        let cloud = PointCloud::synthetic(synthetic_song(SYNTHETIC_SONG_POINTS, 1), DataMode::Song);
        return Ok((cloud, "synthetic song".into()));
    }
    let cloud = super::args::load_cloud(input)?;
    Ok((cloud, input.display().to_string()))
}

fn export(points: &[Point], path: &Path, input: &Path) -> anyhow::Result<()> {
    super::args::check_not_input(path, &[input])?;
    super::write_atomically(path, |out| {
        std::io::Write::write_all(out, bytemuck::cast_slice::<Point, u8>(points))?;
        Ok(())
    })?;
    super::wrote(
        path,
        &format!("{} points, x y z scalar hp float32", points.len()),
    );
    Ok(())
}

/// One line per stage: name, median ms, runs. The song stages and the volume frame use INPUT
/// (its own grid resolution: 128^3 for a song, 224^3 for a timeline) and the frame `size`.
pub fn run(
    input: &Path,
    size: (u32, u32),
    runs: usize,
    export_points: Option<&PathBuf>,
    fields_dir: Option<&Path>,
) -> anyhow::Result<()> {
    let runs = runs.max(1);
    let gpu = GpuContext::new_headless()?;
    let timer = GpuTimer::new(&gpu);
    println!("adapter: {}", gpu.describe());
    println!(
        "timing: {}, median of {runs} runs after one warm-up",
        timer.method()
    );
    let renderer = Renderer::new(&gpu.device);

    let (song, song_name) = song_cloud(input)?;
    let settings = RenderSettings {
        view: ViewKind::Volume,
        ..Default::default()
    };
    let song_resolution = settings.voxels.resolution_for(song.meta.mode);
    println!(
        "song: {song_name} ({} points, {song_resolution}^3 grid)",
        song.points.len()
    );
    let large = PointCloud::synthetic(synthetic_song(LARGE_CLOUD_POINTS, 2), DataMode::Timeline);
    if let Some(dir) = export_points {
        std::fs::create_dir_all(dir)
            .with_context(|| format!("{}: cannot create the folder", dir.display()))?;
        export(&song.points, &dir.join("song.f32"), input)?;
        export(&large.points, &dir.join("large.f32"), input)?;
    }

    // Per-pass timestamps, where the adapter has them.
    let passes = Timestamps::new(
        &gpu.device,
        &gpu.queue,
        "bench::pass_timestamps",
        2 * MAX_PASSES as u32,
        wgpu::Features::TIMESTAMP_QUERY,
    );
    let stages: [(&str, &PointCloud, u32, f32); 4] = [
        ("voxelize song", &song, song_resolution, 0.0),
        (
            "voxelize song, smoothed (sigma 1)",
            &song,
            song_resolution,
            1.0,
        ),
        ("voxelize 2M points", &large, 224, 0.0),
        ("voxelize 2M points, smoothed (sigma 1)", &large, 224, 1.0),
    ];
    for (name, cloud, resolution, sigma) in stages {
        let start = Instant::now();
        let job: VoxelizeJob = renderer.voxelize.prepare(
            &gpu.device,
            &VoxelizeRequest::new(&cloud.points, resolution, sigma),
        )?;
        let upload = start.elapsed().as_secs_f64() * 1e3;
        let mut times = Vec::new();
        let mut pass_times: Vec<Vec<f64>> = Vec::new();
        let mut pass_names = Vec::new();
        for i in 0..=runs {
            let ms = timer.time(&gpu, |encoder| {
                pass_names =
                    renderer
                        .voxelize
                        .encode(encoder, &job, passes.as_ref().map(|p| &p.set));
                if let Some(passes) = &passes {
                    passes.resolve(encoder, 2 * pass_names.len() as u32);
                }
            })?;
            if i > 0 {
                times.push(ms);
                if let Some(passes) = &passes {
                    let ticks = passes.read_ticks(&gpu.device)?;
                    pass_times.resize(pass_names.len(), Vec::new());
                    for (p, times) in pass_times.iter_mut().enumerate() {
                        times.push(passes.ms(ticks[2 * p], ticks[2 * p + 1]));
                    }
                }
            }
        }
        println!(
            "{name}: {} points -> {resolution}^3: {:.2} ms (upload and allocation {upload:.1} ms)",
            cloud.points.len(),
            median(times)
        );
        if !pass_times.is_empty() {
            let parts: Vec<String> = pass_names
                .iter()
                .zip(pass_times)
                .map(|(name, t)| {
                    format!("{} {:.1}", name.trim_start_matches("voxelize::"), median(t))
                })
                .collect();
            println!("    passes (ms): {}", parts.join(", "));
        }
        if renderer.voxelize.on_cpu() {
            // What the app builds on this device instead: the same grid on the CPU's cores
            // (voxelize_host.rs), with its upload, waited for.
            let mut host_times = Vec::new();
            for i in 0..=runs {
                let start = Instant::now();
                renderer.voxelize.voxelize(
                    &gpu.device,
                    &gpu.queue,
                    &VoxelizeRequest::new(&cloud.points, resolution, sigma),
                )?;
                gpu.device.poll(wgpu::PollType::wait_indefinitely())?;
                if i > 0 {
                    host_times.push(start.elapsed().as_secs_f64() * 1e3);
                }
            }
            println!(
                "    on the CPU's cores (what the app does on this device): {:.2} ms",
                median(host_times)
            );
        }
    }

    // One volume frame of the song at the frame size, at rest (full quality) and moving.
    let mut data = SceneData::new(&gpu.device, &renderer, &song);
    data.ensure_grid(&gpu.device, &gpu.queue, &renderer, &song, &settings.voxels)?;
    let (width, height) = size;
    let target = RenderTarget::new(&gpu.device, width, height);
    let at_rest = FrameView::fitted(
        Camera::default(),
        data.world_from_data,
        data.world_box(),
        width,
        height,
    );
    if let Some(grid) = &data.grid {
        let grids = VolumeGridsPass::new(&gpu.device);
        let mut times = Vec::new();
        for i in 0..=runs {
            let start = Instant::now();
            grids.build(&gpu.device, grid).submit_once(&gpu.queue);
            gpu.device
                .poll(wgpu::PollType::wait_indefinitely())
                .context("waiting for the GPU")?;
            if i > 0 {
                times.push(start.elapsed().as_secs_f64() * 1e3);
            }
        }
        println!(
            "volume derived grids (gradient texture, brick maxima), {song_resolution}^3: {:.2} ms \
             (wall time, once per grid)",
            median(times)
        );
        if let Some(dir) = fields_dir {
            export_volume(&gpu, grid, &at_rest, &settings.volume, dir)?;
        }
    }
    for (moving, shading) in [(false, true), (false, false), (true, true)] {
        let view = FrameView { moving, ..at_rest };
        let mut medians = [0.0; 2];
        for (full_march, median_ms) in [false, true].into_iter().zip(&mut medians) {
            let mut settings = settings.clone();
            settings.volume.shading = shading;
            settings.volume.full_march = full_march;
            let mut times = Vec::new();
            for i in 0..=runs {
                let ms = timer.time(&gpu, |encoder| {
                    renderer.render(&gpu.queue, encoder, &target, Some(&data), &view, &settings);
                })?;
                if i > 0 {
                    times.push(ms);
                }
            }
            *median_ms = median(times);
        }
        println!(
            "volume frame {width}x{height} ({}, {song_resolution}^3, step {} voxel, {}): {:.2} ms \
             (full march {:.2} ms)",
            if moving { "moving" } else { "at rest" },
            settings.volume.step(moving),
            if shading { "shaded" } else { "unshaded" },
            medians[0],
            medians[1],
        );
    }
    progressive_volume(&gpu, &renderer, &data, &at_rest, &settings)?;
    Ok(())
}

/// The window's volume at rest drawn progressively (`render/volume/progressive.rs`): the wall
/// time of the coarse first frame and of each band frame (its bands of [`INITIAL_ROWS`], as the
/// window starts; the rows are not adapted here), each submitted and waited for.
fn progressive_volume(
    gpu: &GpuContext,
    renderer: &Renderer,
    data: &SceneData,
    view: &FrameView,
    settings: &RenderSettings,
) -> anyhow::Result<()> {
    let target = RenderTarget::new(&gpu.device, view.width, view.height);
    let mut progressive = ProgressiveVolume::<u32>::default();
    let mut now = Instant::now();
    let mut frame_ms = Vec::new();
    loop {
        let start = Instant::now();
        let mut encoder = gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("bench::progressive_volume"),
            });
        let complete = progressive.frame(
            &gpu.device,
            &gpu.queue,
            &mut encoder,
            renderer,
            &target,
            data,
            &0,
            view,
            settings,
            now,
        );
        gpu.queue.submit([encoder.finish()]);
        gpu.device
            .poll(wgpu::PollType::wait_indefinitely())
            .context("waiting for the GPU")?;
        frame_ms.push(start.elapsed().as_secs_f64() * 1e3);
        // Frames on the target time: the rows per band stay as the window starts them.
        now += TARGET_FRAME;
        if complete {
            break;
        }
    }
    let coarse = frame_ms[0];
    let bands = frame_ms[1..].to_vec();
    let total: f64 = frame_ms.iter().sum();
    let longest = bands.iter().copied().fold(0.0, f64::max);
    println!(
        "volume progressive {}x{} (at rest, shaded): first (coarse) frame {coarse:.1} ms, then {} \
         bands of {INITIAL_ROWS} rows, median {:.1} ms, longest {longest:.1} ms; {total:.0} ms in \
         all (wall time, each frame submitted and waited for)",
        view.width,
        view.height,
        bands.len(),
        median(bands.clone()),
    );
    Ok(())
}

/// Writes the grid's density (`volume_density.npy`, float32, shape (nz, ny, nx)) and what a
/// peer needs to draw the same frame (`volume_view.json`: the camera in world space, the grid's
/// box in world space, the step, the transfer function's constants).
fn export_volume(
    gpu: &GpuContext,
    grid: &loudscape::render::grid::VoxelGrid,
    view: &FrameView,
    volume: &VolumeSettings,
    dir: &Path,
) -> anyhow::Result<()> {
    let density = grid
        .read_field(&gpu.device, &gpu.queue, &grid.density)
        .context("reading the density grid back")?;
    let dims = grid.dims;
    let path = dir.join("volume_density.npy");
    super::write_atomically(&path, |out| Ok(super::npy::write(out, &[&density], dims)?))?;
    super::wrote(
        &path,
        &format!("{}x{}x{} density grid", dims.x, dims.y, dims.z),
    );
    let world = |p: glam::Vec3| view.world_from_data.transform_point3(p).to_array();
    let camera = &view.camera;
    let json = serde_json::json!({
        "width": view.width,
        "height": view.height,
        "dims": dims.to_array(),
        "box_min_world": world(grid.box_min),
        "box_max_world": world(grid.box_max),
        "eye": camera.eye().to_array(),
        "target": camera.target.to_array(),
        "up": [0.0, 1.0, 0.0],
        "fov_y_degrees": FOV_Y_DEGREES,
        "step_voxels": volume.step(false),
        "preset": volume.preset.name(),
        "density_scale": volume.density_scale,
        "opacity_per_voxel": volume.opacity_scale * BASE_OPACITY,
        "ramp": volume.preset.stops(),
    });
    let path = dir.join("volume_view.json");
    super::write_atomically(&path, |out| {
        serde_json::to_writer_pretty(&mut *out, &json)?;
        Ok(())
    })?;
    super::wrote(
        &path,
        "the volume frame's camera, box and transfer function",
    );
    Ok(())
}
