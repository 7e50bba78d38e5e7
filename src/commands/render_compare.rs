//! `loudscape render A --compare B --view compare|difference`: an A/B compare, headless.
//!
//! Both clouds go onto the union of their axes (`data::compare`); `compare` draws them side by
//! side, A left and B right, from one camera, as points, surfaces or volumes (`--compare-as`;
//! grids in one box and on one scale); `difference` draws the difference grid as a volume in
//! the diverging map with its legend (`--measure density|level`). The pictures are made by
//! `picture::compare`.

use anyhow::bail;
use loudscape::picture::compare::{CompareView, render_compare_image};
use loudscape::render::compare::CompareScene;
use loudscape::render::gpu::context::GpuContext;
use loudscape::render::grid::difference::DifferenceMeasure;
use loudscape::render::points::PointStyle;
use loudscape::render::scene::{RenderSettings, Renderer, ViewKind};
use loudscape::view::camera::Camera;

use super::args::ViewChoice;

/// `--view` with `--compare`: `compare` (side by side, as `--compare-as`) or `difference`
/// (as `--measure`); the views of one cloud are refused.
pub fn compare_view(
    view: ViewChoice,
    compare_as: ViewKind,
    measure: DifferenceMeasure,
) -> anyhow::Result<CompareView> {
    match view {
        ViewChoice::Compare => Ok(CompareView::SideBySide(compare_as)),
        ViewChoice::Difference => Ok(CompareView::Difference(measure)),
        other => bail!(
            "--view {} is not a view of --compare: compare (side by side) or difference",
            loudscape::value_name(&other)
        ),
    }
}

/// `loudscape render A --compare B ...`: the output checked against both inputs, then the
/// common options checked as for one cloud ([`super::render::compare_settings`]).
pub fn run_args(args: super::render::RenderArgs, compare: &std::path::Path) -> anyhow::Result<()> {
    super::args::check_output(&args.output, &["png"], &[args.input.as_path(), compare])?;
    let size = args.size;
    let (settings, camera) = super::render::compare_settings(&args)?;
    run(&args, compare, settings, camera, size)
}

/// `loudscape render A --compare B ...`, after the checks of [`run_args`].
pub fn run(
    args: &super::render::RenderArgs,
    compare: &std::path::Path,
    settings: RenderSettings,
    camera: Option<Camera>,
    size: (u32, u32),
) -> anyhow::Result<()> {
    let what = compare_view(args.view, args.draw.compare_as, args.draw.measure)?;
    let cloud_a = super::args::load_cloud(&args.input)?;
    let cloud_b = super::args::load_cloud(compare)?;
    // B on A's time (and loudness) as --align, --offset and --match-loudness ask.
    let aligned = super::compare_align::align_b(&cloud_a, cloud_b, &args.draw)?;
    let cloud_b = aligned.cloud;
    let mut settings = settings;
    settings.points.size_px = args
        .draw
        .point_size
        .unwrap_or_else(|| PointStyle::size_for(cloud_a.points.len().max(cloud_b.points.len())));
    let gpu = GpuContext::new_headless()?;
    let renderer = Renderer::new(&gpu.device);
    let mut scene = CompareScene::new(&gpu.device, &renderer, &cloud_a, &cloud_b)
        .map_err(|e| anyhow::anyhow!("{e}"))?;
    // On the union of both time axes, where the compare draws.
    if let Some(seconds) = args.playhead {
        settings.markers = vec![super::render::playhead_marker(&scene.a, seconds)?];
    }
    let image = render_compare_image(
        &gpu,
        &renderer,
        &mut scene,
        what,
        camera,
        size,
        &settings,
        !args.draw.no_labels,
        aligned.note.as_deref(),
        None,
    )?;
    super::render::save_png(&image, &args.output)?;
    let detail = match what {
        CompareView::SideBySide(kind) => format!("compare, {}", kind.name().to_lowercase()),
        CompareView::Difference(measure) => {
            let range = scene.grids.as_ref().map(|g| g.range()).unwrap_or(0.0);
            format!("difference, {} range ±{range:.3}", measure.name())
        }
    };
    let note = aligned.note.map(|n| format!(", {n}")).unwrap_or_default();
    super::wrote(
        &args.output,
        &format!("{}x{} {detail}{note}", size.0, size.1),
    );
    Ok(())
}
