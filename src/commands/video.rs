//! `loudscape video SONG -o out.mp4`: the view `render` draws, frame after frame, with the
//! playhead moving through the data in step with the song, the song's passage as the sound
//! track, and the loudness strip under the view; encoded by ffmpeg (`video_encode`).
//!
//! Frame k shows the playhead at `start + k / fps`, exactly what `render --playhead` draws for
//! that time (the same passes, labels and legend). A timeline sweeps across its years instead,
//! the title of the song under the sweep on top, over a silent sound track.

use std::path::PathBuf;

use anyhow::{Context, bail};
use glam::Vec3;
use loudscape::annotate::axes::AxisLabels;
use loudscape::annotate::legend::PictureLegend;
use loudscape::annotate::strip::{LoudnessStrip, STRIP_HEIGHT};
use loudscape::annotate::{Annotation, Rect, Shape, raster};
use loudscape::data::cloud::{DataMode, PointCloud};
use loudscape::picture::compare::{CompareView, render_compare_image};
use loudscape::render::compare::CompareScene;
use loudscape::render::gpu::context::GpuContext;
use loudscape::render::gpu::target::{RenderTarget, TargetReader};
use loudscape::render::markers::MarkerBox;
use loudscape::render::points::PointStyle;
use loudscape::render::scene::{RenderSettings, Renderer, SceneData, ViewKind};
use loudscape::render::still::StillLayer;
use loudscape::view::camera::Camera;
use loudscape::view::frame_view::FrameView;

use super::args::{ViewChoice, camera_arg, check_iso, check_output, load_cloud, size_arg};
use super::render::{DrawArgs, prepare_grid};
use super::video_encode::{EncodeSpec, Encoder, Progress, ProgressMode, Sound, song_sound};
use super::video_frames::{self, Layout, Rendered, StripLayer};

/// The largest frame: 4K UHD (either way round).
pub const MAX_PIXELS: u64 = 3840 * 2160;
/// How fast `--camera orbit` turns: degrees a second (a turn in 40 s).
pub const ORBIT_DEGREES_PER_S: f32 = 9.0;
/// How close `--camera follow` comes: its distance as a share of the fitted one.
pub const FOLLOW_DISTANCE: f32 = 0.55;

#[derive(clap::Args, Debug)]
pub struct VideoArgs {
    /// The point cloud (.ply), or an audio file (WAV, FLAC, Ogg, MP3...), extracted by loudscape-extract and cached.
    pub input: PathBuf,
    /// What to draw: points, surface or volume; compare or difference with --compare; timeline
    /// (the points of a timeline cloud; any view of a timeline sweeps across its years).
    #[arg(long, value_enum, ignore_case = true, default_value_t = ViewChoice::Points)]
    pub view: ViewChoice,
    /// Camera motion.
    #[arg(long, value_enum, ignore_case = true, default_value_t = CameraMotion::Fixed)]
    pub camera: CameraMotion,
    /// The camera to start from, as AZ,EL,DIST (as `render --camera`); fitted when omitted.
    #[arg(long, allow_hyphen_values = true, value_parser = camera_arg)]
    pub camera_at: Option<Camera>,
    /// Frame size as WIDTHxHEIGHT: even sides, at most 3840x2160 pixels.
    #[arg(long, default_value = "1280x720", value_parser = size_arg)]
    pub size: (u32, u32),
    /// Frames a second (1 to 120).
    #[arg(long, default_value_t = 30)]
    pub fps: u32,
    /// Start of the passage, seconds into the song (default: its start).
    #[arg(long)]
    pub start: Option<f64>,
    /// End of the passage, seconds into the song (default: its end).
    #[arg(long)]
    pub end: Option<f64>,
    /// A timeline's sweep: how long it takes to cross the years, seconds.
    #[arg(long, default_value_t = 20.0)]
    pub sweep: f64,
    /// Level of detail.
    #[arg(long, value_enum, ignore_case = true, default_value_t = Detail::Auto)]
    pub detail: Detail,
    /// Leave out the loudness strip under the view (drawn for songs with loudness curves when
    /// the frame is at least 360 pixels tall).
    #[arg(long)]
    pub no_strip: bool,
    /// Make the sound track silent instead of the song's audio.
    #[arg(long)]
    pub silent: bool,
    #[command(flatten)]
    pub draw: DrawArgs,
    /// Progress report.
    #[arg(long, value_enum, ignore_case = true, default_value_t = ProgressMode::Auto)]
    pub progress: ProgressMode,
    /// H.264 quality, x264's constant rate factor (0 to 51, lower is better).
    #[arg(long, default_value_t = 18)]
    pub crf: u32,
    /// The MP4 file to write (.mp4; not the input).
    #[arg(short, long)]
    pub output: PathBuf,
}

/// Camera motion.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum CameraMotion {
    /// Still.
    Fixed,
    /// A slow turn, 9 degrees a second.
    Orbit,
    /// Travels along the time axis with the playhead.
    Follow,
}

/// `--detail`: how much of the data each frame draws.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Detail {
    /// Full with a fixed camera (the scene is drawn once); with a moving one, fast on a
    /// software rasterizer such as lavapipe, else full.
    Auto,
    /// Every point, the volume's full ray step: what `render` draws.
    Full,
    /// The window's level of detail while the camera moves: at most 40,000 points, a coarser
    /// ray step.
    Fast,
}

impl CameraMotion {
    /// The camera at `elapsed_s` into the video whose playhead is at world x `head_x`.
    pub fn camera(self, base: Camera, elapsed_s: f64, head_x: f32) -> Camera {
        let mut camera = base;
        match self {
            Self::Fixed => {}
            Self::Orbit => {
                camera.azimuth = (base.azimuth
                    + (ORBIT_DEGREES_PER_S * elapsed_s as f32).to_radians())
                .rem_euclid(std::f32::consts::TAU);
            }
            Self::Follow => {
                camera.target.x = head_x;
                camera.distance = base.distance * FOLLOW_DISTANCE;
            }
        }
        camera
    }
}

/// Checks a video frame size: even sides (yuv420p halves the colour planes), 4K at most.
pub fn check_video_size(size: (u32, u32)) -> anyhow::Result<()> {
    let (w, h) = size;
    if w % 2 != 0 || h % 2 != 0 {
        bail!(
            "size {w}x{h}: a video's sides must be even (H.264 in yuv420p), e.g. {}x{}",
            w & !1,
            h & !1
        );
    }
    if u64::from(w) * u64::from(h) > MAX_PIXELS || w.max(h) > 3840 {
        bail!("size {w}x{h} is larger than 3840x2160");
    }
    Ok(())
}

/// The passage of a song `duration_s` long: (start, end), checked.
pub fn passage(
    start: Option<f64>,
    end: Option<f64>,
    duration_s: f64,
) -> anyhow::Result<(f64, f64)> {
    let start = start.unwrap_or(0.0);
    let end = end.unwrap_or(duration_s);
    if !start.is_finite() || start < 0.0 {
        bail!("--start {start} is not a time in seconds (0 or more)");
    }
    if start >= duration_s {
        bail!("--start {start} is past the song's end ({duration_s:.1} s)");
    }
    if !end.is_finite() || end <= start {
        bail!("--end {end} must come after --start {start}");
    }
    if end > duration_s + 1e-3 {
        bail!("--end {end} is past the end of the song ({duration_s:.3} s)");
    }
    Ok((start, end))
}

/// The number of frames of a passage of `seconds` at `fps` (at least one).
pub fn frame_count(seconds: f64, fps: u32) -> u64 {
    ((seconds * f64::from(fps)).round() as u64).max(1)
}

/// What one video draws, and how.
struct Plan {
    size: (u32, u32),
    view_height: u32,
    fps: u32,
    frames: u64,
    /// Song time of frame 0 (seconds), or the sweep's length for a timeline.
    start_s: f64,
    motion: CameraMotion,
    fast: bool,
    timeline: bool,
}

enum Drawn {
    One {
        cloud: Box<PointCloud>,
        data: Box<SceneData>,
        labels: Option<AxisLabels>,
        legend: Option<PictureLegend>,
    },
    Compare {
        scene: Box<CompareScene>,
        what: CompareView,
        labels: bool,
        /// What B was aligned and matched by, for the legend.
        note: Option<String>,
    },
}

pub fn run(args: VideoArgs) -> anyhow::Result<()> {
    keep_freed_memory();
    let mut inputs = vec![args.input.as_path()];
    inputs.extend(args.draw.compare.as_deref());
    check_output(&args.output, &["mp4"], &inputs)?;
    super::video_encode::find_ffmpeg()?;
    let size = args.size;
    check_video_size(size)?;
    if !(1..=120).contains(&args.fps) {
        bail!("--fps {} is out of range 1 to 120", args.fps);
    }
    if args.crf > 51 {
        bail!("--crf {} is out of range 0 to 51", args.crf);
    }
    let motion = args.camera;
    let progress_mode = args.progress;
    let base_camera = args.camera_at;
    args.draw.check_point_size()?;
    args.draw.check_alignment()?;
    let compare_view = match &args.draw.compare {
        Some(_) => Some(super::render_compare::compare_view(
            args.view,
            args.draw.compare_as,
            args.draw.measure,
        )?),
        None => None,
    };
    let view = match args.view.view_kind() {
        Some(kind) if compare_view.is_none() => kind,
        _ if args.view.compares() && compare_view.is_none() => bail!(
            "--view {} needs a second cloud: --compare B",
            loudscape::value_name(&args.view)
        ),
        _ => ViewKind::Points,
    };
    let freq_axis = args.draw.freq_axis;
    let mut settings = RenderSettings {
        view,
        colours: args.draw.colours.colours(),
        ..Default::default()
    };
    settings.surface.method = args.draw.method;
    settings.surface.iso_value = check_iso(args.draw.iso)?;
    args.draw.volume.apply(&mut settings)?;

    args.draw.check_normalize(&args.input)?;
    let cloud = args.draw.heard(load_cloud(&args.input)?)?;
    let timeline = cloud.meta.mode == DataMode::Timeline;
    if args.view == ViewChoice::Timeline && !timeline {
        bail!(
            "{}: --view timeline needs a timeline cloud",
            args.input.display()
        );
    }
    if cloud.meta.mode == DataMode::Generic {
        bail!(
            "{}: a video needs a song or a timeline (this cloud has no time axis)",
            args.input.display()
        );
    }
    // The passage and its sound.
    let (start_s, seconds, sound) = if timeline {
        if args.start.is_some() || args.end.is_some() {
            bail!("--start/--end choose a song's passage; a timeline takes --sweep SECONDS");
        }
        if !(args.sweep.is_finite() && (1.0..=3600.0).contains(&args.sweep)) {
            bail!("--sweep {} is out of range 1 to 3600 seconds", args.sweep);
        }
        (0.0, args.sweep, Sound::Silence)
    } else {
        let duration = loudscape::playback::song_duration_s(&cloud);
        let (start, end) = passage(args.start, args.end, duration)?;
        let sound = if args.silent {
            Sound::Silence
        } else {
            let path = song_sound(&args.input, &cloud)?;
            check_output(&args.output, &["mp4"], &[path.as_path()])?;
            Sound::Passage {
                path,
                start_s: start,
                duration_s: end - start,
            }
        };
        (start, end - start, sound)
    };
    let frames = frame_count(seconds, args.fps);
    let strip = (!timeline && !args.no_strip && size.1 >= 360 && compare_view.is_none())
        .then(|| LoudnessStrip::for_cloud(&cloud))
        .flatten();
    let strip_height = if strip.is_some() {
        strip_height_for(size.1)
    } else {
        0
    };
    let view_height = size.1 - strip_height;

    let gpu = GpuContext::new_headless()?;
    // A still camera's scene is drawn once (`render/still.rs`), so `auto` draws it in full even on
    // a software rasterizer; a moving camera draws every frame afresh.
    let fast = match args.detail {
        Detail::Full => false,
        Detail::Fast => true,
        Detail::Auto => {
            args.camera != CameraMotion::Fixed
                && gpu.adapter.get_info().device_type == wgpu::DeviceType::Cpu
        }
    };
    let renderer = Renderer::new(&gpu.device);
    let mut drawn = match (&args.draw.compare, compare_view) {
        (Some(compare), Some(what)) => {
            // B on A's time (and loudness): the playhead at A's moment is B's same moment.
            let aligned = super::compare_align::align_b(&cloud, load_cloud(compare)?, &args.draw)?;
            if let Some(note) = &aligned.note {
                eprintln!("compare: {note}");
            }
            let cloud_b = aligned.cloud;
            settings.points.size_px = args.draw.point_size.unwrap_or_else(|| {
                PointStyle::size_for(cloud.points.len().max(cloud_b.points.len()))
            });
            let scene = CompareScene::new(&gpu.device, &renderer, &cloud, &cloud_b)
                .map_err(|e| anyhow::anyhow!("{e}"))?;
            Drawn::Compare {
                scene: Box::new(scene),
                what,
                labels: !args.draw.no_labels,
                note: aligned.note,
            }
        }
        _ => {
            settings.points.size_px = args
                .draw
                .point_size
                .unwrap_or_else(|| PointStyle::size_for(cloud.points.len()));
            let mut data = SceneData::upload(&gpu.device, &gpu.queue, &renderer, &cloud);
            data.set_freq_axis(&gpu.device, &renderer, &cloud, freq_axis)
                .map_err(anyhow::Error::msg)?;
            if matches!(view, ViewKind::Volume | ViewKind::Surface) {
                prepare_grid(&gpu, &renderer, &cloud, &mut data, &settings)?;
            }
            let labels = (!args.draw.no_labels)
                .then(|| loudscape::annotate::axes::axis_labels(&cloud, &data));
            let legend = (!args.draw.no_legend)
                .then(|| loudscape::annotate::legend::picture_legend(&cloud, &settings));
            Drawn::One {
                cloud: Box::new(cloud),
                data: Box::new(data),
                labels,
                legend,
            }
        }
    };
    let plan = Plan {
        size,
        view_height,
        fps: args.fps,
        frames,
        start_s,
        motion,
        fast,
        timeline,
    };
    let spec = EncodeSpec {
        width: size.0,
        height: size.1,
        fps: args.fps,
        frames,
        sound,
        crf: args.crf,
    };
    let layout = Layout {
        width: size.0,
        view_height,
        strip: strip.map(|strip| StripLayer {
            image: render_strip(&strip, size.0, strip_height),
            strip,
        }),
    };
    let encoder = Encoder::start(&spec, &args.output)?;
    let progress = Progress::new(progress_mode, frames);
    let base = base_camera;
    // Two targets and staging buffers, used in turn for every frame: frame k is read back
    // while frame k+1 draws.
    let targets = [0, 1].map(|_| RenderTarget::new(&gpu.device, size.0, view_height));
    let readers = targets
        .each_ref()
        .map(|target| TargetReader::new(&gpu.device, target));
    let view_bytes = layout.view_bytes();
    video_frames::run(layout, encoder, progress, |out| {
        // A still camera's scene (each half of a compare's), drawn once (`render/still.rs`).
        let mut stills: [StillLayer; 2] = Default::default();
        // The frame drawn last, still to be read back and handed on.
        let mut pending: Option<Pending> = None;
        // Reads `frame` back (where its copy is still on the GPU) and hands it on; false
        // when the second stage has stopped.
        let finish = |frame: Pending| -> anyhow::Result<bool> {
            let Pending {
                mut pixels,
                overlay,
                t,
                copy,
            } = frame;
            if let Some((slot, index)) = copy {
                readers[slot]
                    .finish_into(&gpu.device, index, &mut pixels[..view_bytes])
                    .context("reading a frame back from the GPU")?;
            }
            Ok(out.send(Rendered { pixels, overlay, t }))
        };
        for k in 0..frames {
            let Some(mut pixels) = out.buffer() else {
                break;
            };
            let slot = (k % 2) as usize;
            let mut gpu_frame = GpuFrame {
                gpu: &gpu,
                renderer: &renderer,
                target: &targets[slot],
                reader: &readers[slot],
                stills: &mut stills,
            };
            let (overlay, index) = render_video_frame(
                &mut gpu_frame,
                &mut drawn,
                &plan,
                &settings,
                base,
                k,
                &mut pixels[..view_bytes],
            )?;
            let t = plan.start_s + k as f64 / f64::from(plan.fps);
            let drawn_now = Pending {
                pixels,
                overlay,
                t,
                copy: index.map(|index| (slot, index)),
            };
            if let Some(previous) = pending.replace(drawn_now)
                && !finish(previous)?
            {
                return Ok(());
            }
        }
        if let Some(last) = pending.take() {
            finish(last)?;
        }
        Ok(())
    })?;
    let detail_text = format!(
        "{}x{}, {frames} frames at {} fps, {}{}",
        size.0,
        size.1,
        args.fps,
        loudscape::playback::format_clock(frames as f64 / f64::from(args.fps)),
        if fast { ", fast detail" } else { "" }
    );
    super::wrote(&args.output, &detail_text);
    Ok(())
}

/// Keeps freed memory in the process. The software rasterizer (lavapipe) allocates and frees
/// blocks of megabytes for every frame, which glibc by default hands back to the kernel and
/// maps afresh each time: the kernel then zeroes every page again (a third of the command's
/// system time went to page faults). Blocks under 32 MiB (glibc's largest threshold on 64-bit
/// machines) come from the heap, and freed memory is kept for the next frame.
fn keep_freed_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: mallopt only sets allocator parameters; called before the frames' threads start.
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, 32 << 20);
        libc::mallopt(libc::M_TRIM_THRESHOLD, 512 << 20);
    }
}

/// A frame drawn, its read-back submitted (the reader's slot and the copy's submission) unless
/// it was read already.
struct Pending {
    pixels: Vec<u8>,
    overlay: Vec<Shape>,
    t: f64,
    copy: Option<(usize, wgpu::SubmissionIndex)>,
}

/// The GPU side of a video's frames, kept from frame to frame.
struct GpuFrame<'a> {
    gpu: &'a GpuContext,
    renderer: &'a Renderer,
    /// The view's size.
    target: &'a RenderTarget,
    reader: &'a TargetReader,
    /// A still camera's scene (each half of a compare's), drawn once (`render/still.rs`).
    stills: &'a mut [StillLayer; 2],
}

/// Frame `k` of the video, without the strip, into `out` (the view's RGBA rows); returns what
/// is drawn over it (labels, legend, title), laid out in pixels, and the submission of its
/// read-back where it is still on the GPU (`TargetReader::finish_into` fills `out`).
fn render_video_frame(
    frame: &mut GpuFrame,
    drawn: &mut Drawn,
    plan: &Plan,
    settings: &RenderSettings,
    base_camera: Option<Camera>,
    k: u64,
    out: &mut [u8],
) -> anyhow::Result<(Vec<Shape>, Option<wgpu::SubmissionIndex>)> {
    let (gpu, renderer) = (frame.gpu, frame.renderer);
    let elapsed = k as f64 / f64::from(plan.fps);
    let (w, h) = (plan.size.0, plan.view_height);
    let mut settings = settings.clone();
    match drawn {
        Drawn::One {
            cloud,
            data,
            labels,
            legend,
        } => {
            let (head, title) = if plan.timeline {
                let u = if plan.frames > 1 {
                    k as f64 / (plan.frames - 1) as f64
                } else {
                    0.0
                };
                let x = (-1.0 + 2.0 * u) as f32;
                let song = song_at(cloud, x);
                settings.markers = timeline_markers(cloud, x, song);
                (x, song.map(|i| song_title(cloud, i)))
            } else {
                let x = loudscape::playback::time_to_x(&cloud.meta.axes.x, plan.start_s + elapsed);
                settings.markers = vec![MarkerBox::playhead(x)];
                (x, None)
            };
            let fitted = FrameView::fitted(
                Camera::default(),
                data.world_from_data,
                data.world_box(),
                w,
                h,
            )
            .camera;
            let base = base_camera.unwrap_or(fitted);
            let head_x = data
                .world_from_data
                .transform_point3(Vec3::new(head, 0.0, 0.0))
                .x;
            let camera = plan.motion.camera(base, elapsed, head_x);
            let mut view = FrameView::at_rest(camera, data.world_from_data, w, h);
            view.moving = plan.fast;
            view.frame_index = k as u32;
            if plan.motion == CameraMotion::Fixed {
                frame.stills[0].render(gpu, renderer, data, &view, &settings, frame.target);
            } else {
                loudscape::render::headless::render_into(
                    gpu,
                    renderer,
                    Some(data),
                    &view,
                    &settings,
                    frame.target,
                );
            }
            let copy = frame
                .reader
                .submit_copy(&gpu.device, &gpu.queue, frame.target)
                .context("reading a frame back from the GPU")?;
            let background = settings.colours.background;
            let rect = loudscape::picture::whole(w, h);
            let mut over = Annotation::default();
            if let Some(legend) = legend.as_ref() {
                over.extend(loudscape::annotate::legend::layout(rect, legend));
            }
            if let Some(title) = &title {
                over.extend(loudscape::annotate::legend::caption(
                    rect, title, background,
                ));
            }
            let overlay = loudscape::annotate::overlay::labels_and_legend(
                rect,
                &view,
                labels.as_ref(),
                background,
                over,
            );
            Ok((overlay.shapes, Some(copy)))
        }
        Drawn::Compare {
            scene,
            what,
            labels,
            note,
        } => {
            let x = loudscape::playback::time_to_x(&scene.a.meta.axes.x, plan.start_s + elapsed);
            settings.markers = vec![MarkerBox::playhead(x)];
            // Fixed and fitted: the compare's own framing; otherwise from the fitted camera of
            // a half (both halves share one box and one camera).
            let camera = match (base_camera, plan.motion) {
                (None, CameraMotion::Fixed) => None,
                (base, motion) => {
                    let data = &scene.data_a;
                    let base = base.unwrap_or_else(|| {
                        let mut view = FrameView::fitted(
                            Camera::default(),
                            data.world_from_data,
                            data.world_box(),
                            w / 2,
                            h,
                        );
                        view.camera.zoom(-2.0);
                        view.camera
                    });
                    let head_x = data
                        .world_from_data
                        .transform_point3(Vec3::new(x, 0.0, 0.0))
                        .x;
                    Some(motion.camera(base, elapsed, head_x))
                }
            };
            // A still camera's halves are drawn once, the playheads over them every frame.
            let stills = (plan.motion == CameraMotion::Fixed).then_some(&mut *frame.stills);
            let image = render_compare_image(
                gpu,
                renderer,
                scene,
                *what,
                camera,
                (w, h),
                &settings,
                *labels,
                note.as_deref(),
                stills,
            )?;
            out.copy_from_slice(image.as_raw());
            Ok((Vec::new(), None))
        }
    }
}

/// The timeline song under `x`, or else the nearest one (songs are bands with gaps between).
fn song_at(cloud: &PointCloud, x: f32) -> Option<usize> {
    let x = f64::from(x);
    let distance = |a: f64, b: f64| {
        if x < a {
            a - x
        } else if x > b {
            x - b
        } else {
            0.0
        }
    };
    cloud
        .meta
        .songs
        .iter()
        .enumerate()
        .filter_map(|(i, s)| Some((i, distance(s.x_min?, s.x_max?))))
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(i, _)| i)
}

/// "Title · Artist (1994)" of timeline song `i`.
fn song_title(cloud: &PointCloud, i: usize) -> String {
    let song = &cloud.meta.songs[i];
    let mut text = if song.title.trim().is_empty() {
        song.path
            .as_deref()
            .and_then(|p| std::path::Path::new(p).file_stem())
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| format!("song {}", i + 1))
    } else {
        song.title.trim().to_string()
    };
    if !song.artist.trim().is_empty() {
        text.push_str(" · ");
        text.push_str(song.artist.trim());
    }
    if let Some(year) = song.year {
        text.push_str(&format!(" ({year})"));
    }
    text
}

/// The sweep's plane and the span of the song under it.
fn timeline_markers(cloud: &PointCloud, x: f32, song: Option<usize>) -> Vec<MarkerBox> {
    let mut markers = Vec::new();
    if let Some(song) = song.and_then(|i| cloud.meta.songs.get(i))
        && let (Some(a), Some(b)) = (song.x_min, song.x_max)
    {
        markers.push(MarkerBox::x_span(
            a as f32,
            b as f32,
            [1.0, 1.0, 1.0, 0.12],
            [1.0, 1.0, 1.0, 0.6],
        ));
    }
    markers.push(MarkerBox::playhead(x));
    markers
}

/// The strip's height in a frame `frame_height` pixels tall: the window's at 720 lines and
/// below, in proportion above (so 1080p and 4K read alike); even, as the frame's sides are.
pub fn strip_height_for(frame_height: u32) -> u32 {
    let scale = (f64::from(frame_height) / 720.0).max(1.0);
    2 * (f64::from(STRIP_HEIGHT) / 2.0 * scale).round() as u32
}

/// The strip of the song, without a playhead, `width` x `height` pixels.
fn render_strip(strip: &LoudnessStrip, width: u32, height: u32) -> image::RgbaImage {
    let ppp = height as f32 / STRIP_HEIGHT;
    let rect = Rect::from_min_size([0.0, 0.0], [width as f32 / ppp, STRIP_HEIGHT]);
    let mut image = image::RgbaImage::new(width, height);
    raster::draw(&mut image, &strip.layout(rect, None).shapes, ppp);
    image
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_passages_and_frames() {
        assert!(check_video_size((1280, 720)).is_ok());
        assert!(check_video_size((3840, 2160)).is_ok());
        assert!(check_video_size((2160, 3840)).is_ok());
        assert!(check_video_size((1281, 720)).is_err());
        assert!(check_video_size((7680, 4320)).is_err());
        assert_eq!(passage(None, None, 30.0).unwrap(), (0.0, 30.0));
        assert_eq!(passage(Some(2.0), Some(3.5), 30.0).unwrap(), (2.0, 3.5));
        assert!(passage(Some(3.0), Some(2.0), 30.0).is_err());
        assert!(passage(None, Some(31.0), 30.0).is_err());
        assert!(passage(Some(-1.0), None, 30.0).is_err());
        // No --end given: the message is about --start, not an --end the user never wrote.
        let late = passage(Some(100.0), None, 30.0).unwrap_err().to_string();
        assert_eq!(late, "--start 100 is past the song's end (30.0 s)");
        assert!(passage(Some(30.0), None, 30.0).is_err());
        assert_eq!(frame_count(1.0, 30), 30);
        assert_eq!(frame_count(2.5, 24), 60);
        assert_eq!(frame_count(0.001, 24), 1);
        assert_eq!(strip_height_for(360), 118);
        assert_eq!(strip_height_for(720), 118);
        assert_eq!(strip_height_for(1080), 178);
        assert_eq!(strip_height_for(2160), 354);
    }

    #[test]
    fn camera_motions() {
        let base = Camera::from_angles(-35.0, 25.0, 4.0);
        assert_eq!(CameraMotion::Fixed.camera(base, 10.0, 0.5), base);
        let orbit = CameraMotion::Orbit.camera(base, 10.0, 0.5);
        let turned = (orbit.azimuth - base.azimuth).rem_euclid(std::f32::consts::TAU);
        assert!((turned - 90f32.to_radians()).abs() < 1e-4, "{turned}");
        let follow = CameraMotion::Follow.camera(base, 10.0, 0.5);
        assert_eq!(follow.target.x, 0.5);
        assert!(follow.distance < base.distance);
    }
}
