//! The frequency axis selector's effect on the window: applies the chosen axis (linear, log,
//! mel; src/data/freq_axis.rs) to the active song's scene, labels and grid, and keeps a copy of
//! its points as the view shows them for hover picking, made on a thread.

use std::sync::Arc;
use std::sync::mpsc::channel;

use eframe::egui;

use crate::data::freq_axis::{FreqAxis, unsupported};
use crate::ui::bridge::ViewResources;
use crate::ui::labels;
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
        let result = {
            let mut renderer = render_state.renderer.write();
            let Some(resources) = renderer.callback_resources.get_mut::<ViewResources>() else {
                return;
            };
            let ViewResources {
                renderer, scenes, ..
            } = resources;
            let Some(data) = scenes.get_mut(&loaded.id) else {
                return;
            };
            let result = data
                .set_freq_axis(&render_state.device, renderer, &loaded.cloud, axis)
                .map(|()| {
                    let labels = labels::axis_labels(&loaded.cloud, data);
                    (labels, data.freq.clone())
                });
            resources.cache.invalidate_points();
            result
        };
        match result {
            Ok((labels, mapping)) => {
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
