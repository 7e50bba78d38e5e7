//! `loudscape render` and `loudscape render-demo`: the window's passes, offscreen, to PNG, with
//! the axis labels and the legend (colour key, name) drawn over them in the background's ink.

use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use loudscape::data::cloud::{DataMode, PointCloud};
use loudscape::data::freq_axis::FreqAxis;
use loudscape::data::normalize::Normalization;
use loudscape::picture::{Overlay, draw_overlay};
use loudscape::render::colormap::{Background, Colours, DensityColourMap, HpColourMap};
use loudscape::render::gpu::context::GpuContext;
use loudscape::render::grid::difference::DifferenceMeasure;
use loudscape::render::grid::voxelize::VoxelSettings;
use loudscape::render::markers::MarkerBox;
use loudscape::render::points::PointStyle;
use loudscape::render::scene::{RenderSettings, Renderer, SceneData, ViewKind};
use loudscape::render::surface::SurfaceMethod;
use loudscape::render::volume::{TransferPreset, VolumeSettings};
use loudscape::view::camera::Camera;
use loudscape::view::frame_view::FrameView;

use crate::commands::args::{
    ViewChoice, camera_arg, check_iso, check_not_input, check_output, check_output_folder,
    check_range, check_resolution, check_smoothing, load_cloud, size_arg,
};

#[derive(clap::Args, Debug)]
pub struct RenderArgs {
    /// The point cloud (.ply), or an audio file (WAV, FLAC, Ogg, MP3...), extracted by loudscape-extract and cached.
    pub input: PathBuf,
    /// What to draw: a view of the cloud, or with --compare one of the compare's.
    #[arg(long, value_enum, ignore_case = true, default_value_t = ViewChoice::Points)]
    pub view: ViewChoice,
    /// Camera as AZ,EL,DIST (degrees, degrees, world units); fitted to the data when omitted.
    #[arg(long, allow_hyphen_values = true, value_parser = camera_arg)]
    pub camera: Option<Camera>,
    /// Image size as WIDTHxHEIGHT.
    #[arg(long, default_value = "1280x720", value_parser = size_arg)]
    pub size: (u32, u32),
    #[command(flatten)]
    pub draw: DrawArgs,
    /// Draw the playhead plane at this time, in seconds into the song (a song cloud).
    #[arg(long)]
    pub playhead: Option<f64>,
    /// The PNG file to write (.png; not the input).
    #[arg(short, long)]
    pub output: PathBuf,
}

/// Colour maps and background of a picture.
/// How a cloud is drawn, shared by `render` and `video`: points, surface, annotations, colours,
/// frequency axis, the compare cloud, the volume and the playback normalization.
#[derive(clap::Args, Debug)]
pub struct DrawArgs {
    /// Point disc diameter in pixels (default: by the number of points).
    #[arg(long)]
    pub point_size: Option<f32>,
    /// Surface extraction method: mt (marching tetrahedra) or dc (dual contouring).
    #[arg(long, value_enum, ignore_case = true, default_value_t = SurfaceMethod::MarchingTetrahedra)]
    pub method: SurfaceMethod,
    /// Surface isovalue in [0, 1] of the normalized loudness density.
    #[arg(long, default_value_t = 0.5)]
    pub iso: f32,
    /// Leave out the axis labels.
    #[arg(long)]
    pub no_labels: bool,
    /// Leave out the legend (colour key and name).
    #[arg(long)]
    pub no_legend: bool,
    #[command(flatten)]
    pub colours: ColourArgs,
    /// Frequency axis of a song cloud (remapped from the bin frequencies in the metadata; no
    /// re-extraction). A timeline has no frequency axis: only linear.
    #[arg(long, value_enum, ignore_case = true, default_value_t)]
    pub freq_axis: FreqAxis,
    /// A second cloud to compare with (B); --view is then compare or difference.
    #[arg(long)]
    pub compare: Option<PathBuf>,
    /// With --view compare: how each half is drawn.
    #[arg(long, value_enum, ignore_case = true, default_value_t = ViewKind::Points)]
    pub compare_as: ViewKind,
    /// With --view difference: density (B - A per voxel) or level (level-weighted, per column).
    #[arg(long, value_enum, ignore_case = true, default_value_t)]
    pub measure: DifferenceMeasure,
    /// With --compare: B moved onto A's time by the offset found in their audio (the
    /// extractor's comparison; docs/COMPARE.md "Releases"), so the same moment of the music
    /// is at the same place.
    #[arg(long)]
    pub align: bool,
    /// With --compare: B's offset against A in seconds (positive: B's music comes later),
    /// added to the one --align finds.
    #[arg(long, allow_hyphen_values = true)]
    pub offset: Option<f64>,
    /// With --compare and --align: B's levels moved by the gain that matches its loudness to
    /// A's, so the difference shows dynamics and tonal balance, not loudness.
    #[arg(long)]
    pub match_loudness: bool,
    #[command(flatten)]
    pub volume: VolumeArgs,
    /// A timeline as heard after playback normalization: each song's y shifted by the gain the
    /// preset applies (docs/DYNAMICS.md).
    #[arg(long, value_enum, ignore_case = true, default_value_t)]
    pub normalize: Normalization,
}

impl DrawArgs {
    /// Refuses a `--point-size` outside 0.5 to 64 pixels.
    pub fn check_point_size(&self) -> anyhow::Result<()> {
        if let Some(size) = self.point_size
            && !(0.5..=64.0).contains(&size)
        {
            bail!("point size {size} is out of range 0.5 to 64 pixels");
        }
        Ok(())
    }

    /// Refuses a `--normalize` preset for `input` when it is an audio file (a song:
    /// normalization applies to a timeline), before anything is loaded or extracted.
    pub fn check_normalize(&self, input: &Path) -> anyhow::Result<()> {
        if self.normalize.preset().is_some() && loudscape::extract::is_audio(input) {
            bail!(
                "{}: normalization applies to a timeline, not a song cloud",
                input.display()
            );
        }
        Ok(())
    }

    /// `cloud` as heard under `--normalize` (a timeline's songs shifted by their playback
    /// gain); unchanged with `none`. Each song left where it was (no integrated loudness) is
    /// named on stderr with the reason (the legend says it too).
    pub fn heard(&self, cloud: PointCloud) -> anyhow::Result<PointCloud> {
        use loudscape::data::normalize;
        match self.normalize.preset() {
            Some(preset) => {
                let heard = normalize::normalized(&cloud, &preset).map_err(anyhow::Error::msg)?;
                for line in normalize::left_out_lines(&heard) {
                    eprintln!("{line}");
                }
                Ok(heard)
            }
            None => Ok(cloud),
        }
    }
}

#[derive(clap::Args, Debug, Clone)]
pub struct ColourArgs {
    /// hp colour map of points, surface and hp tint.
    #[arg(long, value_enum, ignore_case = true, default_value_t)]
    pub colormap: HpColourMap,
    /// Colour map of the volume's transfer function: preset (the --tf's own ramp) or a
    /// perceptually uniform map.
    #[arg(long, value_enum, ignore_case = true, default_value_t)]
    pub tf_colormap: DensityColourMap,
    /// Background: dark, or light for print (dark ink; the volume's ramp dark where dense).
    #[arg(long, value_enum, ignore_case = true, default_value_t)]
    pub background: Background,
}

impl ColourArgs {
    /// The colour maps and background they choose.
    pub fn colours(&self) -> Colours {
        Colours {
            hp: self.colormap,
            density: self.tf_colormap,
            background: self.background,
        }
    }
}

/// Volume view options (also used by `voxelize` for --res and --smooth).
#[derive(clap::Args, Debug, Clone)]
pub struct VolumeArgs {
    /// Volume transfer function.
    #[arg(long, value_enum, ignore_case = true, default_value_t = TransferPreset::Classic)]
    pub tf: TransferPreset,
    /// Volume density scale (0.1 to 8).
    #[arg(long, default_value_t = 1.0)]
    pub density: f32,
    /// Volume opacity scale (0.05 to 10).
    #[arg(long, default_value_t = 1.0)]
    pub opacity: f32,
    /// Tint the volume by mean hp (the points' red-to-blue palette).
    #[arg(long)]
    pub hp_tint: bool,
    /// Turn off the volume's gradient shading.
    #[arg(long)]
    pub no_shading: bool,
    /// Ray step in voxels (0.25 to 4).
    #[arg(long, default_value_t = 1.0)]
    pub step: f32,
    /// Grid resolution in voxels per side (64 to 384); by default 128 for a song, 224 for a
    /// timeline.
    #[arg(long)]
    pub res: Option<u32>,
    /// Gaussian smoothing of the grid, sigma in voxels (0 turns it off); by default 1 for a
    /// song, 4 for a timeline.
    #[arg(long)]
    pub smooth: Option<f32>,
}

impl VolumeArgs {
    /// Checks the values and writes them into `settings`.
    pub fn apply(&self, settings: &mut RenderSettings) -> anyhow::Result<()> {
        check_range(self.density, VolumeSettings::DENSITY_RANGE, "density")?;
        check_range(self.opacity, VolumeSettings::OPACITY_RANGE, "opacity")?;
        check_range(self.step, VolumeSettings::STEP_RANGE, "step")?;
        if let Some(sigma) = self.smooth {
            check_smoothing(sigma)?;
        }
        check_resolution(self.res)?;
        settings.volume = VolumeSettings {
            preset: self.tf,
            density_scale: self.density,
            opacity_scale: self.opacity,
            hp_tint: self.hp_tint,
            shading: !self.no_shading,
            step_voxels: self.step,
            ..settings.volume
        };
        settings.voxels = VoxelSettings {
            resolution: self.res,
            smoothing_sigma: self.smooth,
        };
        Ok(())
    }
}

#[derive(clap::Args, Debug)]
pub struct RenderDemoArgs {
    /// Where to write the PNG files.
    #[arg(long, default_value = "out")]
    pub out_dir: PathBuf,
    /// Image size as WIDTHxHEIGHT.
    #[arg(long, default_value = "1280x720", value_parser = size_arg)]
    pub size: (u32, u32),
    #[command(flatten)]
    pub colours: ColourArgs,
    /// Clouds to render (.ply).
    #[arg(required = true)]
    pub inputs: Vec<PathBuf>,
}

/// Renders `cloud` as `view` and writes `output` (via a temporary file, so no half-written PNG).
#[allow(clippy::too_many_arguments)]
fn render_to_file(
    gpu: &GpuContext,
    renderer: &Renderer,
    cloud: &PointCloud,
    data: &SceneData,
    camera: Option<Camera>,
    size: (u32, u32),
    settings: &RenderSettings,
    overlay: Overlay,
    output: &Path,
) -> anyhow::Result<()> {
    let view = match camera {
        Some(camera) => FrameView::at_rest(camera, data.world_from_data, size.0, size.1),
        None => FrameView::fitted(
            Camera::default(),
            data.world_from_data,
            data.world_box(),
            size.0,
            size.1,
        ),
    };
    let target =
        loudscape::render::headless::render_frame(gpu, renderer, Some(data), &view, settings);
    let mut image = target
        .read_rgba(&gpu.device, &gpu.queue)
        .with_context(|| format!("rendering {}", output.display()))?;
    draw_overlay(&mut image, &view, cloud, data, settings, overlay);
    save_png(&image, output)
}

/// Writes a PNG (through a temporary file, see [`loudscape::picture::save_png`]), first
/// saying plainly when the folder is missing.
pub fn save_png(image: &image::RgbaImage, output: &Path) -> anyhow::Result<()> {
    check_output_folder(output)?;
    Ok(loudscape::picture::save_png(image, output)?)
}

/// The view of `render` without `--compare`: one of a single cloud's.
fn single_view(view: ViewChoice) -> anyhow::Result<ViewKind> {
    match view.view_kind() {
        Some(kind) => Ok(kind),
        None if view.compares() => bail!(
            "--view {} needs a second cloud: --compare B",
            loudscape::value_name(&view)
        ),
        None => bail!(
            "--view timeline is video's sweep across the years; render draws a timeline with --view points"
        ),
    }
}

/// `loudscape render` of one cloud (with `--compare`, `render_compare::run_args` runs instead).
pub fn run(args: RenderArgs) -> anyhow::Result<()> {
    check_output(&args.output, &["png"], &[args.input.as_path()])?;
    let size = args.size;
    let view = single_view(args.view)?;
    let camera = args.camera;
    args.draw.check_point_size()?;
    args.draw.check_alignment()?;
    let iso_value = check_iso(args.draw.iso)?;
    let freq_axis = args.draw.freq_axis;
    let mut settings = RenderSettings {
        view,
        colours: args.draw.colours.colours(),
        ..Default::default()
    };
    settings.surface.method = args.draw.method;
    settings.surface.iso_value = iso_value;
    args.draw.volume.apply(&mut settings)?;
    args.draw.check_normalize(&args.input)?;
    let mut cloud = args.draw.heard(load_cloud(&args.input)?)?;
    if let Some(seconds) = args.playhead {
        settings.markers = vec![playhead_marker(&cloud, seconds)?];
    }
    settings.points.size_px = args
        .draw
        .point_size
        .unwrap_or_else(|| PointStyle::size_for(cloud.points.len()));
    let gpu = GpuContext::new_headless()?;
    let renderer = Renderer::new(&gpu.device);
    // One frame, no picking: on the stored frequency axis the host's copy of the points goes
    // as they reach the device (the grid is built from the device's copy); a remapped axis
    // keeps it for the remapped grid box.
    let mut data = if freq_axis == FreqAxis::Linear {
        SceneData::upload_draining(&gpu.device, &gpu.queue, &renderer, &mut cloud)
    } else {
        SceneData::upload(&gpu.device, &gpu.queue, &renderer, &cloud)
    };
    data.set_freq_axis(&gpu.device, &renderer, &cloud, freq_axis)
        .map_err(anyhow::Error::msg)?;
    if matches!(view, ViewKind::Volume | ViewKind::Surface) {
        prepare_grid(&gpu, &renderer, &cloud, &mut data, &settings)?;
    }
    render_to_file(
        &gpu,
        &renderer,
        &cloud,
        &data,
        camera,
        size,
        &settings,
        Overlay {
            labels: !args.draw.no_labels,
            legend: !args.draw.no_legend,
        },
        &args.output,
    )?;
    super::wrote(
        &args.output,
        &format!("{}x{} {}", size.0, size.1, view.name().to_lowercase()),
    );
    Ok(())
}

/// The playhead plane at `seconds` into the song of `cloud` (whose x axis is time).
pub fn playhead_marker(cloud: &PointCloud, seconds: f64) -> anyhow::Result<MarkerBox> {
    if cloud.meta.mode != DataMode::Song {
        bail!(
            "{}: --playhead needs a song cloud (its x axis is time)",
            cloud.path.display()
        );
    }
    if !seconds.is_finite() || seconds < 0.0 {
        bail!("playhead {seconds} is not a time in seconds (0 or more)");
    }
    Ok(MarkerBox::playhead(loudscape::playback::time_to_x(
        &cloud.meta.axes.x,
        seconds,
    )))
}

/// The settings and camera of a compare render: every option but --view, checked as for one
/// cloud.
pub fn compare_settings(args: &RenderArgs) -> anyhow::Result<(RenderSettings, Option<Camera>)> {
    let camera = args.camera;
    args.draw.check_point_size()?;
    args.draw.check_alignment()?;
    let mut settings = RenderSettings::default();
    settings.surface.method = args.draw.method;
    settings.surface.iso_value = check_iso(args.draw.iso)?;
    args.draw.volume.apply(&mut settings)?;
    Ok((settings, camera))
}

/// Builds the voxel grid the volume and surface views need, and extracts the surface when
/// that is the view (headless rendering waits for it; the window does not).
pub fn prepare_grid(
    gpu: &GpuContext,
    renderer: &Renderer,
    cloud: &PointCloud,
    data: &mut SceneData,
    settings: &RenderSettings,
) -> anyhow::Result<()> {
    data.ensure_grid(&gpu.device, &gpu.queue, renderer, cloud, &settings.voxels)
        .with_context(|| format!("{}: voxelizing", cloud.path.display()))?;
    if settings.view == ViewKind::Surface
        && let Some(grid) = data.grid.as_ref()
    {
        renderer
            .surface
            .extract_blocking(&gpu.queue, &data.surface, grid, &settings.surface)
            .with_context(|| format!("{}: extracting the surface", cloud.path.display()))?;
    }
    Ok(())
}

pub fn run_demo(args: RenderDemoArgs) -> anyhow::Result<()> {
    let size = args.size;
    let colours = args.colours.colours();
    // Every output is named up front and checked against every input, before any work.
    let inputs: Vec<&Path> = args.inputs.iter().map(PathBuf::as_path).collect();
    check_not_input(&args.out_dir, &inputs)?;
    let outputs: Vec<Vec<PathBuf>> = args
        .inputs
        .iter()
        .map(|input| demo_outputs(&args.out_dir, input))
        .collect();
    for output in outputs.iter().flatten() {
        check_not_input(output, &inputs)?;
    }
    std::fs::create_dir_all(&args.out_dir)
        .with_context(|| format!("{}: cannot create the folder", args.out_dir.display()))?;
    let gpu = GpuContext::new_headless()?;
    let renderer = Renderer::new(&gpu.device);
    for (input, outputs) in args.inputs.iter().zip(&outputs) {
        let cloud = load_cloud(input)?;
        let mut data = SceneData::upload(&gpu.device, &gpu.queue, &renderer, &cloud);
        for (view, output) in ViewKind::ALL.into_iter().zip(outputs) {
            let mut settings = RenderSettings {
                view,
                colours,
                ..Default::default()
            };
            settings.points.size_px = PointStyle::size_for(cloud.points.len());
            if matches!(view, ViewKind::Volume | ViewKind::Surface) {
                prepare_grid(&gpu, &renderer, &cloud, &mut data, &settings)?;
            }
            let overlay = Overlay {
                labels: true,
                legend: true,
            };
            render_to_file(
                &gpu, &renderer, &cloud, &data, None, size, &settings, overlay, output,
            )?;
            super::wrote(
                output,
                &format!("{}x{} {}", size.0, size.1, view.name().to_lowercase()),
            );
        }
    }
    Ok(())
}

/// The PNG files `render-demo` writes for `input`: `OUT_DIR/STEM_VIEW.png`, one per view.
fn demo_outputs(out_dir: &Path, input: &Path) -> Vec<PathBuf> {
    let stem = input
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "cloud".into());
    ViewKind::ALL
        .into_iter()
        .map(|view| out_dir.join(format!("{stem}_{}.png", view.name().to_lowercase())))
        .collect()
}
