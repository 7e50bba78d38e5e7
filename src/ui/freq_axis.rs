//! The frequency axis selector's effect on the window: applies the chosen axis (linear, log,
//! mel; src/data/freq_axis.rs) to the active song's scene, labels and grid, and keeps a copy of
//! its points as the view shows them for hover picking, made on a thread.

use std::sync::Arc;
use std::sync::mpsc::channel;

use eframe::egui;

use crate::data::freq_axis::{FreqAxis, unsupported};
use crate::ui::bridge::{FreqAxisShown, ViewResources};
use crate::ui::state::{LoudscapeApp, Slot};

impl LoudscapeApp {
    /// Whether the active cloud has a frequency axis to choose (a song with bin metadata).
    pub(super) fn has_freq_axis(&self) -> bool {
        self.active == Slot::Song
            && self
                .active()
                .is_some_and(|l| unsupported(&l.cloud.meta).is_none())
    }

    /// The "Frequency axis" row of the side panel (not shown for timelines).
    pub(super) fn freq_axis_controls(&mut self, ui: &mut egui::Ui) {
        if !self.has_freq_axis() {
            return;
        }
        ui.add_space(6.0);
        ui.label(egui::RichText::new("Frequency axis").strong());
        ui.horizontal_wrapped(|ui| {
            for axis in FreqAxis::ALL {
                ui.selectable_value(&mut self.freq_axis, axis, axis.title())
                    .on_hover_text(match axis {
                        FreqAxis::Linear => "Linear in Hz, as the paper draws it",
                        FreqAxis::Log => "Octaves equally wide; each bin spread over its width",
                        FreqAxis::Mel => "The mel scale (HTK): close to how pitch is heard",
                    });
            }
        });
    }

    /// Puts the song slot's scene on the chosen frequency axis when it is not there yet, and
    /// collects the picking copy once its thread is done.
    pub(super) fn apply_freq_axis(&mut self, frame: &eframe::Frame) {
        let Some(render_state) = frame.wgpu_render_state() else {
            return;
        };
        let axis = self.freq_axis;
        let Some(loaded) = self.song.as_mut() else {
            return;
        };
        if let Some(receiver) = &loaded.view_points_pending
            && let Ok(points) = receiver.try_recv()
        {
            loaded.view_points = Some(Arc::new(points));
            loaded.view_points_pending = None;
            self.hover = None;
        }
        if loaded.view_points_pending.is_some() {
            self.needs_repaint = true;
        }
        if unsupported(&loaded.cloud.meta).is_some() || loaded.freq_axis == axis {
            return;
        }
        let Some(result) = ViewResources::write(render_state, |r| {
            r.set_freq_axis(loaded.id, &loaded.cloud, axis)
        })
        .flatten() else {
            return;
        };
        match result {
            Ok(FreqAxisShown { labels, mapping }) => {
                loaded.labels = labels;
                loaded.freq_axis = axis;
                loaded.freq = mapping.clone();
                loaded.view_points = None;
                loaded.view_points_pending = None;
                loaded.cpu_grid = None;
                if let Some(mapping) = mapping {
                    let (sender, receiver) = channel();
                    let cloud = loaded.cloud.clone();
                    std::thread::spawn(move || {
                        let _ = sender.send(mapping.view_points(&cloud.points));
                    });
                    loaded.view_points_pending = Some(receiver);
                }
                self.hover = None;
                self.needs_repaint = true;
            }
            Err(message) => {
                self.messages.error(message);
                self.freq_axis = loaded.freq_axis;
            }
        }
    }
}
