//! Hover picking on clouds made in code: the point under the cursor is the bin drawn there, the
//! read-out gives its values in physical units, and the ray finds the first dense voxel.

use glam::{UVec3, Vec2, Vec3};

use loudscape::data::cloud::{DataMode, Point, PointCloud, SongInfo};
use loudscape::data::field::Field;
use loudscape::render::scene::world_from_data;
use loudscape::view::camera::Camera;
use loudscape::view::frame_view::FrameView;
use loudscape::view::pick::{cursor_ray, pick_point, point_readings, song_at};

/// A 31 x 21 grid of bins over time and frequency, level rising with time.
fn grid_cloud() -> PointCloud {
    let mut points = Vec::new();
    for i in 0..31 {
        for k in 0..21 {
            let x = -1.0 + 2.0 * i as f32 / 30.0;
            let z = -1.0 + 2.0 * k as f32 / 20.0;
            points.push(Point {
                position: [x, 0.0, z],
                scalar: 0.5 + 0.01 * i as f32,
                hp: k as f32 / 20.0,
            });
        }
    }
    PointCloud::synthetic(points, DataMode::Song)
}

fn view_from(camera: Camera) -> FrameView {
    FrameView::at_rest(camera, world_from_data(DataMode::Song), 640, 400)
}

#[test]
fn hovering_a_bin_reads_its_values() {
    let cloud = grid_cloud();
    let mut camera = Camera::from_angles(20.0, 35.0, 4.0);
    camera.fit(Vec3::new(-1.6, -0.8, -1.0), Vec3::new(1.6, 0.8, 1.0), 1.6);
    let view = view_from(camera);
    // Bin (i = 10, k = 15): 10 s, 16537.5 Hz.
    let index = 10 * 21 + 15;
    let target = view
        .project(Vec3::from(cloud.points[index].position))
        .expect("in view");
    let picked = pick_point(
        &cloud.points,
        &view,
        target + Vec2::new(1.5, -1.0),
        4.0,
        0.0,
    );
    assert_eq!(picked, Some(index));
    let readings = point_readings(&cloud.meta.axes, &cloud.points[index]);
    let text: Vec<String> = readings
        .iter()
        .map(|r| format!("{}: {}", r.name, r.value))
        .collect();
    assert!(text[0].starts_with("time: 10"), "{text:?}");
    assert!(
        text[1].contains("16.54 kHz") || text[1].contains("16537"),
        "{text:?}"
    );
    assert!(text[1].contains('('), "nearest note given: {text:?}");
    assert!(text[2].starts_with("level: -40"), "{text:?}");
    assert!(
        text[3].contains("-32"),
        "loudness 0.6 of -80..0 dB: {text:?}"
    );
    assert!(text[4].starts_with("hp: 0.75"), "{text:?}");
    // Hidden points are not picked; empty space picks nothing.
    assert_ne!(
        pick_point(&cloud.points, &view, target, 4.0, 0.61),
        Some(index)
    );
    assert_eq!(
        pick_point(&cloud.points, &view, Vec2::new(2.0, 2.0), 4.0, 0.0),
        None
    );
}

#[test]
fn the_cursor_ray_passes_through_the_projected_point() {
    let camera = Camera::from_angles(-30.0, 20.0, 5.0);
    let view = view_from(camera);
    let p = Vec3::new(0.3, -0.2, 0.6);
    let px = view.project(p).expect("in view");
    let (origin, dir) = cursor_ray(&view, px);
    let closest = origin + dir * (p - origin).dot(dir);
    assert!(closest.distance(p) < 1e-3, "{closest} vs {p}");
}

#[test]
fn the_ray_stops_at_the_first_dense_voxel() {
    let dims = UVec3::new(4, 4, 4);
    let mut density = vec![0.0f32; 64];
    let mut hp = vec![0.5f32; 64];
    // Voxels (1, 2, 2) and (3, 2, 2): the ray along +x meets (1, 2, 2) first.
    for (i, d, h) in [(1u32, 0.8f32, 0.9f32), (3, 1.0, 0.1)] {
        let idx = (i + 4 * (2 + 4 * 2)) as usize;
        density[idx] = d;
        hp[idx] = h;
    }
    let grid = Field {
        dims,
        box_min: Vec3::splat(-1.0),
        box_max: Vec3::splat(1.0),
        density,
        hp_mean: hp,
    };
    let hit = grid
        .pick(Vec3::new(-3.0, 0.25, 0.25), Vec3::X, 0.5)
        .expect("hit");
    assert_eq!(hit.voxel, UVec3::new(1, 2, 2));
    assert_eq!(hit.density, 0.8);
    assert_eq!(hit.hp_mean, 0.9);
    assert!((hit.position - Vec3::new(-0.25, 0.25, 0.25)).length() < 1e-6);
    let hit = grid
        .pick(Vec3::new(-3.0, 0.25, 0.25), Vec3::X, 0.9)
        .expect("hit");
    assert_eq!(hit.voxel, UVec3::new(3, 2, 2));
    assert!(
        grid.pick(Vec3::new(-3.0, 0.9, 0.25), Vec3::X, 0.5)
            .is_none()
    );
}

#[test]
fn timeline_positions_find_their_song() {
    let song = |title: &str, a: f64, b: f64| SongInfo {
        title: title.into(),
        x_min: Some(a),
        x_max: Some(b),
        ..Default::default()
    };
    let songs = vec![
        song("one", -1.0, -0.2),
        song("two", -0.2, 0.5),
        song("three", 0.5, 1.0),
    ];
    assert_eq!(song_at(&songs, -0.9), Some(0));
    assert_eq!(song_at(&songs, 0.0), Some(1));
    assert_eq!(song_at(&songs, 0.99), Some(2));
    assert_eq!(song_at(&songs, 1.5), None);
}

/// A dense but empty voxel (smoothing spread density into it; the voxelizer wrote the empty
/// default 0.5 as its hp) reads the hp of the points beside it, not "0.50 (mixed)".
#[test]
fn an_empty_voxel_reads_the_hp_of_its_neighbours() {
    use loudscape::view::pick::{EMPTY_VOXEL_HP, voxel_readings};
    let dims = UVec3::new(8, 8, 8);
    let n = 512;
    let index = |x: u32, y: u32, z: u32| (x + 8 * (y + 8 * z)) as usize;
    let mut density = vec![0.0f32; n];
    let mut hp = vec![EMPTY_VOXEL_HP; n];
    // (2, 4, 4) is dense and empty; (3, 4, 4) and (3, 5, 4) hold percussive points, (7, 4, 4)
    // (out of reach) a harmonic one.
    density[index(2, 4, 4)] = 0.6;
    for (x, y, d, h) in [(3, 4, 0.9f32, 0.1f32), (3, 5, 0.3, 0.3), (7, 4, 1.0, 0.95)] {
        density[index(x, y, 4)] = d;
        hp[index(x, y, 4)] = h;
    }
    let grid = Field {
        dims,
        box_min: Vec3::splat(-1.0),
        box_max: Vec3::splat(1.0),
        density,
        hp_mean: hp,
    };
    // Along +x through the centre of row (y = 4, z = 4).
    let hit = grid
        .pick(Vec3::new(-3.0, 0.125, 0.125), Vec3::X, 0.5)
        .expect("hit");
    assert_eq!(hit.voxel, UVec3::new(2, 4, 4));
    let expected = (0.1 * 0.9 + 0.3 * 0.3) / (0.9 + 0.3);
    assert!((hit.hp_mean - expected).abs() < 1e-6, "{}", hit.hp_mean);
    let readings = voxel_readings(
        &loudscape::data::axes::Axes::generic([(-1.0, 1.0); 3]),
        &hit,
    );
    let hp_line = readings.iter().find(|r| r.name == "mean hp").unwrap();
    assert_eq!(hp_line.value, "0.15 (percussive)");
    // Nothing holding points within two voxels: said so, not 0.50.
    let mut lonely = grid.clone();
    lonely.hp_mean.iter_mut().for_each(|h| *h = EMPTY_VOXEL_HP);
    let hit = lonely
        .pick(Vec3::new(-3.0, 0.125, 0.125), Vec3::X, 0.5)
        .expect("hit");
    assert!(hit.hp_mean.is_nan());
    let readings = voxel_readings(
        &loudscape::data::axes::Axes::generic([(-1.0, 1.0); 3]),
        &hit,
    );
    assert!(readings.iter().any(|r| r.value == "no points nearby"));
}

/// The year under the cursor on a timeline comes from the song spans: two 1987 songs side by
/// side both read 1987, and songs placed by order (not by year) read their own year.
#[test]
fn the_timeline_year_comes_from_the_song_spans() {
    use loudscape::data::axes::{Axes, Axis};
    use loudscape::view::pick::timeline_year;
    let axes = Axes {
        x: Axis::linear("year", "year", 1980.0, 2010.0),
        ..Axes::generic([(-1.0, 1.0); 3])
    };
    let song = |year: i32, a: f64, b: f64| SongInfo {
        year: Some(year),
        x_min: Some(a),
        x_max: Some(b),
        ..Default::default()
    };
    // By order: a 2005 song in the middle, where the linear map says 1995.
    let songs = vec![
        song(1987, -1.0, -0.6),
        song(1987, -0.6, -0.2),
        song(2005, -0.2, 0.3),
        song(2009, 0.5, 1.0),
    ];
    let year = |x: f32| timeline_year(&axes, &songs, x).map(|r| r.value);
    assert_eq!(year(-0.9).as_deref(), Some("1987"));
    assert_eq!(year(-0.3).as_deref(), Some("1987"));
    assert_eq!(year(0.0).as_deref(), Some("2005"));
    assert_eq!(year(0.4), None, "between songs there is no year");
    assert_eq!(
        timeline_year(&axes, &songs, 0.0).unwrap().name,
        "year",
        "named as the axis"
    );
    // Without spans, the axis's own map is all there is.
    assert!(timeline_year(&axes, &[], 0.0).is_some());
}

/// The Surface and Volume views' read-out, shared by the window and the web page: over a dense
/// voxel its position in the axes' units, its density and mean hp, and the x it reads at; where
/// the ray meets no dense voxel (or no grid is there yet), the time where it enters the box;
/// nothing where it misses the box.
#[test]
fn the_grid_readout_reads_the_first_dense_voxel_or_the_box() {
    use loudscape::view::pick::grid_readout;
    let cloud = grid_cloud();
    let axes = &cloud.meta.axes;
    let mut density = vec![0.0f32; 64];
    let mut hp = vec![0.5f32; 64];
    let idx = (1 + 4 * (2 + 4 * 2)) as usize;
    density[idx] = 0.8;
    hp[idx] = 0.9;
    let field = Field {
        dims: UVec3::splat(4),
        box_min: Vec3::splat(-1.0),
        box_max: Vec3::splat(1.0),
        density,
        hp_mean: hp,
    };
    let text = |readings: &[loudscape::view::pick::Reading]| {
        readings
            .iter()
            .map(|r| format!("{}: {}", r.name, r.value))
            .collect::<Vec<_>>()
    };
    let origin = Vec3::new(-3.0, 0.25, 0.25);
    let (readings, x) = grid_readout(Some(&field), axes, origin, Vec3::X, 0.5);
    assert_eq!(x, Some(-0.25));
    let lines = text(&readings);
    assert_eq!(lines.len(), 5, "{lines:?}");
    assert!(
        lines[0].starts_with("time: ") && lines[0].ends_with(" s"),
        "{lines:?}"
    );
    assert!(lines[1].contains("Hz"), "{lines:?}");
    assert!(lines[2].contains("dB"), "{lines:?}");
    assert_eq!(lines[3], "density: 0.800");
    assert_eq!(lines[4], "mean hp: 0.90 (harmonic)");

    // Above every voxel, or no grid yet: the time where the ray enters the box (x = -1).
    for field in [Some(&field), None] {
        let (readings, x) = grid_readout(field, axes, origin, Vec3::X, 0.9);
        assert_eq!(x, Some(-1.0));
        let lines = text(&readings);
        assert_eq!(lines.len(), 1, "{lines:?}");
        assert!(lines[0].starts_with("time: "), "{lines:?}");
    }
    // Beside the box: nothing.
    let (readings, x) = grid_readout(Some(&field), axes, Vec3::new(-3.0, 2.0, 0.0), Vec3::X, 0.5);
    assert!(readings.is_empty() && x.is_none());
}

/// The read-out's names by mode: a song's level is a bin level; a timeline's year comes from
/// its song spans (and goes between songs).
#[test]
fn readings_are_named_by_the_datas_mode() {
    use loudscape::data::axes::{Axes, Axis};
    use loudscape::view::pick::{Reading, name_readings};
    let reading = |name: &str, value: &str| Reading {
        name: name.into(),
        value: value.into(),
    };
    let cloud = grid_cloud();
    let mut readings = vec![reading("time", "1.0 s"), reading("level", "-23.4 dB")];
    name_readings(
        &mut readings,
        &cloud.meta.axes,
        DataMode::Song,
        &[],
        Some(0.0),
    );
    assert_eq!(readings[0].name, "time");
    assert_eq!(readings[1], reading("bin level", "-23.4 dB"));

    let axes = Axes {
        x: Axis::linear("year", "year", 1980.0, 2010.0),
        ..Axes::generic([(-1.0, 1.0); 3])
    };
    let songs = vec![SongInfo {
        year: Some(2005),
        x_min: Some(-1.0),
        x_max: Some(0.0),
        ..Default::default()
    }];
    let mut on_song = vec![reading("year", "1987"), reading("level", "-9 dB")];
    name_readings(&mut on_song, &axes, DataMode::Timeline, &songs, Some(-0.5));
    assert_eq!(on_song[0], reading("year", "2005"));
    assert_eq!(on_song[1].name, "level", "a timeline's level is a loudness");
    let mut between = vec![reading("year", "2000"), reading("level", "-9 dB")];
    name_readings(&mut between, &axes, DataMode::Timeline, &songs, Some(0.5));
    assert_eq!(between, vec![reading("level", "-9 dB")]);
}
