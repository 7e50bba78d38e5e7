//! Song mode shows the loudness strip under the 3D view when the cloud carries loudness curves
//! (Xvfb in CI: `make test` runs the tests under xvfb-run): the demo song with synthetic curves
//! written into its metadata, a screenshot of the window, the strip's colours found under the
//! view.

use crate::common;

use std::path::PathBuf;

use loudscape::data::cloud;

/// Pixels within `tolerance` per channel of `colour` in rows `rows` right of `x0`.
fn count_colour(
    image: &image::RgbaImage,
    colour: [u8; 3],
    tolerance: i32,
    rows: std::ops::Range<u32>,
    x0: u32,
) -> usize {
    let mut n = 0;
    for y in rows {
        for x in x0..image.width() {
            let p = image.get_pixel(x, y);
            if (0..3).all(|c| (i32::from(p[c]) - i32::from(colour[c])).abs() <= tolerance) {
                n += 1;
            }
        }
    }
    n
}

#[test]
fn song_mode_shows_the_loudness_strip_under_the_view() {
    let _screen = common::screen();
    common::assert_display();
    let repo = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let demo = cloud::load(&repo.join("data/demo_song.ply")).expect("demo song");
    let duration = demo
        .meta
        .source
        .as_ref()
        .and_then(|s| s.duration_s)
        .unwrap_or(30.0);
    let n = (duration * 10.0) as usize;
    let wave = |i: usize, base: f64, depth: f64| base + depth * (i as f64 * 0.05).sin();
    let mut meta = demo.meta.raw.clone();
    meta["loudness"] = serde_json::json!({
        "rate_hz": 10.0,
        "momentary_start_s": 0.2,
        "momentary_lufs": (0..n).map(|i| wave(i, -14.0, 8.0)).collect::<Vec<_>>(),
        "short_term_start_s": 1.5,
        "short_term_lufs": (0..n.saturating_sub(26)).map(|i| wave(i, -14.0, 5.0)).collect::<Vec<_>>(),
        "psr_db": (0..n.saturating_sub(26)).map(|i| wave(i, 11.0, 3.0)).collect::<Vec<_>>(),
        "overs_0dbtp": [[duration * 0.3, duration * 0.32], [duration * 0.7, duration * 0.75]],
        "overs_0dbtp_count": 2,
        "overs_1dbtp": [[duration * 0.29, duration * 0.33]],
        "overs_1dbtp_count": 1,
    });
    let out = common::output_dir();
    let ply = out.join("strip_song.ply");
    let mut file = std::io::BufWriter::new(std::fs::File::create(&ply).expect("create ply"));
    cloud::write(&mut file, &demo.points, Some(&meta)).expect("write ply");
    drop(file);
    let shot = out.join("window_strip.png");
    let image = common::window_screenshot(&ply, &shot);
    let (w, h) = image.dimensions();
    assert!(w >= 640 && h >= 400, "window too small: {w}x{h}");
    // The strip sits under the view, above the transport bar: the bottom 200 rows, right of the
    // side panel (270 points wide).
    let rows = h.saturating_sub(200)..h;
    let short_term = count_colour(&image, [120, 200, 255], 20, rows.clone(), 280);
    let psr = count_colour(&image, [255, 170, 60], 20, rows.clone(), 280);
    let overs = count_colour(&image, [235, 60, 60], 20, rows.clone(), 280);
    assert!(
        short_term > 300,
        "no short-term loudness line: {short_term} pixels"
    );
    assert!(psr > 300, "no PSR line: {psr} pixels");
    assert!(overs > 20, "no true-peak overs marked: {overs} pixels");
    // and not elsewhere: the top half of the window has none of the short-term line's colour
    let above = count_colour(&image, [120, 200, 255], 6, 0..h / 2, 280);
    assert!(
        above < short_term / 4,
        "{above} short-term pixels above the strip"
    );
}
