//! The side panel: data slots, view, points, voxel grid, volume and surface controls, camera,
//! the timeline's song and what the file says about itself. A control that does nothing for
//! what is shown is disabled with the reason on hover: the compare in Timeline mode, and in the
//! compare's Difference view (always a volume of B - A in its own colours) the view buttons,
//! the surface's method and isovalue, the transfer function's choices.

use std::path::{Path, PathBuf};

use eframe::egui::{self, Color32, RichText};

use crate::data::cloud::{DataMode, PointCloud};
use crate::render::scene::ViewKind;
use crate::ui::compare_shot::CompareView;
use crate::ui::hover::song_title;
use crate::ui::labels;
use crate::ui::legends;
use crate::ui::state::LoudscapeApp;
use crate::ui::state::Slot;

/// The narrowest a slider's track gets in a narrow side panel, points.
const MIN_SLIDER_WIDTH: f32 = 50.0;

/// The track of a slider in a side panel whose rows are `available` points wide: egui's 100 at
/// the full width, narrower in a small window so the value and the slider's name still fit
/// beside it (about 110 points for "opacity scale" and its value).
pub(super) fn slider_width(available: f32) -> f32 {
    (available - 125.0).clamp(MIN_SLIDER_WIDTH, 100.0)
}

impl LoudscapeApp {
    /// The side panel's contents, scrolling down when taller than the window; never sideways:
    /// rows of buttons wrap and sliders narrow to the panel's width.
    pub(super) fn side_panel(&mut self, ui: &mut egui::Ui) {
        egui::ScrollArea::vertical().show(ui, |ui| {
            ui.spacing_mut().slider_width = slider_width(ui.available_width());
            self.controls(ui);
        });
    }

    pub(super) fn controls(&mut self, ui: &mut egui::Ui) {
        ui.horizontal(|ui| {
            ui.heading("loudscape");
            // On the title's line, where the Open row's buttons cannot push it past the edge.
            ui.with_layout(egui::Layout::right_to_left(egui::Align::Center), |ui| {
                if ui
                    .small_button("?")
                    .on_hover_text("keyboard shortcuts (?)")
                    .clicked()
                {
                    self.open.show_shortcuts = !self.open.show_shortcuts;
                }
            });
        });
        ui.add_space(4.0);
        self.open_controls(ui);
        if self.active == Slot::Timeline {
            // B is compared with the song (A): nothing here acts on a timeline. The reason
            // shows over the whole section (its disabled widgets take no hover of their own).
            let section = ui
                .add_enabled_ui(false, |ui| self.compare_controls(ui))
                .response;
            ui.interact(
                section.rect,
                ui.scope_id().with("compare-in-timeline"),
                egui::Sense::hover(),
            )
            .on_hover_text(COMPARE_IN_TIMELINE);
        } else {
            self.compare_controls(ui);
        }
        let difference = self.difference_shown();

        ui.label(RichText::new("Data").strong());
        ui.horizontal_wrapped(|ui| {
            for slot in [Slot::Song, Slot::Timeline] {
                let present = self.slot(slot).is_some();
                let response = ui.add_enabled(
                    present,
                    egui::Button::selectable(self.active == slot, slot.name()),
                );
                let response = if present {
                    response
                } else {
                    response.on_disabled_hover_text(format!(
                        "No {} cloud loaded: open one with `loudscape song.ply timeline.ply` or drop a .ply here",
                        slot.name().to_lowercase()
                    ))
                };
                if response.clicked() {
                    self.switch_slot(slot);
                }
            }
        });

        ui.add_space(6.0);
        ui.label(RichText::new("View").strong());
        ui.horizontal_wrapped(|ui| {
            for view in ViewKind::ALL {
                let response = ui
                    .add_enabled(
                        !difference,
                        egui::Button::selectable(self.settings.view == view, view.name()),
                    )
                    .on_disabled_hover_text(DIFFERENCE_DRAWS);
                if response.clicked() {
                    self.settings.view = view;
                }
            }
        });
        self.freq_axis_controls(ui);

        if self.settings.view == ViewKind::Points && !difference {
            ui.add_space(6.0);
            ui.label(RichText::new("Points").strong());
            if let Some(size) = self.active().map(|l| l.point_size) {
                self.settings.points.size_px = size;
            }
            let size_changed = ui
                .add(
                    egui::Slider::new(&mut self.settings.points.size_px, 1.0..=12.0)
                        .text("size (px)"),
                )
                .changed();
            if size_changed {
                let size = self.settings.points.size_px;
                match self.active {
                    Slot::Song => self.song.iter_mut().for_each(|l| l.point_size = size),
                    Slot::Timeline => self.timeline.iter_mut().for_each(|l| l.point_size = size),
                }
            }
            ui.add(
                egui::Slider::new(&mut self.settings.points.min_scalar, 0.0..=1.0)
                    .text("min loudness"),
            );
            legends::hp(ui, self.settings.colours.hp);
        }
        if self.settings.view != ViewKind::Points || difference {
            self.grid_controls(ui);
        }
        if self.settings.view == ViewKind::Volume || difference {
            self.volume_controls(ui, difference);
        }
        if self.settings.view == ViewKind::Surface {
            ui.add_enabled_ui(!difference, |ui| self.surface_controls(ui));
            if !difference {
                legends::surface(ui, self.settings.colours.hp);
            }
        }

        self.colour_controls(ui);

        ui.add_space(6.0);
        ui.label(RichText::new("Camera").strong());
        ui.horizontal_wrapped(|ui| {
            if ui
                .button("Fit (F)")
                .on_hover_text("Frame the data, keeping the viewing direction")
                .clicked()
            {
                self.motion.request_fit();
            }
            if ui
                .button("Reset (R)")
                .on_hover_text("The default viewing direction, framed")
                .clicked()
            {
                self.reset_view();
            }
            ui.checkbox(&mut self.settings.show_box, "axes");
        });
        ui.label(
            RichText::new(
                "Left drag: orbit · right/middle drag: pan · wheel: zoom · F: fit · R: reset",
            )
            .small()
            .weak(),
        );

        ui.add_space(6.0);
        self.screenshot_controls(ui);

        if self.active == Slot::Timeline {
            self.heard_choice(ui);
            self.timeline_song(ui);
        }

        if let Some(loaded) = self.active() {
            ui.add_space(8.0);
            ui.separator();
            cloud_info(ui, &loaded.cloud);
        }

        // At the end of the scrolling panel (a bottom-up layout inside the scroll area drew it
        // over the last lines when the window was small).
        ui.add_space(8.0);
        ui.label(
            RichText::new(format!(
                "{:.1} ms/frame · {} scene renders",
                self.clock.ms(),
                self.clock.renders
            ))
            .small()
            .weak(),
        )
        .on_hover_text(
            "Time of frames drawn one after another (waiting for input not counted); \
             the scene renders only when the camera, the data or a setting changed",
        );
    }

    pub(super) fn grid_controls(&mut self, ui: &mut egui::Ui) {
        ui.add_space(6.0);
        ui.label(RichText::new("Voxel grid").strong());
        let mode = self.active().map_or(DataMode::Song, |l| l.cloud.meta.mode);
        let mut resolution = self.settings.voxels.resolution_for(mode);
        let changed = ui
            .add(
                egui::Slider::new(
                    &mut resolution,
                    crate::render::grid::voxelize::MIN_RESOLUTION
                        ..=crate::render::grid::voxelize::MAX_RESOLUTION,
                )
                .step_by(16.0)
                .text("voxels/side"),
            )
            .on_hover_text("128 for songs and 224 for timelines by default; rebuilt on release")
            .drag_stopped();
        if changed {
            self.settings.voxels.resolution = Some(resolution);
        }
        let mut sigma = self.settings.voxels.smoothing_for(mode);
        if ui
            .add(egui::Slider::new(&mut sigma, 0.0..=8.0).text("smoothing σ"))
            .on_hover_text(
                "Gaussian smoothing of the grid in voxels: 1 for songs and 4 for timelines \
                 (a few hundred points a song) by default; rebuilt on release",
            )
            .drag_stopped()
        {
            self.settings.voxels.smoothing_sigma = Some(sigma);
        }
    }

    /// The volume's controls; in the Difference view (`difference`) only the density, opacity
    /// and step apply, the rest is disabled with the reason on hover.
    pub(super) fn volume_controls(&mut self, ui: &mut egui::Ui, difference: bool) {
        use crate::render::transfer::TransferPreset;
        ui.add_space(6.0);
        ui.label(RichText::new("Volume").strong());
        ui.add_enabled_ui(!difference, |ui| {
            let volume = &mut self.settings.volume;
            ui.horizontal_wrapped(|ui| {
                for preset in TransferPreset::ALL {
                    ui.selectable_value(&mut volume.preset, preset, preset.name())
                        .on_disabled_hover_text(DIFFERENCE_DRAWS);
                }
            });
            self.density_colour_controls(ui);
        });
        let volume = &mut self.settings.volume;
        if !difference {
            legends::transfer(ui, volume.preset, &self.settings.colours);
        }
        ui.add(egui::Slider::new(&mut volume.density_scale, 0.1..=4.0).text("density"));
        ui.add(egui::Slider::new(&mut volume.opacity_scale, 0.1..=4.0).text("opacity scale"));
        ui.add(
            egui::Slider::new(&mut volume.step_voxels, 0.25..=4.0)
                .logarithmic(true)
                .text("step (voxels)"),
        )
        .on_hover_text("Smaller steps: finer detail, slower frames");
        ui.add_enabled_ui(!difference, |ui| {
            ui.horizontal_wrapped(|ui| {
                ui.checkbox(&mut volume.hp_tint, "hp tint")
                    .on_hover_text("Colour by mean hp: red percussive to blue harmonic")
                    .on_disabled_hover_text(DIFFERENCE_DRAWS);
                ui.checkbox(&mut volume.shading, "shading")
                    .on_disabled_hover_text(DIFFERENCE_DRAWS);
            });
        });
    }

    pub(super) fn surface_controls(&mut self, ui: &mut egui::Ui) {
        use crate::render::surface::SurfaceMethod;
        ui.add_space(6.0);
        ui.label(RichText::new("Surface").strong());
        let surface = &mut self.settings.surface;
        ui.horizontal_wrapped(|ui| {
            for method in SurfaceMethod::ALL {
                ui.selectable_value(&mut surface.method, method, method.name())
                    .on_disabled_hover_text(DIFFERENCE_DRAWS);
            }
        });
        let slider = ui
            .add(isovalue_slider(&mut surface.iso_value))
            .on_hover_text(
                "The loudness density the surface encloses (above 0: at 0 it is only the \
                 grid's box, a grey solid with no hp colour)",
            )
            .on_disabled_hover_text(DIFFERENCE_DRAWS);
        if surface.iso_value < LOW_ISOVALUE {
            // What a low isovalue shows: the envelope of nearly every point, where percussive
            // and harmonic average out to the neutral middle of the hp colours.
            ui.label(
                RichText::new(
                    "low isovalue: the surface wraps almost every point, so its hp colour \
                     averages to neutral grey; raise it to see the loud parts and their colour",
                )
                .small()
                .weak(),
            );
        }
        let sweeping = self.iso_sweep.as_ref().is_some_and(|s| s.sweeping());
        if slider.dragged() || sweeping {
            self.surface.isovalue_dragged();
        }
        ui.checkbox(&mut surface.lit, "lit from above");
        if self.surface.busy {
            ui.horizontal_wrapped(|ui| {
                ui.spinner();
                ui.label("extracting surface…");
            });
        } else if let Some(error) = &self.surface.error {
            ui.colored_label(Color32::from_rgb(240, 120, 100), error);
        } else if self.surface.empty {
            ui.label(
                RichText::new("no surface at this isovalue: the density crosses it nowhere")
                    .color(Color32::from_rgb(230, 190, 110)),
            );
        }
    }

    /// The hovered or selected timeline song: who, when, how loud, and its own Song cloud.
    pub(super) fn timeline_song(&mut self, ui: &mut egui::Ui) {
        let Some(loaded) = self.timeline.as_ref() else {
            return;
        };
        let cloud = loaded.cloud.clone();
        let index = self.hovered_song.or(self.selected_song);
        ui.add_space(6.0);
        ui.label(RichText::new("Song").strong());
        let Some(song) = index.and_then(|i| cloud.meta.songs.get(i)) else {
            ui.label(
                RichText::new("Hover a song's span to see it; click to keep it.")
                    .small()
                    .weak(),
            );
            return;
        };
        ui.label(RichText::new(song_title(song)).strong());
        if let Some((name, gain)) = crate::ui::normalize::gain_reading(song) {
            ui.label(RichText::new(format!("{name}: {gain}")).small());
        }
        // Songs of one year share the year's span, each a narrow slice of it: pick them here.
        let same_year = songs_of_year(&cloud.meta.songs, song.year);
        if same_year.len() > 1 {
            let at = same_year
                .iter()
                .position(|&i| Some(i) == index)
                .unwrap_or(0);
            egui::ComboBox::from_id_salt("same-year-songs")
                .selected_text(format!(
                    "song {} of {} in {}",
                    at + 1,
                    same_year.len(),
                    song.year.unwrap_or_default()
                ))
                .show_ui(ui, |ui| {
                    for &i in &same_year {
                        let title = song_title(&cloud.meta.songs[i]);
                        if ui.selectable_label(Some(i) == index, title).clicked() {
                            self.selected_song = Some(i);
                        }
                    }
                });
        }
        for line in song
            .metrics
            .as_ref()
            .map(labels::describe_metrics)
            .unwrap_or_default()
        {
            ui.label(RichText::new(line).small());
        }
        match song_open_target(&cloud, song) {
            Some((path, how)) => {
                if ui
                    .button("Open in Song mode")
                    .on_hover_text(format!("{how}: {}", path.display()))
                    .clicked()
                {
                    self.start_loading(path);
                }
            }
            None => {
                ui.label(
                    RichText::new("Its audio is not where the timeline says, and no Song cloud of it is next to the timeline.")
                        .small()
                        .weak(),
                );
            }
        }
    }
}

impl LoudscapeApp {
    /// Whether the view shows the compare's Difference (a volume of B - A in its own colours).
    fn difference_shown(&self) -> bool {
        matches!(self.compare_shown_as(), Some(CompareView::Difference(_)))
    }
}

/// Why the view's, the surface's and the colour choices are disabled in the Difference view.
pub(super) const DIFFERENCE_DRAWS: &str = "The Difference view draws B - A as a volume in its \
    own diverging colours: only the voxel grid, density, opacity and step apply; choose A only \
    or Side by side for the views";

/// Why the compare section is disabled in Timeline mode.
pub(super) const COMPARE_IN_TIMELINE: &str = "A/B compare is for songs: B is compared with the \
    song (A). Switch Data to Song to compare";

/// The isovalue slider, its value always with two decimals (0.50, 1.00), so the number does not
/// change width or precision as it moves.
pub(super) fn isovalue_slider(iso_value: &mut f32) -> egui::Slider<'_> {
    egui::Slider::new(iso_value, MIN_ISOVALUE..=1.0)
        .text("isovalue")
        .fixed_decimals(2)
}

/// The songs (indices) of `year` in a timeline, in their order; none for an unknown year.
pub(super) fn songs_of_year(
    songs: &[crate::data::cloud::SongInfo],
    year: Option<i32>,
) -> Vec<usize> {
    songs
        .iter()
        .enumerate()
        .filter(|(_, s)| year.is_some() && s.year == year)
        .map(|(i, _)| i)
        .collect()
}

/// The isovalue slider's low end: at 0 the "surface" is the voxel grid's own box, a blocky grey
/// solid that shows nothing of the music.
pub(super) const MIN_ISOVALUE: f32 = 0.01;

/// Below this isovalue the side panel says why the surface is a grey envelope.
pub(super) const LOW_ISOVALUE: f32 = 0.15;

/// What the file says about itself: source, size and loudness metrics.
pub(super) fn cloud_info(ui: &mut egui::Ui, cloud: &PointCloud) {
    let name = match cloud.meta.mode {
        // A timeline built in the window: its songs' folder, not the cache's file name.
        DataMode::Timeline => legends::timeline_name(cloud),
        DataMode::Song | DataMode::Generic => cloud
            .path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default(),
    };
    ui.label(RichText::new(name).strong());
    ui.label(format!(
        "{} points",
        group_thousands(cloud.points.len() as u64)
    ));
    for line in crate::ui::labels::describe_cloud(cloud) {
        ui.label(RichText::new(line).small());
    }
    crate::ui::report_link::report_button(ui, cloud);
    // What the extractor found wrong or odd in the input (truncated, clipping...), by the
    // metrics it may have made less true.
    for warning in cloud.warnings() {
        let text = match &warning.path {
            Some(song) => format!("warning: {song}: {}", warning.message),
            None => format!("warning: {}", warning.message),
        };
        ui.label(
            RichText::new(text)
                .small()
                .color(ui.visuals().warn_fg_color),
        );
    }
}

pub(super) fn group_thousands(n: u64) -> String {
    let digits = n.to_string();
    let mut out = String::new();
    for (i, c) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i).is_multiple_of(3) {
            out.push('\u{2009}');
        }
        out.push(c);
    }
    out
}

/// What "Open in Song mode" opens for a timeline's song, and how to say it: its own Song cloud
/// next to it, else its audio (which opens as any song does: from the cloud cache when it was
/// extracted before, such as by a timeline built in the window, else extracted now).
pub(super) fn song_open_target(
    timeline: &PointCloud,
    song: &crate::data::cloud::SongInfo,
) -> Option<(PathBuf, &'static str)> {
    if let Some(cloud) = song_cloud_path(timeline, song) {
        return Some((cloud, "its Song cloud"));
    }
    let audio = song.open_path()?;
    let folder = timeline.path.parent().unwrap_or(Path::new(""));
    [audio.clone(), folder.join(&audio)]
        .into_iter()
        .find(|p| p.is_file())
        .map(|p| (p, "its audio, from the cloud cache or extracted now"))
}

/// The song's own Song cloud: same stem .ply next to the song's audio, or next to the timeline.
pub(super) fn song_cloud_path(
    timeline: &PointCloud,
    song: &crate::data::cloud::SongInfo,
) -> Option<PathBuf> {
    let audio = song.open_path()?;
    let stem = audio.file_stem()?;
    let mut name = stem.to_os_string();
    name.push(".ply");
    let folder = timeline.path.parent().unwrap_or(Path::new(""));
    let candidates = [
        audio.with_file_name(&name),
        folder
            .join(audio.parent().unwrap_or(Path::new("")))
            .join(&name),
        folder.join(&name),
    ];
    candidates
        .into_iter()
        .find(|p| p.is_file() && p != &timeline.path)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A timeline's song with no Song cloud beside it opens through its audio (the cloud cache
    /// then finds the cloud extracted before); with one beside it, that cloud.
    #[test]
    fn a_timeline_song_opens_through_its_audio_when_no_cloud_is_beside_it() {
        let repo = Path::new(env!("CARGO_MANIFEST_DIR"));
        let dir = repo.join("tests/output/panels_song_open_target");
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(dir.join("cache")).unwrap();
        let mut timeline = crate::data::cloud::load(&repo.join("data/demo_timeline.ply")).unwrap();
        timeline.path = dir.join("cache/timeline-0123456789abcdef.ply");
        let audio = dir.join("b-side.wav");
        std::fs::write(&audio, b"RIFF").unwrap();
        let mut song = timeline.meta.songs[0].clone();
        song.path = Some(audio.display().to_string());
        song.path_bytes = None;
        let (path, how) = song_open_target(&timeline, &song).expect("the audio opens");
        assert_eq!(path, audio);
        assert!(how.contains("cache"), "{how}");
        std::fs::write(dir.join("b-side.ply"), b"ply").unwrap();
        let (path, _) = song_open_target(&timeline, &song).unwrap();
        assert_eq!(path, dir.join("b-side.ply"), "its own Song cloud first");
        song.path = Some(dir.join("gone.wav").display().to_string());
        assert_eq!(song_open_target(&timeline, &song), None);
    }

    /// The texts a frame of `add` draws.
    fn texts_drawn(add: impl FnMut(&mut egui::Ui)) -> Vec<String> {
        let ctx = egui::Context::default();
        let mut add = add;
        let mut output = ctx.run_ui(egui::RawInput::default(), |ui| add(ui));
        output.textures_delta.clear();
        let mut texts = Vec::new();
        for clipped in output.shapes {
            collect_texts(&clipped.shape, &mut texts);
        }
        texts
    }

    fn collect_texts(shape: &egui::Shape, texts: &mut Vec<String>) {
        match shape {
            egui::Shape::Text(text) => texts.push(text.galley.text().to_string()),
            egui::Shape::Vec(shapes) => shapes.iter().for_each(|s| collect_texts(s, texts)),
            _ => {}
        }
    }

    #[test]
    fn the_isovalue_shows_two_decimals_at_every_value() {
        for (value, shown) in [
            (0.5, "0.50"),
            (1.0, "1.00"),
            (0.01, "0.01"),
            (0.123, "0.12"),
        ] {
            let mut iso = value;
            let texts = texts_drawn(|ui| {
                ui.add(isovalue_slider(&mut iso));
            });
            assert!(
                texts.iter().any(|t| t == shown),
                "{value} is shown as {texts:?}, not {shown}"
            );
        }
    }

    #[test]
    fn songs_of_one_year_are_listed_to_pick() {
        let song = |year: Option<i32>| crate::data::cloud::SongInfo {
            year,
            ..Default::default()
        };
        let songs = [
            song(Some(1999)),
            song(Some(2005)),
            song(Some(1999)),
            song(None),
            song(Some(1999)),
        ];
        assert_eq!(songs_of_year(&songs, Some(1999)), [0, 2, 4]);
        assert_eq!(songs_of_year(&songs, Some(2005)), [1]);
        assert!(songs_of_year(&songs, None).is_empty(), "no year, no group");
    }
}
