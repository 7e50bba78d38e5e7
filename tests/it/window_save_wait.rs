//! Save PNG pressed while the view is still filling in, and in the Surface and Volume views:
//! the frame of the click draws nothing for the picture. The save waits for the view to finish
//! (the progressive points, the volume's bands), the window drawing frames meanwhile, and then
//! copies the view's own picture (`ViewResources::shown_picture`), which equals a fresh render
//! of the same size. Needs a display (`make test` runs it under xvfb-run).

use crate::common;
use crate::window_save_big::{frames_while_saving, save_in_view};

/// The frames the save waited for the view ("…; waited N frames for the view to fill in"),
/// none when it did not wait.
fn frames_waited(line: &str) -> u32 {
    line.split_once("; waited ")
        .and_then(|(_, rest)| rest.split_whitespace().next())
        .map(|n| n.parse().unwrap_or_else(|_| panic!("no count in {line:?}")))
        .unwrap_or(0)
}

/// The same picture saved at the chosen size equal to `copied`'s: drawn for the picture over
/// frames (the surface in one render, in the frame after the click).
fn rendered_like(
    copied: &image::RgbaImage,
    song: &std::path::Path,
    dir: &std::path::Path,
    view: &str,
) -> image::RgbaImage {
    let (w, h) = copied.dimensions();
    let size = format!("shot-size={w}x{h}");
    let (rendered, line) = save_in_view(song, dir, view, &["when-drawn", &size, "Ctrl+S"]);
    println!("{view}, drawn for the picture: {line}");
    let how = if view == "surface" {
        "(rendered for the picture"
    } else {
        "(drawn for the picture in slices; waited "
    };
    assert!(line.contains(how), "{line}");
    assert_eq!(rendered.dimensions(), (w, h));
    rendered
}

/// Ctrl+S as soon as a song of 1.5 M points is shown, its points still coming in a slice a
/// frame: the save waits frames for the view and copies its picture, the same pixels as a
/// fresh render.
#[test]
fn save_png_while_the_points_fill_in_waits_and_copies_the_view() {
    let _screen = common::screen();
    common::assert_display();
    let home = common::fresh_dir("window_save_wait_points");
    let song = home.join("synthetic_1m5.ply");
    common::write_synthetic_song(&song, 1_500_000, 5);

    let (copied, line) = save_in_view(&song, &home.join("copied"), "points", &["Ctrl+S"]);
    println!("points, copied: {line}");
    assert!(
        line.contains("(the view's picture, copied; waited "),
        "the points were drawn for the picture in the frame of the click: {line}"
    );
    assert!(frames_waited(&line) >= 1, "{line}");
    assert!(frames_while_saving(&line) >= frames_waited(&line), "{line}");
    assert!(common::coverage(&copied) > 0.05, "the picture looks blank");

    let rendered = rendered_like(&copied, &song, &home.join("rendered"), "points");
    let (share, _) = common::difference(&copied, &rendered, 0);
    if share > 0.0 {
        let _ = copied.save(home.join("copied.png"));
        let _ = rendered.save(home.join("rendered.png"));
    }
    assert_eq!(share, 0.0, "differs in {:.3}% of pixels", share * 100.0);
}

/// Saves the view `view` of a 300,000-point song pressing `press`, asserts the picture is the
/// view's own, copied, and returns it with the same picture rendered at its size.
fn copied_and_rendered(view: &str, press: &[&str]) -> (image::RgbaImage, image::RgbaImage) {
    let home = common::fresh_dir(&format!("window_save_wait_{view}"));
    let song = home.join("synthetic_300k.ply");
    common::write_synthetic_song(&song, 300_000, 5);
    let (copied, line) = save_in_view(&song, &home.join("copied"), view, press);
    println!("{view}, copied: {line}");
    assert!(
        line.contains("(the view's picture, copied"),
        "the {view} was rendered again for the picture in the frame of the click: {line}"
    );
    assert!(
        common::coverage(&copied) > 0.05,
        "{view}: the picture looks blank"
    );
    let rendered = rendered_like(&copied, &song, &home.join("rendered"), view);
    let _ = copied.save(home.join("copied.png"));
    let _ = rendered.save(home.join("rendered.png"));
    (copied, rendered)
}

/// The Volume view, Ctrl+S while its bands still come in: the save waits for them and copies
/// the view's picture, which equals a fresh render within the jitter of the ray starts (one
/// render's jitter is its frame's: the refinement's first frame and the frame of the click
/// differ).
#[test]
fn save_png_of_the_volume_waits_for_its_bands_and_copies_the_view() {
    let _screen = common::screen();
    common::assert_display();
    let (copied, rendered) = copied_and_rendered("volume", &["Ctrl+S"]);
    let (share, mean) = common::difference(&copied, &rendered, 24);
    println!(
        "volume: {:.4}% of pixels differ by over 24, mean {mean:.3}",
        share * 100.0
    );
    assert!(
        share < 0.01 && mean < 2.0,
        "the copy differs from a fresh render in {:.3}% of pixels, mean {mean:.3}",
        share * 100.0
    );
}

/// The Surface view at rest: the view's picture, copied, the same pixels as a fresh render.
#[test]
fn save_png_of_the_surface_copies_the_view() {
    let _screen = common::screen();
    common::assert_display();
    let (copied, rendered) = copied_and_rendered("surface", &["when-drawn", "Ctrl+S"]);
    let (share, _) = common::difference(&copied, &rendered, 0);
    assert_eq!(share, 0.0, "differs in {:.3}% of pixels", share * 100.0);
}

/// A chosen size other than the view's, Ctrl+S as soon as the song is shown: the points are
/// drawn for the picture a slice a frame at the camera of the click, the window drawing
/// frames meanwhile, and the PNG has the chosen size and shows the cloud.
#[test]
fn save_png_at_a_chosen_size_draws_its_points_over_frames() {
    let _screen = common::screen();
    common::assert_display();
    let home = common::fresh_dir("window_save_wait_size");
    let song = home.join("synthetic_1m5.ply");
    common::write_synthetic_song(&song, 1_500_000, 5);
    let (picture, line) = save_in_view(&song, &home, "points", &["shot-size=900x500", "Ctrl+S"]);
    println!("chosen size: {line}");
    assert!(
        line.contains("(drawn for the picture in slices; waited "),
        "the points were drawn whole in the frame of the click: {line}"
    );
    // 1.5 M points at 200,000 points in the first slice, at most twice more in each next.
    assert!(frames_waited(&line) >= 2, "{line}");
    assert_eq!(picture.dimensions(), (900, 500));
    assert!(common::coverage(&picture) > 0.05, "the picture looks blank");
}

/// The window asked to close while a save waits for the view to fill in (Ctrl+S on a 1.5
/// M-point song and the close button's request in the same frame: `--press close-window`, the
/// request the window system sends): it stays open until the PNG is written, says so, then
/// closes with status 0, the PNG whole. It used to close at once and write nothing.
#[test]
fn closing_the_window_while_a_save_waits_writes_the_png_first() {
    let _screen = common::screen();
    common::assert_display();
    let home = common::fresh_dir("window_save_wait_close");
    let song = home.join("synthetic_1m5.ply");
    common::write_synthetic_song(&song, 1_500_000, 5);
    let mut command = std::process::Command::new(env!("CARGO_BIN_EXE_loudscape"));
    let child = common::no_dialog(common::home_in(&mut command, &home))
        .current_dir(&home)
        .arg(&song)
        .args(["--press", "Ctrl+S", "--press", "close-window"])
        .stderr(std::process::Stdio::piped())
        .stdout(std::process::Stdio::null())
        .spawn()
        .expect("start loudscape");
    common::while_running(child, |child, lines| {
        let mut seen = Vec::new();
        let timeout = std::time::Duration::from_secs(120);
        let waiting = common::line_starting(lines, "loudscape: saving ", timeout, &mut seen)
            .unwrap_or_else(|| panic!("the save never started:\n{}", seen.join("\n")));
        assert!(
            waiting.ends_with("(waiting for the view to fill in)"),
            "the save did not wait for the view, so closing tests nothing: {waiting}"
        );
        let closing = common::line_starting(lines, "loudscape: closing once ", timeout, &mut seen)
            .unwrap_or_else(|| panic!("the window did not say it waits:\n{}", seen.join("\n")));
        assert!(
            closing.contains("close again to quit without it"),
            "{closing}"
        );
        let saved = common::line_starting(lines, "loudscape: saved ", timeout, &mut seen)
            .unwrap_or_else(|| panic!("the PNG was not saved:\n{}", seen.join("\n")));
        let deadline = std::time::Instant::now() + timeout;
        let status = loop {
            if let Some(status) = child.try_wait().expect("wait") {
                break status;
            }
            assert!(
                std::time::Instant::now() < deadline,
                "the window did not close once saved: {saved}"
            );
            std::thread::sleep(std::time::Duration::from_millis(100));
        };
        assert!(status.success(), "{status}: {}", seen.join("\n"));
        let pictures = common::saved_pictures(&home);
        assert_eq!(pictures.len(), 1, "{pictures:?}");
        assert!(
            saved.contains(&pictures[0].display().to_string()),
            "{saved}"
        );
        let image = image::open(&pictures[0]).expect("a whole PNG").to_rgba8();
        assert!(common::coverage(&image) > 0.05, "the picture looks blank");
    });
}
