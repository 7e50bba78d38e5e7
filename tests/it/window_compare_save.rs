//! Save PNG while comparing saves what the view shows: in side by side both halves (A, the
//! gap, B), in the difference view the difference picture, not A alone; the picture is read
//! back, encoded and written on a thread while the window goes on drawing frames. Needs a
//! display (`make test` runs it under xvfb-run).

use crate::common;

use std::path::{Path, PathBuf};
use std::process::Command;

/// Runs the window on the demo song compared with itself, presses `press`, and
/// returns the one PNG Ctrl+S saved (no dialog can open: it lands in the current folder) and
/// what the window wrote on stderr.
fn save(dir: &Path, press: &[&str]) -> (image::RgbaImage, String) {
    let repo = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    save_song(&repo.join("data/demo_song.ply"), dir, &[], press)
}

/// As [`save`], `song` compared with itself, the window started with `args` besides.
fn save_song(song: &Path, dir: &Path, args: &[&str], press: &[&str]) -> (image::RgbaImage, String) {
    let _ = std::fs::remove_dir_all(dir);
    std::fs::create_dir_all(dir).unwrap();
    let mut command = Command::new(env!("CARGO_BIN_EXE_loudscape"));
    command
        .current_dir(dir)
        .env("DBUS_SESSION_BUS_ADDRESS", "")
        .env("PATH", "/usr/bin/false-folder-without-zenity")
        .arg(song)
        .arg("--compare")
        // B is A again: its audio is found, so no message changes the view's size between
        // runs, and the difference picture is still unlike A's points.
        .arg(song)
        .args(args)
        .arg("--screenshot")
        .arg(dir.join("window.png"));
    let err = common::run_pressing(&mut command, press);
    let saved = common::saved_pictures(dir);
    assert_eq!(saved.len(), 1, "one PNG saved: {saved:?}\n{err}");
    assert!(
        err.contains(&format!("saving {}…", saved[0].display()))
            && err.contains(&format!("saved {}", saved[0].display())),
        "the window says where, first while it saves: {err}"
    );
    (image::open(&saved[0]).unwrap().to_rgba8(), err)
}

/// The frames the window drew while the picture was saved, from its log line
/// ("picture: saved in T ms on a thread, while the window drew N frames").
fn frames_while_saving(err: &str) -> u32 {
    let line = err
        .lines()
        .find(|l| l.starts_with("picture: saved in "))
        .unwrap_or_else(|| panic!("no line saying how the picture was saved: {err}"));
    line.split_whitespace()
        .rev()
        .nth(1)
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("no frame count in {line:?}"))
}

#[test]
fn save_png_while_comparing_saves_what_the_view_shows() {
    let _screen = common::screen();
    assert!(
        std::env::var_os("DISPLAY").is_some(),
        "this test needs a display: run it under xvfb-run"
    );
    let out = common::output_dir();
    // A large picture: its read-back, labels and PNG take several of the window's frames, which
    // go on meanwhile (the frame of Ctrl+S is not counted).
    let (side, err) = save(
        &out.join("compare_save_side"),
        &["shot-size=2400x1500", "compare=side", "Ctrl+S"],
    );
    let frames = frames_while_saving(&err);
    assert!(
        frames >= 1,
        "the window drew no frame while the picture was saved: {err}"
    );
    let (w, h) = side.dimensions();
    assert_eq!((w, h), (2400, 1500), "the chosen size");
    // The gap between the halves, in the compare picture's gap colour, runs down the middle.
    let gap = loudscape::ui::compare_shot::GAP;
    let half = (w - gap) / 2;
    let gap_rows = (0..h)
        .filter(|&y| {
            let p = side.get_pixel(half + gap / 2, y);
            (p[0], p[1], p[2]) == (90, 96, 110)
        })
        .count();
    assert!(
        gap_rows as f64 > 0.95 * f64::from(h),
        "no gap between two halves in the {w}x{h} picture ({gap_rows} rows)"
    );
    // Both halves hold the song's points, read back whole.
    for region in [[0, 0, half, h], [half + gap, 0, w, h]] {
        let share = common::coloured_share(&side, region);
        assert!(share > 0.01, "half {region:?} looks blank ({share:.3})");
    }

    let (difference, _) = save(
        &out.join("compare_save_difference"),
        &["shot-size=900x500", "compare=difference", "Ctrl+S"],
    );
    let (only_a, err) = save(
        &out.join("compare_save_off"),
        &["shot-size=900x500", "compare=off", "Ctrl+S"],
    );
    // The single view's Save PNG goes the same way.
    frames_while_saving(&err);
    assert_eq!(difference.dimensions(), only_a.dimensions());
    let (share, _) = common::difference(&difference, &only_a, 40);
    assert!(
        share > 0.05,
        "the difference picture looks like A alone ({:.1}% of pixels differ)",
        share * 100.0
    );
}

/// The line saying how the picture was saved ("picture: saved in T ms on a thread (how…").
fn saved_line(err: &str) -> String {
    err.lines()
        .find(|l| l.starts_with("picture: saved in "))
        .unwrap_or_else(|| panic!("no line saying how the picture was saved: {err}"))
        .to_string()
}

/// The frames the save waited for the view or its slices ("…; waited N frames …").
fn frames_waited(line: &str) -> u32 {
    line.split_once("; waited ")
        .and_then(|(_, rest)| rest.split_whitespace().next())
        .map(|n| n.parse().unwrap_or_else(|_| panic!("no count in {line:?}")))
        .unwrap_or(0)
}

/// Save PNG at the view's size while comparing never draws the compare for the picture: it
/// copies what the view shows once complete; at a chosen size it draws both halves for the
/// save over frames. The two are the same picture at the same size, side by side and in the
/// Difference view. A song of 600,000 points compared with itself is more than a frame's
/// points: Ctrl+S as soon as it is shown waits frames for both halves to fill in, and at a
/// chosen size draws them a slice a frame.
#[test]
fn save_png_while_comparing_copies_the_view_or_draws_it_over_frames() {
    let _screen = common::screen();
    common::assert_display();
    let home = common::fresh_dir("window_compare_save_copy");
    let song = home.join("synthetic_600k.ply");
    common::write_synthetic_song(&song, 600_000, 5);
    for layout in ["side", "difference"] {
        let compare = format!("compare={layout}");
        let dir = home.join(format!("{layout}_copied"));
        let (copied, err) = save_song(&song, &dir, &[], &[&compare, "Ctrl+S"]);
        let line = saved_line(&err);
        println!("{layout}, copied: {line}");
        assert!(
            line.contains("(the view's picture, copied"),
            "{layout}: the compare was drawn for the picture in the frame of the click: {line}"
        );
        if layout == "side" {
            assert!(
                frames_waited(&line) >= 1,
                "no frame drawn while both halves filled in: {line}"
            );
        }
        // The song against itself differs nowhere: the Difference view shows its box, title and
        // legend over an empty grid.
        if layout == "side" {
            assert!(common::coverage(&copied) > 0.05, "{layout}: looks blank");
        }
        let (w, h) = copied.dimensions();
        let size = format!("shot-size={w}x{h}");
        let dir = home.join(format!("{layout}_drawn"));
        let (drawn, err) = save_song(&song, &dir, &[], &[&size, &compare, "Ctrl+S"]);
        let line = saved_line(&err);
        println!("{layout}, drawn: {line}");
        assert!(
            line.contains("(drawn for the picture in slices"),
            "{layout}: the compare was drawn whole in the frame of the click: {line}"
        );
        if layout == "side" {
            assert!(
                frames_waited(&line) >= 1,
                "both halves drawn in one frame: {line}"
            );
        }
        assert_eq!(drawn.dimensions(), (w, h));
        let (share, mean) = common::difference(&copied, &drawn, 24);
        println!(
            "{layout}: {:.4}% of pixels differ by over 24, mean {mean:.3}",
            share * 100.0
        );
        if share > 0.0 {
            let _ = copied.save(home.join(format!("{layout}_copied.png")));
            let _ = drawn.save(home.join(format!("{layout}_drawn.png")));
        }
        assert!(
            share < 0.01 && mean < 2.0,
            "{layout}: the view's picture and the one drawn over frames differ in {:.3}% of \
             pixels, mean {mean:.3}",
            share * 100.0
        );
    }
}

/// Side by side in the Surface and Volume views: Ctrl+S as soon as the compare is shown waits
/// for the grids and the surfaces the view builds in the background (never built for the
/// picture in a frame), then copies the view's picture, which equals the one drawn for the
/// save at the same size (the volume within its ray jitter).
#[test]
fn save_png_of_surfaces_and_volumes_side_by_side_waits_for_the_view() {
    let _screen = common::screen();
    common::assert_display();
    let home = common::fresh_dir("window_compare_save_grids");
    let song = home.join("synthetic_300k.ply");
    common::write_synthetic_song(&song, 300_000, 5);
    for view in ["surface", "volume"] {
        let args = ["--view", view];
        let dir = home.join(format!("{view}_copied"));
        let (copied, err) = save_song(&song, &dir, &args, &["compare=side", "Ctrl+S"]);
        let line = saved_line(&err);
        println!("{view}, copied: {line}");
        assert!(
            line.contains("(the view's picture, copied"),
            "{view}: the compare was drawn for the picture in the frame of the click: {line}"
        );
        // The grids (and then the surfaces) come after the compare is shown: the click finds
        // them building, and the status says what the save waits for.
        assert!(
            err.contains("… (waiting for the grids)")
                || err.contains("… (waiting for the surfaces)"),
            "{view}: the save did not say it waits for the grids or surfaces: {err}"
        );
        assert!(common::coverage(&copied) > 0.05, "{view}: looks blank");
        let (w, h) = copied.dimensions();
        let size = format!("shot-size={w}x{h}");
        let dir = home.join(format!("{view}_drawn"));
        let (drawn, err) = save_song(&song, &dir, &args, &[&size, "compare=side", "Ctrl+S"]);
        let line = saved_line(&err);
        println!("{view}, drawn: {line}");
        assert!(
            line.contains("(drawn for the picture in slices"),
            "{view}: the compare was drawn whole in the frame of the click: {line}"
        );
        let (share, mean) = common::difference(&copied, &drawn, 24);
        println!(
            "{view}: {:.4}% of pixels differ by over 24, mean {mean:.3}",
            share * 100.0
        );
        if share > 0.0 {
            let _ = copied.save(home.join(format!("{view}_copied.png")));
            let _ = drawn.save(home.join(format!("{view}_drawn.png")));
        }
        assert!(
            share < 0.01 && mean < 2.0,
            "{view}: the view's picture and the one drawn over frames differ in {:.3}% of \
             pixels, mean {mean:.3}",
            share * 100.0
        );
    }
}

/// Side by side follows the selected view: in Volume both halves draw the volume (its density
/// colours), not the points (the song's saturated reds), and each half has its colour key.
#[test]
fn side_by_side_draws_the_selected_view_in_both_halves() {
    let _screen = common::screen();
    assert!(
        std::env::var_os("DISPLAY").is_some(),
        "this test needs a display: run it under xvfb-run"
    );
    let repo = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let shot = common::output_dir().join("window_side_by_side_volume.png");
    let _ = std::fs::remove_file(&shot);
    let run = |view: &str| {
        let output = Command::new(env!("CARGO_BIN_EXE_loudscape"))
            .arg(repo.join("data/demo_song.ply"))
            .arg("--compare")
            .arg(repo.join("data/demo_song.ply"))
            .args(["--view", view, "--screenshot"])
            .arg(&shot)
            .output()
            .expect("start loudscape");
        let err = String::from_utf8_lossy(&output.stderr).into_owned();
        assert!(output.status.success(), "loudscape failed: {err}");
        image::open(&shot).unwrap().to_rgba8()
    };
    // The points' red (percussive) pixels in each half of the view, right of the side panel.
    let reds = |image: &image::RgbaImage| {
        let (w, h) = image.dimensions();
        let left = 300;
        let middle = left + (w - left) / 2;
        let count = |x0: u32, x1: u32| {
            (0..h * 2 / 3)
                .flat_map(|y| (x0..x1).map(move |x| (x, y)))
                .filter(|&(x, y)| {
                    let p = image.get_pixel(x, y);
                    p[0] > 150 && p[1] < 90 && p[2] < 90
                })
                .count()
        };
        (count(left, middle), count(middle, w))
    };
    let points = reds(&run("points"));
    assert!(
        points.0 > 2000 && points.1 > 2000,
        "the points view shows red points in both halves: {points:?}"
    );
    let volume = reds(&run("volume"));
    assert!(
        volume.0 < points.0 / 20 && volume.1 < points.1 / 20,
        "in Volume the halves still draw points: {volume:?} red pixels (points: {points:?})"
    );
}
