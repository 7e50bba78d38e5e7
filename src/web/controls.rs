//! The side panel's controls and the view's input, written once for the song's page
//! ([`super::WebApp`]) and the compare page ([`super::compare`]): the volume's transfer
//! functions, the surface's method and isovalue, the camera input, the axes legend, the hp
//! strip, the read-outs and the fit that follows the view's shape.

use eframe::egui;
use glam::Vec3;

use crate::data::cloud::PointCloud;
use crate::render::surface::SurfaceSettings;
use crate::view::camera::Camera;
use crate::view::frame_view::FrameView;

/// Wheel movement (points) per zoom step, as in the window.
const SCROLL_PER_STEP: f32 = 50.0;

/// The Volume view's controls, as the window's: the transfer function (Classic, Ember,
/// Glacial), shading and hp tint. The preset buttons' places go on `canvas`, for scripts and
/// tests (`data-volume-transfer`: "classic:x,y,width,height;ember:…", CSS pixels from the
/// canvas's corner).
pub(super) fn volume_controls(
    ui: &mut egui::Ui,
    volume: &mut crate::render::volume::VolumeSettings,
    canvas: &web_sys::HtmlCanvasElement,
) {
    use crate::render::transfer::TransferPreset;
    let mut places = Vec::new();
    ui.horizontal_wrapped(|ui| {
        for preset in TransferPreset::ALL {
            let r = ui
                .selectable_value(&mut volume.preset, preset, preset.name())
                .rect;
            places.push(format!(
                "{}:{},{},{},{}",
                preset.name().to_lowercase(),
                r.left(),
                r.top(),
                r.width(),
                r.height()
            ));
        }
    });
    ui.horizontal_wrapped(|ui| {
        ui.checkbox(&mut volume.shading, "shading")
            .on_hover_text("Lit by the density's gradient");
        ui.checkbox(&mut volume.hp_tint, "hp tint")
            .on_hover_text("Coloured by mean hp: red percussive to blue harmonic");
    });
    set_place(canvas, "data-volume-transfer", &places.join(";"));
}

/// Sets the canvas's attribute `name` to `value` where it differs (widget places for scripts).
fn set_place(canvas: &web_sys::HtmlCanvasElement, name: &str, value: &str) {
    if canvas.get_attribute(name).as_deref() != Some(value) {
        canvas.set_attribute(name, value).ok();
    }
}

/// The surface's method chooser (as the window's) and isovalue slider. Their places go on
/// `canvas`, for scripts and tests: each method button's (`data-surface-method`:
/// "mt:x,y,width,height;dc:…") and the slider's rail (`data-iso-slider`: x,y,width,height), CSS
/// pixels from the canvas's corner. Returns whether the slider is being dragged.
pub(super) fn surface_method_and_isovalue(
    ui: &mut egui::Ui,
    surface: &mut SurfaceSettings,
    canvas: &web_sys::HtmlCanvasElement,
) -> bool {
    use crate::render::surface::SurfaceMethod;
    let mut places = Vec::new();
    ui.horizontal_wrapped(|ui| {
        for method in SurfaceMethod::ALL {
            let r = ui
                .selectable_value(&mut surface.method, method, method.name())
                .rect;
            places.push(format!(
                "{}:{},{},{},{}",
                method.short_name(),
                r.left(),
                r.top(),
                r.width(),
                r.height()
            ));
        }
    });
    let slider = ui.add(egui::Slider::new(&mut surface.iso_value, 0.01..=0.99).text("isovalue"));
    // The rail is the first `slider_width` points of the widget (the value and the name follow
    // it).
    let r = slider.rect;
    let rail = ui.spacing().slider_width;
    let slider_place = format!("{},{},{},{}", r.left(), r.top(), rail, r.height());
    set_place(canvas, "data-surface-method", &places.join(";"));
    set_place(canvas, "data-iso-slider", &slider_place);
    slider.dragged()
}

/// The camera input of a frame (orbit, pan, zoom, F, R; `follow_fit`: see
/// `WebApp::follow_fit`), the camera fitted to `world_box` while it follows; whether the view
/// moves.
pub(super) fn camera_input(
    camera: &mut Camera,
    follow_fit: &mut Option<f32>,
    world_box: (Vec3, Vec3),
    ctx: &egui::Context,
    response: &egui::Response,
    aspect: f32,
    height: f32,
) -> bool {
    let delta = response.drag_delta() * ctx.pixels_per_point();
    let mut moving = false;
    if response.dragged_by(egui::PointerButton::Primary) {
        camera.orbit(delta.x, delta.y, height);
        moving = true;
    } else if response.dragged_by(egui::PointerButton::Secondary)
        || response.dragged_by(egui::PointerButton::Middle)
    {
        camera.pan(delta.x, delta.y, height);
        moving = true;
    }
    if response.hovered() {
        let scroll = ctx.input(|i| i.smooth_scroll_delta.y);
        if scroll != 0.0 {
            camera.zoom(scroll / SCROLL_PER_STEP);
            moving = true;
        }
    }
    let (fit, reset) = ctx.input(|i| (i.key_pressed(egui::Key::F), i.key_pressed(egui::Key::R)));
    if reset {
        *camera = Camera::default();
    }
    *follow_fit = next_fit(*follow_fit, moving, fit || reset);
    if let Some(fitted) = *follow_fit
        && fitted != aspect
    {
        let (min, max) = world_box;
        camera.fit(min, max, aspect);
        *follow_fit = Some(aspect);
    }
    moving
}

/// The legend of the axes: each one's name, label and range in its units.
pub(super) fn axes_legend(ui: &mut egui::Ui, axes: &crate::data::axes::Axes) {
    egui::Grid::new("axes").show(ui, |ui| {
        for (name, axis) in axes.named() {
            let label = if axis.label.is_empty() {
                name
            } else {
                &axis.label
            };
            ui.label(format!("{name}: {label}"));
            ui.label(format!(
                "{} to {}",
                axis.format_value(axis.min),
                axis.format_value(axis.max)
            ));
            ui.end_row();
        }
    });
}

/// The values of `cloud`'s point under the cursor in `rect` (the view `view` draws there), with
/// their units, in a tooltip headed `title` where given (the window's picking and read-out
/// texts, `view::pick`). Returns the readings shown.
pub(super) fn point_readout(
    response: &egui::Response,
    rect: egui::Rect,
    view: &FrameView,
    scale: f32,
    cloud: &PointCloud,
    min_scalar: f32,
    title: Option<&str>,
) -> Vec<crate::view::pick::Reading> {
    let Some(pos) = response.hover_pos().filter(|pos| rect.contains(*pos)) else {
        return Vec::new();
    };
    let px = (pos - rect.min) * scale;
    let Some(index) = crate::view::pick::pick_point(
        &cloud.points,
        view,
        glam::Vec2::new(px.x, px.y),
        6.0 * scale,
        min_scalar,
    ) else {
        return Vec::new();
    };
    let mut readings = crate::view::pick::point_readings(&cloud.meta.axes, &cloud.points[index]);
    crate::view::pick::name_readings(
        &mut readings,
        &cloud.meta.axes,
        cloud.meta.mode,
        &cloud.meta.songs,
        Some(cloud.points[index].position[0]),
    );
    show_readings(response, &readings, title);
    readings
}

/// `readings` in a tooltip at the pointer, headed `title` where given (nothing when empty).
pub(super) fn show_readings(
    response: &egui::Response,
    readings: &[crate::view::pick::Reading],
    title: Option<&str>,
) {
    if readings.is_empty() {
        return;
    }
    response.clone().on_hover_ui_at_pointer(|ui| {
        if let Some(title) = title {
            ui.strong(title);
        }
        egui::Grid::new("readout").show(ui, |ui| {
            for reading in readings {
                ui.label(&reading.name);
                ui.label(&reading.value);
                ui.end_row();
            }
        });
    });
}

/// Whether the camera follows the view's shape after this frame's input (see
/// `WebApp::follow_fit`): F or R start following (and fit at once), the user's own move stops it.
fn next_fit(follow: Option<f32>, user_moved: bool, fit_asked: bool) -> Option<f32> {
    if fit_asked {
        Some(f32::NAN)
    } else if user_moved {
        None
    } else {
        follow
    }
}

/// The points' hp colours, percussive to harmonic.
pub(super) fn hp_strip(ui: &mut egui::Ui, map: crate::render::colormap::HpColourMap) {
    const STEPS: usize = 50;
    let ramp = map.points();
    let (rect, _) = ui.allocate_exact_size(egui::vec2(200.0, 12.0), egui::Sense::hover());
    let painter = ui.painter_at(rect);
    for i in 0..STEPS {
        let [r, g, b] = ramp.sample_u8(i as f32 / (STEPS - 1) as f32);
        let x0 = rect.left() + rect.width() * i as f32 / STEPS as f32;
        let x1 = rect.left() + rect.width() * (i + 1) as f32 / STEPS as f32;
        painter.rect_filled(
            egui::Rect::from_x_y_ranges(x0..=x1 + 0.5, rect.y_range()),
            0.0,
            egui::Color32::from_rgb(r, g, b),
        );
    }
    ui.horizontal(|ui| {
        ui.label(egui::RichText::new("percussive (0)").small());
        ui.add_space(70.0);
        ui.label(egui::RichText::new("harmonic (1)").small());
    });
}
