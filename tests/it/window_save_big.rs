//! Save PNG of a large cloud at full detail does not draw its points again: the window copies
//! the view's own picture (`ViewResources::shown_picture`) in the frame of Ctrl+S, where
//! drawing 1.5 M points on a software GPU held the window for seconds, and a thread reads it
//! back, draws the labels and writes the PNG while the window goes on drawing frames. The PNG
//! is the picture that drawing it again at the same size, chosen in the panel, gives (a slice
//! of the points a frame into a target of the save's own, `ui/save_slices.rs`). Needs a display
//! (`make test` runs it under xvfb-run).

use crate::common;

use std::path::Path;
use std::process::Command;

/// Points in the synthetic song: several frames' budget of progressive points
/// (`ui/progressive.rs`), so the view fills in over frames before Ctrl+S.
const POINTS: usize = 1_500_000;

/// Runs the window on `song` in `dir`, presses `press` once every point is drawn, and returns
/// the one PNG Ctrl+S saved there (no dialog can open) and the window's "picture: saved" line.
fn save(song: &Path, dir: &Path, press: &[&str]) -> (image::RgbaImage, String) {
    let mut presses = vec!["when-drawn"];
    presses.extend_from_slice(press);
    save_in_view(song, dir, "points", &presses)
}

/// As [`save`], in the view `view` (`--view`), pressing `press` as soon as the song is shown
/// (a `when-drawn` among them waits for the view at full detail).
pub(crate) fn save_in_view(
    song: &Path,
    dir: &Path,
    view: &str,
    press: &[&str],
) -> (image::RgbaImage, String) {
    std::fs::create_dir_all(dir).unwrap();
    let mut command = Command::new(env!("CARGO_BIN_EXE_loudscape"));
    common::no_dialog(common::home_in(&mut command, dir))
        .current_dir(dir)
        .arg(song)
        .args(["--view", view])
        .arg("--screenshot")
        .arg(dir.join("window.png"));
    let err = common::run_pressing(&mut command, press);
    let saved = common::saved_pictures(dir);
    assert_eq!(saved.len(), 1, "one PNG saved: {saved:?}\n{err}");
    let line = err
        .lines()
        .find(|l| l.starts_with("picture: saved in "))
        .unwrap_or_else(|| panic!("no line saying how the picture was saved: {err}"))
        .to_string();
    (image::open(&saved[0]).unwrap().to_rgba8(), line)
}

/// The frames the window drew while the picture was saved ("… while the window drew N
/// frames").
pub(crate) fn frames_while_saving(line: &str) -> u32 {
    line.split_whitespace()
        .rev()
        .nth(1)
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("no frame count in {line:?}"))
}

#[test]
fn save_png_of_a_big_cloud_copies_the_view_and_equals_a_fresh_render() {
    let _screen = common::screen();
    common::assert_display();
    let home = common::fresh_dir("window_save_big");
    let song = home.join("synthetic_1m5.ply");
    common::write_synthetic_song(&song, POINTS, 5);

    // At the view's size (the default): the view's picture, copied.
    let copied_dir = home.join("copied");
    std::fs::create_dir_all(&copied_dir).unwrap();
    let (copied, line) = save(&song, &copied_dir, &["Ctrl+S"]);
    assert!(
        line.contains("(the view's picture, copied)"),
        "the points were drawn again for the picture: {line}"
    );
    // The copy is read back and written on the thread (often within the frame after it).
    println!("copied: {line}, {} frames", frames_while_saving(&line));
    assert!(
        common::coverage(&copied) > 0.05,
        "the copied picture looks blank"
    );

    // The same size chosen in the panel: drawn again for the picture, a slice a frame into a
    // target of its own (the window drawing frames meanwhile), not in the frame of the click.
    let (w, h) = copied.dimensions();
    let rendered_dir = home.join("rendered");
    std::fs::create_dir_all(&rendered_dir).unwrap();
    let size = format!("shot-size={w}x{h}");
    let (rendered, line) = save(&song, &rendered_dir, &[&size, "Ctrl+S"]);
    println!("drawn in slices: {line}");
    assert!(
        line.contains("(drawn for the picture in slices; waited "),
        "the points were drawn whole in the frame of the click: {line}"
    );
    assert!(frames_while_saving(&line) >= 2, "{line}");
    assert_eq!(rendered.dimensions(), (w, h));
    // The same pixels: the slices of the view and of the save end as the single pass, the
    // labels are drawn by the same code on the CPU.
    let (share, _) = common::difference(&copied, &rendered, 0);
    if share > 0.0 {
        let _ = copied.save(home.join("copied.png"));
        let _ = rendered.save(home.join("rendered.png"));
    }
    assert_eq!(
        share,
        0.0,
        "the copied picture differs from the one drawn for it in {:.3}% of pixels (both in {})",
        share * 100.0,
        home.display()
    );
}
