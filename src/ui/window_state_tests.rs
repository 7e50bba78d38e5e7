//! Unit tests of the window's state driven through egui frames without a window or a GPU: the
//! status area stays in sight whatever the side panel holds, and the compare's B field keeps
//! what is typed before any compare exists.

use eframe::egui;

use crate::ui::app::WindowOptions;
use crate::ui::state::LoudscapeApp;

fn app() -> LoudscapeApp {
    // A scripted run (a screenshot path) remembers nothing and opens no audio device.
    let options = WindowOptions {
        screenshot: Some(std::env::temp_dir().join("loudscape-unit-never-written.png")),
        ..Default::default()
    };
    LoudscapeApp::new(options, None)
}

fn input(size: egui::Vec2, events: Vec<egui::Event>) -> egui::RawInput {
    egui::RawInput {
        screen_rect: Some(egui::Rect::from_min_size(egui::Pos2::ZERO, size)),
        events,
        ..Default::default()
    }
}

/// The text shapes of a frame whose text starts with `start`: where they are drawn and clipped.
fn texts_starting(output: &egui::FullOutput, start: &str) -> Vec<(egui::Rect, egui::Rect)> {
    output
        .shapes
        .iter()
        .filter_map(|clipped| match &clipped.shape {
            egui::Shape::Text(text) if text.galley.text().starts_with(start) => Some((
                text.galley.rect.translate(text.pos.to_vec2()),
                clipped.clip_rect,
            )),
            _ => None,
        })
        .collect()
}

#[test]
fn the_status_area_is_in_sight_under_a_side_panel_taller_than_the_window() {
    let mut app = app();
    app.messages
        .warn("no file dialog can open here: type a path");
    let ctx = egui::Context::default();
    let size = egui::vec2(800.0, 500.0);
    let mut last = None;
    for _ in 0..3 {
        let mut output = ctx.run_ui(input(size, Vec::new()), |ui| {
            egui::Panel::left("controls")
                .exact_size(270.0)
                .show(ui, |ui| {
                    egui::ScrollArea::vertical().show(ui, |ui| {
                        for i in 0..200 {
                            ui.label(format!("a control row {i}"));
                        }
                    });
                });
            app.status_area(ui);
            egui::CentralPanel::default().show(ui, |_| {});
        });
        output.textures_delta.clear();
        last = Some(output);
    }
    let output = last.unwrap();
    let shown = texts_starting(&output, "warning: no file dialog");
    assert_eq!(shown.len(), 1, "the warning is drawn once");
    let (rect, clip) = shown[0];
    let screen = egui::Rect::from_min_size(egui::Pos2::ZERO, size);
    assert!(
        screen.contains_rect(rect) && clip.contains_rect(rect),
        "the warning {rect:?} is cut (clip {clip:?}, screen {screen:?})"
    );
    assert!(
        rect.left() >= 270.0,
        "under the view, not in the side panel: {rect:?}"
    );
    assert!(rect.top() > size.y * 0.5, "at the bottom: {rect:?}");
}

#[test]
fn the_b_field_keeps_typing_before_any_compare() {
    let mut app = app();
    let ctx = egui::Context::default();
    let size = egui::vec2(800.0, 600.0);
    let frame = |app: &mut LoudscapeApp, events: Vec<egui::Event>, focus: bool| {
        let mut output = ctx.run_ui(input(size, events), |ui| {
            if focus {
                ui.ctx().memory_mut(|m| {
                    m.request_focus(egui::Id::unique(crate::ui::compare_window::COMPARE_FIELD))
                });
            }
            egui::Panel::left("controls")
                .exact_size(270.0)
                .show(ui, |ui| app.compare_controls(ui));
        });
        output.textures_delta.clear();
    };
    frame(&mut app, Vec::new(), false);
    frame(&mut app, Vec::new(), true);
    frame(
        &mut app,
        vec![egui::Event::Text("b-side.flac".into())],
        false,
    );
    assert_eq!(app.open.compare_path, "b-side.flac");
    assert!(app.compare.is_none(), "typing alone starts nothing");
    let enter = crate::ui::shortcuts::key_event("Enter").unwrap();
    frame(&mut app, vec![enter], false);
    frame(&mut app, Vec::new(), false);
    assert!(app.compare.is_none(), "no song (A) to compare with");
    assert!(
        app.messages.contains(
            crate::ui::state::messages::Kind::Warning,
            "open a song (A) first, then compare it with B"
        ),
        "Enter says why nothing happened"
    );
    assert_eq!(app.open.compare_path, "b-side.flac", "the field keeps it");
}

#[test]
fn a_low_isovalue_says_why_the_surface_is_grey_and_zero_is_not_offered() {
    let mut app = app();
    let ctx = egui::Context::default();
    let shown = |app: &mut LoudscapeApp, iso: f32| {
        app.settings.surface.iso_value = iso;
        let mut output = ctx.run_ui(input(egui::vec2(800.0, 600.0), Vec::new()), |ui| {
            egui::Panel::left("controls")
                .exact_size(270.0)
                .show(ui, |ui| app.surface_controls(ui));
        });
        output.textures_delta.clear();
        !texts_starting(&output, "low isovalue").is_empty()
    };
    assert!(shown(&mut app, 0.05));
    assert!(!shown(&mut app, 0.5));
    shown(&mut app, 0.0);
    assert!(
        app.settings.surface.iso_value >= crate::ui::panels::MIN_ISOVALUE,
        "the slider keeps the isovalue above 0: {}",
        app.settings.surface.iso_value
    );
}

/// At 500x400 the side panel's rows ran past its edge (Folder…, Compare with…, Volume, Mel,
/// the sliders' names), scrolled sideways out of sight: the rows now wrap and the sliders
/// narrow, so every button and name in the panel is whole within its 200 points, in the Points
/// and the Volume view.
#[test]
fn a_small_windows_side_panel_cuts_no_button_or_name() {
    let mut app = app();
    let ctx = egui::Context::default();
    let width = crate::ui::app::side_panel_width(500.0);
    assert!(width <= 200.0);
    // Tall enough to show every row: only the width is tested.
    let size = egui::vec2(500.0, 3000.0);
    let names = [
        "Open…",
        "Folder…",
        "Compare with…",
        "Points",
        "Surface",
        "Volume",
        "Linear",
        "Logarithmic",
        "Mel",
        "size (px)",
        "min loudness",
        "hp colour map",
        "Save PNG",
        "Export video…",
        "voxels/side",
        "smoothing σ",
        "opacity scale",
        "step (voxels)",
    ];
    let mut seen = std::collections::BTreeSet::new();
    for view in [
        crate::render::scene::ViewKind::Points,
        crate::render::scene::ViewKind::Volume,
    ] {
        app.settings.view = view;
        let mut last = None;
        for _ in 0..3 {
            let mut output = ctx.run_ui(input(size, Vec::new()), |ui| {
                egui::Panel::left("controls")
                    .resizable(false)
                    .exact_size(width)
                    .show(ui, |ui| app.side_panel(ui));
            });
            output.textures_delta.clear();
            last = Some(output);
        }
        let output = last.unwrap();
        for name in names {
            for (rect, clip) in texts_starting(&output, name) {
                seen.insert(name);
                assert!(
                    rect.right() <= clip.right() + 0.5 && rect.right() <= width + 0.5,
                    "{view:?}: '{name}' is cut at the panel's edge: {rect:?} (clip {clip:?})"
                );
            }
        }
    }
    // The song-only rows (frequency axis, points) need no song to be laid out; what is drawn
    // must include the buttons the walk found cut.
    for name in ["Folder…", "Compare with…", "Volume", "opacity scale"] {
        assert!(seen.contains(name), "'{name}' is drawn: {seen:?}");
    }
}
