//! The window opens on the demo under a display (Xvfb in CI: `make test` runs the tests under
//! xvfb-run), draws the song, saves a screenshot of itself and closes.

use crate::common;

use std::path::PathBuf;

#[test]
fn window_opens_and_shows_the_demo() {
    let _screen = common::screen();
    common::assert_display();
    let repo = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let shot = common::output_dir().join("window_demo.png");
    let image = common::window_screenshot(&repo.join("data/demo_song.ply"), &shot);
    assert!(
        image.width() >= 640 && image.height() >= 400,
        "window too small: {:?}",
        image.dimensions()
    );
    // The 3D view (right of the side panel) must show the cloud: many pixels in the palette's
    // red and blue, not only the background.
    let (w, h) = image.dimensions();
    let mut coloured = 0usize;
    for y in 0..h {
        for x in (w / 4)..w {
            let p = image.get_pixel(x, y);
            let (r, g, b) = (i32::from(p[0]), i32::from(p[1]), i32::from(p[2]));
            if (r - b).abs() > 80 || (b - r) > 60 && b > 120 || r > 150 && g < 100 {
                coloured += 1;
            }
        }
    }
    let share = coloured as f64 / f64::from((w - w / 4) * h);
    assert!(
        share > 0.05,
        "the 3D view looks blank: {:.2}% coloured pixels",
        share * 100.0
    );
    // The side panel keeps egui's panel colour: the window is cleared to it and the panels are
    // drawn without a fill of their own (ui/app.rs `panel_frame`), so most of the panel's
    // pixels (all but its text and widgets) are exactly that colour.
    let fill = eframe::egui::Visuals::dark().panel_fill;
    let mut panel = 0usize;
    let mut same = 0usize;
    for y in 0..h {
        for x in 0..(w / 5) {
            let p = image.get_pixel(x, y);
            panel += 1;
            if (p[0], p[1], p[2]) == (fill.r(), fill.g(), fill.b()) {
                same += 1;
            }
        }
    }
    let share = same as f64 / panel as f64;
    assert!(
        share > 0.5,
        "the side panel is not egui's panel colour {fill:?}: {:.1}% of its pixels are",
        share * 100.0
    );
}
