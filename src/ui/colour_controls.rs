//! The side panel's colour controls: the hp colour map (points, surface, hp tint), the volume's
//! density colour map and the light background for print (`render::colormap`).

use eframe::egui::{self, RichText};

use crate::render::colormap::{Background, DensityColourMap, HpColourMap};
use crate::ui::state::LoudscapeApp;

impl LoudscapeApp {
    /// The hp map and the background, under the view's own controls.
    pub(super) fn colour_controls(&mut self, ui: &mut egui::Ui) {
        ui.add_space(6.0);
        ui.label(RichText::new("Colours").strong());
        let colours = &mut self.settings.colours;
        // Wrapped: in a narrow side panel the name goes under the box rather than past the edge.
        ui.horizontal_wrapped(|ui| {
            egui::ComboBox::from_id_salt("hp colour map")
                .selected_text(colours.hp.name())
                .show_ui(ui, |ui| {
                    for map in HpColourMap::ALL {
                        ui.selectable_value(&mut colours.hp, map, map.name());
                    }
                })
                .response
                .on_hover_text(
                    "Points, surface and hp tint. PuOr and Cividis are colour-blind safe; \
                     Cividis and Viridis are perceptually uniform",
                );
            ui.label("hp colour map");
        });
        let mut light = colours.background.is_light();
        if ui
            .checkbox(&mut light, "light background (print)")
            .on_hover_text(
                "White background, dark axes and legends; the volume's ramp runs dark where dense",
            )
            .changed()
        {
            colours.background = if light {
                Background::Light
            } else {
                Background::Dark
            };
        }
    }

    /// The colour map of the volume's transfer function.
    pub(super) fn density_colour_controls(&mut self, ui: &mut egui::Ui) {
        let colours = &mut self.settings.colours;
        egui::ComboBox::from_label("density colours")
            .selected_text(colours.density.name())
            .show_ui(ui, |ui| {
                for map in DensityColourMap::ALL {
                    ui.selectable_value(&mut colours.density, map, map.name());
                }
            })
            .response
            .on_hover_text(
                "Preset: the transfer function's own ramp; Viridis, Cividis, Magma, Inferno: \
                 perceptually uniform (matplotlib)",
            );
    }
}
