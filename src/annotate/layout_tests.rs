//! The layout rules of picture annotation, checked on the data: what overlaps what at the sizes
//! and angles pictures and the window use.

use glam::Vec3;

use super::{Rect, Text, axes, legend};
use crate::render::colormap::Background;
use crate::render::scene::{RenderSettings, ViewKind, world_box, world_from_data};
use crate::view::camera::Camera;
use crate::view::frame_view::FrameView;

fn demo_song() -> crate::data::cloud::PointCloud {
    let repo = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    crate::data::cloud::load(&repo.join("data/demo_song.ply")).expect("the demo song loads")
}

fn overlapping<'a>(texts: &[&'a Text]) -> Option<(&'a Text, &'a Text)> {
    for (i, a) in texts.iter().enumerate() {
        for b in &texts[i + 1..] {
            if a.rect.intersects(&b.rect) {
                return Some((a, b));
            }
        }
    }
    None
}

/// The level axis's title ("bin level (dB re FS sine)") sat 30 points left of the axis, over
/// the middle tick labels (-30/-40 dB), which were then left out: the title now goes beyond its
/// ticks (or above the axis where there is no room beside them), and no text overlaps another.
#[test]
fn the_level_title_never_covers_its_tick_labels() {
    let cloud = demo_song();
    let labels = axes::axis_labels_for_box(&cloud, Vec3::splat(-1.0), Vec3::splat(1.0));
    let level_title = labels
        .labels
        .iter()
        .find(|l| l.title && l.axis == 1)
        .map(|l| l.text.clone())
        .expect("a level title");
    let middle: Vec<String> = {
        let ticks = cloud.meta.axes.y.ticks(8);
        let n = ticks.len();
        assert!(n >= 4, "{n} level ticks");
        ticks[n / 2 - 1..=n / 2]
            .iter()
            .map(|t| t.label.clone())
            .collect()
    };
    let transform = world_from_data(cloud.meta.mode);
    let bounds = world_box(transform, Vec3::splat(-1.0), Vec3::splat(1.0));
    for (w, h) in [(1280, 720), (640, 400), (640, 242), (500, 400), (320, 200)] {
        for azimuth in [-35.0f32, -60.0, 20.0] {
            let camera = Camera {
                azimuth: azimuth.to_radians(),
                ..Camera::default()
            };
            let view = FrameView::fitted(camera, transform, bounds, w, h);
            let rect = Rect::from_min_size([0.0, 0.0], [w as f32, h as f32]);
            let out = axes::layout(rect, &view, &labels, Background::Dark);
            let texts: Vec<&Text> = out.texts().collect();
            if let Some((a, b)) = overlapping(&texts) {
                panic!("{w}x{h} at {azimuth}: '{}' overlaps '{}'", a.text, b.text);
            }
            let title = texts.iter().find(|t| t.text == level_title);
            let title = title.unwrap_or_else(|| panic!("{w}x{h} at {azimuth}: no level title"));
            assert!(
                title.rect.left() >= 0.0 && title.rect.right() <= w as f32,
                "{w}x{h}: the level title runs off the picture"
            );
            for t in texts.iter().filter(|t| t.size == axes::TITLE_SIZE) {
                assert!(
                    t.rect.bottom() <= h as f32 && t.rect.top() >= 0.0,
                    "{w}x{h} at {azimuth}: '{}' runs off the picture",
                    t.text
                );
            }
            if (w, h) == (1280, 720) || (w, h) == (640, 400) {
                for tick in &middle {
                    assert!(
                        texts.iter().any(|t| &t.text == tick),
                        "{w}x{h} at {azimuth}: the {tick} dB tick is missing"
                    );
                }
            }
        }
    }
}

/// Side by side in a small window (500x400, the side panel taking half the width), each half's
/// legend overlapped its title ("A: name"): now the key goes under the name where they would
/// meet, long text is cut to the half's width, and crowded key ticks drop their words.
#[test]
fn a_half_views_legend_never_covers_its_title() {
    let cloud = demo_song();
    for view in [ViewKind::Points, ViewKind::Surface, ViewKind::Volume] {
        let settings = RenderSettings {
            view,
            ..Default::default()
        };
        let mut picture = legend::picture_legend(&cloud, &settings);
        picture.name = "A: demo_song_with_a_long_name.ply".into();
        picture.detail.clear();
        for width in (100..=700).step_by(10) {
            let rect = Rect::from_min_size([0.0, 0.0], [width as f32, 400.0]);
            let out = legend::layout(rect, &picture);
            let texts: Vec<&Text> = out.texts().collect();
            if let Some((a, b)) = overlapping(&texts) {
                panic!("{view:?} at {width}: '{}' overlaps '{}'", a.text, b.text);
            }
            for t in &texts {
                assert!(
                    t.rect.left() >= -0.5 && t.rect.right() <= width as f32 + 0.5,
                    "{view:?} at {width}: '{}' runs off ({:?})",
                    t.text,
                    t.rect
                );
            }
            assert!(texts[0].text.starts_with("A: "), "the title comes first");
        }
    }
}

/// A timeline as heard on a service titles its level axis "momentary loudness (BS.1770,
/// 400 ms), as heard on Spotify (normal) (LUFS)", which reached the view's edge: every title now
/// keeps [`axes::TITLE_MARGIN`] inside the view, drawn smaller where it is wider than the view
/// and cut with "…" only where even the smallest size is.
#[test]
fn long_titles_stay_inside_the_view() {
    let repo = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut cloud = crate::data::cloud::load(&repo.join("data/demo_timeline.ply"))
        .expect("the demo timeline loads");
    cloud.meta.axes.y.label =
        "momentary loudness (BS.1770, 400 ms), as heard on Spotify (normal)".into();
    let labels = axes::axis_labels_for_box(&cloud, Vec3::splat(-1.0), Vec3::splat(1.0));
    let titles: Vec<String> = labels
        .labels
        .iter()
        .filter(|l| l.title)
        .map(|l| l.text.clone())
        .collect();
    let level_title = titles
        .iter()
        .find(|t| t.contains("as heard on Spotify"))
        .expect("the level title names the service")
        .clone();
    let transform = world_from_data(cloud.meta.mode);
    let bounds = world_box(transform, Vec3::splat(-1.0), Vec3::splat(1.0));
    let margin = axes::TITLE_MARGIN - 0.5;
    let mut shrunk = false;
    for (w, h) in [(1010, 631), (700, 500), (500, 400), (320, 200), (250, 300)] {
        for azimuth in [-35.0f32, -60.0, 20.0, 90.0] {
            let camera = Camera {
                azimuth: azimuth.to_radians(),
                ..Camera::default()
            };
            let view = FrameView::fitted(camera, transform, bounds, w, h);
            let rect = Rect::from_min_size([0.0, 0.0], [w as f32, h as f32]);
            let out = axes::layout(rect, &view, &labels, Background::Dark);
            let texts: Vec<&Text> = out.texts().collect();
            // Whole, shortened to name and unit, or cut: every text that is no tick label.
            let is_title = |t: &Text| !labels.labels.iter().any(|l| !l.title && l.text == t.text);
            for t in texts.iter().filter(|t| is_title(t)) {
                assert!(
                    t.rect.left() >= margin
                        && t.rect.right() <= w as f32 - margin
                        && t.rect.top() >= margin
                        && t.rect.bottom() <= h as f32 - margin,
                    "{w}x{h} at {azimuth}: '{}' reaches the view's edge ({:?})",
                    t.text,
                    t.rect
                );
                assert!(t.size >= axes::MIN_TITLE_SIZE);
            }
            let level = texts
                .iter()
                .find(|t| t.text.starts_with("momentary loudness"))
                .unwrap_or_else(|| panic!("{w}x{h} at {azimuth}: no level title"));
            if w >= 500 {
                // Wide enough for the whole title at some size: never cut.
                assert_eq!(level.text, level_title, "{w}x{h} at {azimuth}");
            }
            shrunk |= level.size < axes::TITLE_SIZE;
        }
    }
    assert!(shrunk, "some view is narrower than the title at full size");
    // The rule itself: full size where it fits, smaller, then cut at the smallest size.
    let full = crate::annotate::font::measure(&level_title, axes::TITLE_SIZE)[0];
    assert_eq!(
        axes::fitted_title(&level_title, full + 1.0),
        (level_title.clone(), axes::TITLE_SIZE)
    );
    let (text, size) = axes::fitted_title(&level_title, full * 0.8);
    assert_eq!(text, level_title);
    assert!((axes::MIN_TITLE_SIZE..axes::TITLE_SIZE).contains(&size));
    assert!(crate::annotate::font::measure(&text, size)[0] <= full * 0.8);
    // Cut, its unit kept.
    let (text, size) = axes::fitted_title(&level_title, 100.0);
    assert!(
        text.ends_with("… (LUFS)") && size == axes::MIN_TITLE_SIZE,
        "{text}"
    );
    assert!(crate::annotate::font::measure(&text, size)[0] <= 100.0);
}

/// At 500x400 the window's view (about 300x300 beside the side panel) showed tick labels cut at
/// its edge ("dB" of "-10 dB"): a tick label the edge would cut is now left out, so every label
/// drawn is whole, on songs and timelines, at every size and angle.
#[test]
fn no_label_is_cut_by_the_views_edge() {
    let repo = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    for file in ["data/demo_song.ply", "data/demo_timeline.ply"] {
        let cloud = crate::data::cloud::load(&repo.join(file)).expect("the demo loads");
        let labels = axes::axis_labels_for_box(&cloud, Vec3::splat(-1.0), Vec3::splat(1.0));
        let transform = world_from_data(cloud.meta.mode);
        let bounds = world_box(transform, Vec3::splat(-1.0), Vec3::splat(1.0));
        let mut ticks_drawn = 0;
        for (w, h) in [(300, 300), (300, 240), (500, 400), (1010, 631), (200, 150)] {
            for azimuth in [-35.0f32, -60.0, 20.0, 90.0, 160.0] {
                for distance in [1.0f32, 0.6] {
                    let fitted = FrameView::fitted(
                        Camera {
                            azimuth: azimuth.to_radians(),
                            ..Camera::default()
                        },
                        transform,
                        bounds,
                        w,
                        h,
                    );
                    // Zoomed in: the box reaches past the view's edges.
                    let camera = Camera {
                        distance: fitted.camera.distance * distance,
                        ..fitted.camera
                    };
                    let view = FrameView::at_rest(camera, transform, w, h);
                    let rect = Rect::from_min_size([0.0, 0.0], [w as f32, h as f32]);
                    let out = axes::layout(rect, &view, &labels, Background::Dark);
                    for t in out.texts() {
                        assert!(
                            t.rect.left() >= -0.5
                                && t.rect.right() <= w as f32 + 0.5
                                && t.rect.top() >= -0.5
                                && t.rect.bottom() <= h as f32 + 0.5,
                            "{file} {w}x{h} at {azimuth} x{distance}: '{}' is cut ({:?})",
                            t.text,
                            t.rect
                        );
                        ticks_drawn += usize::from(t.size == axes::TICK_SIZE);
                    }
                }
            }
        }
        assert!(
            ticks_drawn > 100,
            "{file}: ticks are still drawn ({ticks_drawn})"
        );
    }
}

/// At a 500x400 window (the view about 300x300 beside the side panel, less under the loudness
/// strip) the timeline's level title, "momentary loudness (BS.1770, 400 ms) (LUFS)", had no
/// room beside its ticks nor above its axis under the legend, and was cut or left out: it now
/// keeps its name and unit there ("momentary loudness (LUFS)"), whole, inside the view and
/// clear of the legend and of every other label.
#[test]
fn a_small_timeline_view_keeps_its_level_title_with_its_unit() {
    let repo = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let cloud = crate::data::cloud::load(&repo.join("data/demo_timeline.ply")).unwrap();
    let labels = axes::axis_labels_for_box(&cloud, Vec3::splat(-1.0), Vec3::splat(1.0));
    let transform = world_from_data(cloud.meta.mode);
    let bounds = world_box(transform, Vec3::splat(-1.0), Vec3::splat(1.0));
    let picture = legend::picture_legend(&cloud, &RenderSettings::default());
    let margin = axes::TITLE_MARGIN - 0.5;
    for (w, h) in [(300, 300), (290, 280), (300, 240), (280, 200)] {
        for azimuth in [-35.0f32, -60.0, 20.0] {
            let camera = Camera {
                azimuth: azimuth.to_radians(),
                ..Camera::default()
            };
            let view = FrameView::fitted(camera, transform, bounds, w, h);
            let rect = Rect::from_min_size([0.0, 0.0], [w as f32, h as f32]);
            let out = crate::annotate::overlay::labels_and_legend(
                rect,
                &view,
                Some(&labels),
                Background::Dark,
                legend::layout(rect, &picture),
            );
            let texts: Vec<&Text> = out.texts().collect();
            let level = texts
                .iter()
                .find(|t| t.text.starts_with("momentary loudness"))
                .unwrap_or_else(|| panic!("{w}x{h} at {azimuth}: no level title"));
            assert!(
                level.text.ends_with(" (LUFS)") && !level.text.contains('…'),
                "{w}x{h} at {azimuth}: '{}' is cut or lost its unit",
                level.text
            );
            assert!(
                level.rect.left() >= margin
                    && level.rect.right() <= w as f32 - margin
                    && level.rect.top() >= margin
                    && level.rect.bottom() <= h as f32 - margin,
                "{w}x{h} at {azimuth}: '{}' reaches the view's edge ({:?})",
                level.text,
                level.rect
            );
            for other in texts.iter().filter(|t| !std::ptr::eq(**t, *level)) {
                assert!(
                    !other.rect.intersects(&level.rect),
                    "{w}x{h} at {azimuth}: '{}' covers '{}'",
                    level.text,
                    other.text
                );
            }
        }
    }
    assert_eq!(
        axes::abbreviated_title("momentary loudness (BS.1770, 400 ms) (LUFS)").as_deref(),
        Some("momentary loudness (LUFS)")
    );
    assert_eq!(axes::abbreviated_title("bin level (dB re FS sine)"), None);
}
