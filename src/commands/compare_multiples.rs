//! The sheet's small multiples (`loudscape compare ... -o sheet.png`): a row under the
//! extractor's sheet with every version drawn by the app's own renderer (the points view by
//! default, `--sheet-view`), on shared axes and from one camera. Each version's cloud (a song
//! cloud as given, or an audio file's, extracted and cached as `render` does) is moved onto A's
//! time by the comparison's alignment (`Alignment::move_onto_first`: its time map's
//! segments where it has several, else its one offset), then all onto the union of
//! their axes (folded pairwise with `on_union_axes`), so the same moment of the music and the
//! same level sit at the same place in every tile; the first tile's fitted view is every tile's.

use std::path::{Path, PathBuf};

use anyhow::Context;
use loudscape::data::cloud::PointCloud;
use loudscape::data::compare::on_union_axes;
use loudscape::extract::align::Comparison;
use loudscape::picture::compare::half_overlay;
use loudscape::render::gpu::context::GpuContext;
use loudscape::render::points::PointStyle;
use loudscape::render::scene::{RenderSettings, Renderer, SceneData, ViewKind};
use loudscape::view::camera::Camera;
use loudscape::view::frame_view::FrameView;

/// Every version on A's time and on the union of all their axes, A first.
pub fn on_shared_axes(
    mut clouds: Vec<PointCloud>,
    comparison: &Comparison,
) -> anyhow::Result<Vec<PointCloud>> {
    for (cloud, version) in clouds.iter_mut().zip(&comparison.versions).skip(1) {
        version.alignment.move_onto_first(cloud, 0.0);
    }
    let Some(first) = clouds.first() else {
        return Ok(clouds);
    };
    // The union grows version by version; the last one holds every version's axes.
    let mut union = first.clone();
    for cloud in &clouds[1..] {
        union = on_union_axes(&union, cloud)
            .with_context(|| format!("{}: not on A's axes", cloud.path.display()))?
            .0;
    }
    clouds
        .iter()
        .map(|cloud| {
            on_union_axes(&union, cloud)
                .map(|(_, moved)| moved)
                .with_context(|| format!("{}: not on A's axes", cloud.path.display()))
        })
        .collect()
}

/// A tile's title: "B: name, +0.731 s" (the offset against A where one was found).
fn title(i: usize, path: &Path, comparison: &Comparison) -> String {
    let letter = char::from(b'A' + i.min(25) as u8);
    let name = path.file_name().map_or_else(
        || path.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    );
    match comparison.versions.get(i).map(|v| &v.alignment) {
        Some(alignment) if i > 0 && alignment.alignable => {
            format!("{letter}: {name}, {:+.3} s", alignment.offset_s)
        }
        Some(_) if i > 0 => format!("{letter}: {name}, not aligned"),
        _ => format!("{letter}: {name}"),
    }
}

/// The row of small multiples, `width` pixels wide: one tile a version of `versions` (the
/// paths as given), in `view`.
pub fn render_row(
    versions: &[PathBuf],
    comparison: &Comparison,
    view: ViewKind,
    width: u32,
) -> anyhow::Result<image::RgbaImage> {
    let clouds = versions
        .iter()
        .map(|path| super::args::load_cloud(path))
        .collect::<anyhow::Result<Vec<_>>>()?;
    let clouds = on_shared_axes(clouds, comparison)?;
    let count = clouds.len().max(1) as u32;
    let tile_width = (width / count).max(64);
    let tile_height = tile_width * 3 / 4;
    let gpu = GpuContext::new_headless()?;
    let renderer = Renderer::new(&gpu.device);
    let mut settings = RenderSettings {
        view,
        ..Default::default()
    };
    let most = clouds.iter().map(PointCloud::len).max().unwrap_or(0);
    // Smaller tiles than a picture of its own: one size smaller discs, at least 1 px.
    settings.points.size_px = (PointStyle::size_for(most) - 1.0).max(1.0);
    let mut row =
        image::RgbaImage::from_pixel(tile_width * count, tile_height, image::Rgba([0, 0, 0, 255]));
    let mut shared_view = None;
    for (i, (cloud, path)) in clouds.iter().zip(versions).enumerate() {
        let mut data = SceneData::upload(&gpu.device, &gpu.queue, &renderer, cloud);
        if matches!(view, ViewKind::Volume | ViewKind::Surface) {
            super::render::prepare_grid(&gpu, &renderer, cloud, &mut data, &settings)?;
        }
        // One camera: the first tile's fitted view is every tile's.
        let frame_view = *shared_view.get_or_insert_with(|| {
            FrameView::fitted(
                Camera::default(),
                data.world_from_data,
                data.world_box(),
                tile_width,
                tile_height,
            )
        });
        let target = loudscape::render::headless::render_frame(
            &gpu,
            &renderer,
            Some(&data),
            &frame_view,
            &settings,
        );
        let mut tile = target
            .read_rgba(&gpu.device, &gpu.queue)
            .with_context(|| format!("{}: reading its tile back from the GPU", path.display()))?;
        let shapes = half_overlay(
            cloud,
            &data,
            &frame_view,
            &settings,
            i == 0,
            &title(i, path, comparison),
            None,
        );
        loudscape::annotate::raster::draw(&mut tile, &shapes.shapes, 1.0);
        image::imageops::overlay(&mut row, &tile, i64::from(tile_width * i as u32), 0);
    }
    Ok(row)
}

/// The sheet at `sheet` (a PNG the extractor wrote) with `row` under it, written in its place.
pub fn append_row(sheet: &Path, row: &image::RgbaImage) -> anyhow::Result<()> {
    let top = image::open(sheet)
        .with_context(|| format!("{}: cannot read the sheet back", sheet.display()))?
        .to_rgba8();
    let width = top.width().max(row.width());
    let mut whole = image::RgbaImage::from_pixel(
        width,
        top.height() + row.height(),
        image::Rgba([255, 255, 255, 255]),
    );
    image::imageops::overlay(&mut whole, &top, 0, 0);
    let left = i64::from((width - row.width()) / 2);
    image::imageops::overlay(&mut whole, row, left, i64::from(top.height()));
    loudscape::picture::save_png(&whole, sheet).map_err(anyhow::Error::msg)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// B 0.5 s later, C unrelated (not moved in time).
    const JSON: &str = r#"{"match": "quietest", "versions": [
        {"path": "a.wav", "match_gain_db": 0.0,
         "alignment": {"alignable": true, "offset_s": 0.0, "confidence": 1.0}},
        {"path": "b.wav", "match_gain_db": -4.0,
         "alignment": {"alignable": true, "offset_s": 0.5, "confidence": 0.9}},
        {"path": "c.wav", "match_gain_db": 0.0,
         "alignment": {"alignable": false, "offset_s": 0.0, "confidence": 0.1}}]}"#;

    /// Every tile's cloud on one set of axes, the union of all versions' (B 4 dB louder widens
    /// the level axis), B on A's time (its music 0.5 s earlier on A's clock), C as it is.
    #[test]
    fn every_version_lands_on_as_time_and_the_union_of_the_axes() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/format/song_v2.ply");
        let a = loudscape::data::cloud::load(&path).unwrap();
        let mut b = a.clone();
        b.meta.axes.y.min += 4.0;
        b.meta.axes.y.max += 4.0;
        let c = a.clone();
        let comparison = Comparison::parse(JSON).unwrap();
        let moved = on_shared_axes(vec![a.clone(), b, c], &comparison).unwrap();
        let own = &a.meta.axes;
        for cloud in &moved {
            let axes = &cloud.meta.axes;
            let first = &moved[0].meta.axes;
            assert_eq!((axes.x.min, axes.x.max), (first.x.min, first.x.max));
            assert_eq!((axes.y.min, axes.y.max), (first.y.min, first.y.max));
            assert_eq!(
                (axes.scalar.min, axes.scalar.max),
                (first.scalar.min, first.scalar.max)
            );
        }
        let union = &moved[0].meta.axes;
        assert_eq!((union.y.min, union.y.max), (own.y.min, own.y.max + 4.0));
        assert!((union.x.min - (own.x.min - 0.5)).abs() < 1e-9);
        assert_eq!(union.x.max, own.x.max);
        // A point of B sits 0.5 s before the same point of A (and of C, not moved).
        let at = |cloud: &PointCloud| union.x.value_at(f64::from(cloud.points[7].position[0]));
        assert!((at(&moved[0]) - at(&moved[1]) - 0.5).abs() < 1e-4);
        assert!((at(&moved[0]) - at(&moved[2])).abs() < 1e-9);
    }
}
