//! A/B compare pictures without a window: two clouds side by side from one camera, or their
//! difference grid in the diverging map with its legend. `loudscape render A --compare B`,
//! `loudscape video --compare`, the window's Save PNG while comparing and the golden-image tests
//! draw through here.

use anyhow::{Context, bail};

use crate::annotate::{Annotation, axes, compare, legend};
use crate::data::cloud::PointCloud;
use crate::render::compare::CompareScene;
use crate::render::gpu::context::GpuContext;
use crate::render::gpu::target::RenderTarget;
use crate::render::grid::difference::DifferenceMeasure;
use crate::render::headless::render_frame;
use crate::render::scene::{RenderSettings, Renderer, SceneData, ViewKind};
use crate::render::still::StillLayer;
use crate::render::volume::{TransferPreset, VolumeSettings};
use crate::view::camera::Camera;
use crate::view::frame_view::FrameView;

use super::{PendingPicture, Wait};

/// Pixels between the two halves of a compare picture.
pub const GAP: u32 = 4;

/// What a compare render draws.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CompareView {
    SideBySide(ViewKind),
    Difference(DifferenceMeasure),
}

/// The Difference view's volume settings: the shown grid's hp is the diverging position, so
/// the hp map is the Classic red-white-blue one the legend draws, whatever map the views use
/// (Cividis or Viridis are not diverging).
pub fn difference_settings(base: &RenderSettings) -> RenderSettings {
    RenderSettings {
        view: ViewKind::Volume,
        colours: crate::render::colormap::Colours {
            hp: crate::render::colormap::HpColourMap::Classic,
            ..base.colours
        },
        volume: VolumeSettings {
            preset: TransferPreset::Classic,
            hp_tint: true,
            shading: false,
            ..base.volume
        },
        ..base.clone()
    }
}

/// A file's name for a title.
fn file_name(cloud: &PointCloud) -> String {
    cloud
        .path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| cloud.path.display().to_string())
}

fn view_for(
    camera: Option<Camera>,
    data: &SceneData,
    width: u32,
    height: u32,
    margin_steps: f32,
) -> FrameView {
    match camera {
        Some(camera) => FrameView::at_rest(camera, data.world_from_data, width, height),
        None => {
            let mut view = FrameView::fitted(
                Camera::default(),
                data.world_from_data,
                data.world_box(),
                width,
                height,
            );
            // Room for the axis titles outside the box, as the window's fit leaves (one step
            // more in a narrow half).
            view.camera.zoom(-margin_steps);
            view
        }
    }
}

/// What is drawn over one half (or the whole) of a compare picture of `view`: the axis labels
/// (in the dark background's ink, as the compare draws), then the difference view's title and
/// diverging legend, or a half's title ("A: name") and the colour key of what it draws.
pub fn half_overlay(
    cloud: &PointCloud,
    data: &SceneData,
    view: &FrameView,
    settings: &RenderSettings,
    labels_on: bool,
    title: &str,
    legend: Option<(DifferenceMeasure, f32)>,
) -> Annotation {
    let rect = super::whole(view.width, view.height);
    let over = match legend {
        Some(legend) => compare::difference_overlay(rect, title, Some(legend)),
        None => legend::layout(rect, &half_legend(cloud, settings, title)),
    };
    let labels = labels_on.then(|| axes::axis_labels(cloud, data));
    crate::annotate::overlay::labels_and_legend(
        rect,
        view,
        labels.as_ref(),
        crate::render::colormap::Background::Dark,
        over,
    )
}

/// A half of the side-by-side picture: its title ("A: name") and the colour key of what it
/// draws, as every picture carries. The view and its settings are the same in both halves and
/// say more than a half has room for beside its key, so there is no detail line.
pub fn half_legend(
    cloud: &PointCloud,
    settings: &RenderSettings,
    title: &str,
) -> legend::PictureLegend {
    let mut picture = legend::picture_legend(cloud, settings);
    picture.name = title.to_string();
    picture.detail.clear();
    picture
}

/// Renders the compare of `a` and `b` into one image of `size`; B's title says what B was
/// aligned and matched by where `note` gives it ("B aligned +0.731 s, -3.8 dB to match A",
/// `data::compare::aligned_words`).
#[allow(clippy::too_many_arguments)]
pub fn render_compare_image(
    gpu: &GpuContext,
    renderer: &Renderer,
    scene: &mut CompareScene,
    what: CompareView,
    camera: Option<Camera>,
    size: (u32, u32),
    base: &RenderSettings,
    labels_on: bool,
    note: Option<&str>,
    stills: Option<&mut [StillLayer; 2]>,
) -> anyhow::Result<image::RgbaImage> {
    let picture = submit_compare_image(
        gpu, renderer, scene, what, camera, size, base, labels_on, note, stills,
    )?;
    Ok(picture.finish(&gpu.device, Wait::Blocking)?)
}

/// [`render_compare_image`] up to the GPU: the halves (or the difference) rendered and their
/// read-backs submitted, finished by [`PendingPicture::finish`] where the caller waits best.
/// With `stills` (a video's still camera) each half is drawn once into its layer and each
/// picture draws only the box and the markers over it, the same pixels (`render/still.rs`).
#[allow(clippy::too_many_arguments)]
pub fn submit_compare_image(
    gpu: &GpuContext,
    renderer: &Renderer,
    scene: &mut CompareScene,
    what: CompareView,
    camera: Option<Camera>,
    size: (u32, u32),
    base: &RenderSettings,
    labels_on: bool,
    note: Option<&str>,
    stills: Option<&mut [StillLayer; 2]>,
) -> anyhow::Result<PendingPicture> {
    let needs_grids = match what {
        CompareView::SideBySide(view) => view != ViewKind::Points,
        CompareView::Difference(_) => true,
    };
    if needs_grids {
        scene
            .ensure_grids(&gpu.device, &gpu.queue, renderer, &base.voxels)
            .map_err(|e| anyhow::anyhow!("{e}"))?;
    }
    match what {
        CompareView::SideBySide(view) => {
            let half = half_width(size.0)?;
            let settings = RenderSettings {
                view,
                ..base.clone()
            };
            // One camera for both: the boxes are the same, so A's fitted view is B's.
            let frame = view_for(camera, &scene.data_a, half, size.1, 2.0);
            let held = stills
                .as_deref()
                .is_some_and(|stills| stills.iter().all(|still| still.holds(&frame)));
            if view == ViewKind::Surface && !held {
                for data in [&scene.data_a, &scene.data_b] {
                    if let Some(grid) = data.grid.as_ref() {
                        renderer
                            .surface
                            .extract_blocking(&gpu.queue, &data.surface, grid, &settings.surface)
                            .context("extracting the surface")?;
                    }
                }
            }
            let drawn;
            let targets = match stills {
                Some([a, b]) => [
                    a.render_kept(gpu, renderer, &scene.data_a, &frame, &settings),
                    b.render_kept(gpu, renderer, &scene.data_b, &frame, &settings),
                ],
                None => {
                    drawn = [&scene.data_a, &scene.data_b]
                        .map(|data| render_frame(gpu, renderer, Some(data), &frame, &settings));
                    [&drawn[0], &drawn[1]]
                }
            };
            compose(
                gpu, scene, what, targets, &frame, size, base, labels_on, note,
            )
        }
        CompareView::Difference(measure) => {
            scene.set_measure(&gpu.device, &gpu.queue, renderer, measure);
            let grids = scene
                .grids
                .as_ref()
                .context("the difference grid was not built")?;
            let settings = difference_settings(base);
            let frame = view_for(camera, &grids.data, size.0, size.1, 1.0);
            let drawn;
            let target = match stills {
                Some([still, _]) => {
                    still.render_kept(gpu, renderer, &grids.data, &frame, &settings)
                }
                None => {
                    drawn = render_frame(gpu, renderer, Some(&grids.data), &frame, &settings);
                    &drawn
                }
            };
            compose(
                gpu,
                scene,
                what,
                [target, target],
                &frame,
                size,
                base,
                labels_on,
                note,
            )
        }
    }
}

/// The width of each half of a side-by-side picture `width` wide (the gap between them), or
/// why two halves do not fit.
pub fn half_width(width: u32) -> anyhow::Result<u32> {
    if width < 2 * 16 + GAP {
        bail!("width {width} is too narrow for two views");
    }
    Ok((width - GAP) / 2)
}

/// The compare picture from its halves already drawn (`targets`: A and B side by side, the
/// difference twice in the Difference view), each of `view`, their copies submitted with the
/// labels, titles and colour keys to draw over them, into a picture of `size`: every compare
/// picture's, whether its halves were drawn for it in one go, over frames, or are the
/// window's own.
#[allow(clippy::too_many_arguments)]
pub fn compose(
    gpu: &GpuContext,
    scene: &CompareScene,
    what: CompareView,
    targets: [&RenderTarget; 2],
    view: &FrameView,
    size: (u32, u32),
    base: &RenderSettings,
    labels_on: bool,
    note: Option<&str>,
) -> anyhow::Result<PendingPicture> {
    // The note before the file names, which are elided first when the title is too long.
    let (b_title, difference_title) = match note {
        Some(note) => (format!("{note}: "), format!("B - A, {note}: ")),
        None => ("B: ".to_string(), "B - A: ".to_string()),
    };
    let (name_a, name_b) = (file_name(&scene.a), file_name(&scene.b));
    match what {
        CompareView::SideBySide(kind) => {
            let settings = RenderSettings {
                view: kind,
                ..base.clone()
            };
            let half = view.width;
            let mut picture = PendingPicture::new(size.0, size.1, image::Rgba([90, 96, 110, 255]));
            let halves = [
                (0, &scene.a, &scene.data_a, format!("A: {name_a}")),
                (
                    half + GAP,
                    &scene.b,
                    &scene.data_b,
                    format!("{b_title}{name_b}"),
                ),
            ];
            for ((x, cloud, data, title), target) in halves.into_iter().zip(targets) {
                let shapes = half_overlay(cloud, data, view, &settings, labels_on, &title, None);
                picture.add(gpu, target, x, shapes)?;
            }
            Ok(picture)
        }
        CompareView::Difference(measure) => {
            let grids = scene
                .grids
                .as_ref()
                .context("the difference grid was not built")?;
            let settings = difference_settings(base);
            let mut picture = PendingPicture::new(size.0, size.1, image::Rgba([0; 4]));
            let title = format!("{difference_title}{name_b} against {name_a}");
            let shapes = half_overlay(
                &scene.a,
                &grids.data,
                view,
                &settings,
                labels_on,
                &title,
                Some((measure, grids.range())),
            );
            picture.add(gpu, targets[0], 0, shapes)?;
            Ok(picture)
        }
    }
}
