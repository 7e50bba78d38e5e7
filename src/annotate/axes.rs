//! Axis tick labels and titles in physical units, laid out for a view: which box edge carries
//! each axis (facing the camera), where each label lands, and which make way. The layout is
//! plain data ([`layout`]); the window paints it with egui, pictures draw it on the CPU.

use glam::Vec3;

use super::{Anchor, Annotation, Rect, Rgba, Shape, Text};
use crate::data::axes::Axis;
use crate::data::cloud::{DataMode, PointCloud};
use crate::render::colormap::Background;
use crate::render::scene::SceneData;
use crate::view::frame_view::FrameView;

/// The translucent plate under each label on the dark background (straight RGBA).
pub const LABEL_PLATE: Rgba = [13, 15, 20, 190];

/// The plate under a label on `background`: the paper's colour, mostly opaque, so the ink of
/// [`Background::ink`] stays readable over the cloud on either background.
pub fn label_plate(background: Background) -> Rgba {
    if background.is_light() {
        [255, 255, 255, 190]
    } else {
        LABEL_PLATE
    }
}

/// Font sizes of tick labels and axis titles, points.
pub const TICK_SIZE: f32 = 12.0;
pub const TITLE_SIZE: f32 = 14.0;
/// Space kept between a title and its axis's tick labels, points.
pub const TITLE_GAP: f32 = 4.0;
/// How far a title keeps inside the view's edges, points.
pub const TITLE_MARGIN: f32 = 8.0;
/// The smallest size a title too wide for the view shrinks to before it is cut, points.
pub const MIN_TITLE_SIZE: f32 = 10.0;

/// `title` fitted to `width` points: as it is at [`TITLE_SIZE`] where it fits, else smaller
/// (down to [`MIN_TITLE_SIZE`]), else at that size cut with "…". Its text and size.
pub fn fitted_title(title: &str, width: f32) -> (String, f32) {
    let measured = super::font::measure(title, TITLE_SIZE)[0];
    if measured <= width {
        return (title.to_string(), TITLE_SIZE);
    }
    // Text width grows about linearly with the size (hinting aside): step down to a size
    // that fits.
    let mut size = (TITLE_SIZE * width / measured.max(1.0)).floor();
    while size >= MIN_TITLE_SIZE {
        if super::font::measure(title, size)[0] <= width {
            return (title.to_string(), size);
        }
        size -= 1.0;
    }
    // Cut, but the unit kept: "momentary lou… (LUFS)" says what the ticks count.
    if let (name, Some(unit)) = split_unit(title) {
        let room = width - super::font::measure(&format!(" {unit}"), MIN_TITLE_SIZE)[0];
        if room >= super::font::measure("ab…", MIN_TITLE_SIZE)[0] {
            let name = super::font::fit_text(&short_name(name), MIN_TITLE_SIZE, room);
            return (format!("{name} {unit}"), MIN_TITLE_SIZE);
        }
    }
    (
        super::font::fit_text(title, MIN_TITLE_SIZE, width),
        MIN_TITLE_SIZE,
    )
}

/// A title's name and its unit, the last parenthesised part ("(LUFS)"), where it has one.
fn split_unit(title: &str) -> (&str, Option<&str>) {
    match title.rfind(" (") {
        Some(at) if title.ends_with(')') && at > 0 => (&title[..at], Some(&title[at + 1..])),
        _ => (title, None),
    }
}

/// A title's name without its parenthesised parts and what follows its first comma
/// ("momentary loudness (BS.1770, 400 ms), as heard on Spotify" -> "momentary loudness").
fn short_name(name: &str) -> String {
    let mut short = String::new();
    let mut depth = 0u32;
    for c in name.chars() {
        match c {
            '(' => depth += 1,
            ')' => depth = depth.saturating_sub(1),
            ',' if depth == 0 => break,
            _ if depth == 0 => short.push(c),
            _ => {}
        }
    }
    let short = short.split_whitespace().collect::<Vec<_>>().join(" ");
    if short.is_empty() {
        name.to_string()
    } else {
        short
    }
}

/// `title` shortened to its name and unit, where that is shorter: "momentary loudness
/// (BS.1770, 400 ms) (LUFS)" -> "momentary loudness (LUFS)".
pub fn abbreviated_title(title: &str) -> Option<String> {
    let (name, unit) = split_unit(title);
    let short = short_name(name);
    let short = match unit {
        Some(unit) => format!("{short} {unit}"),
        None => short,
    };
    (short.len() < title.len()).then_some(short)
}

/// A tick label or an axis title, placed along one axis of the box.
#[derive(Clone, Debug)]
pub struct Label {
    /// 0, 1, 2 for x, y, z.
    pub axis: usize,
    /// Normalized position along the axis, -1 to 1.
    pub at: f32,
    pub text: String,
    pub title: bool,
}

/// The labels of a box: which edge carries them is chosen per frame, facing the camera.
#[derive(Clone, Debug, Default)]
pub struct AxisLabels {
    pub box_min: Vec3,
    pub box_max: Vec3,
    pub labels: Vec<Label>,
}

/// "time (s)", or just "hp" for a unitless axis.
pub fn axis_title(axis: &Axis, fallback: &str) -> String {
    let name = if axis.label.is_empty() {
        fallback
    } else {
        &axis.label
    };
    if axis.unit.is_empty() || axis.unit.eq_ignore_ascii_case(name) {
        name.to_string()
    } else if axis.unit == "s" && axis.ticks(8).iter().any(|t| t.label.contains(':')) {
        // The ticks read as a clock: "(s)" over "2:30" would say seconds where minutes are.
        format!("{name} (m:ss)")
    } else {
        format!("{name} ({})", axis.unit)
    }
}

/// Tick labels and axis titles for the box drawn by the scene.
/// (The axes as the view shows them: `data.axes`, z on the frequency axis shown.)
/// The level axis's title names its reference (dBFS RMS, or dB re FS sine) by the cloud's mode.
pub fn axis_labels(cloud: &PointCloud, data: &SceneData) -> AxisLabels {
    with_references(
        axis_labels_for_axes(&data.axes, data.box_min, data.box_max),
        cloud,
        &data.axes,
    )
}

/// Tick labels and axis titles for a box `[min, max]` in data space.
pub fn axis_labels_for_box(cloud: &PointCloud, min: Vec3, max: Vec3) -> AxisLabels {
    with_references(
        axis_labels_for_axes(&cloud.meta.axes, min, max),
        cloud,
        &cloud.meta.axes,
    )
}

/// The titles of `labels` with the level axis's reference for `cloud`'s mode
/// ([`titled_with_reference`]).
fn with_references(
    mut labels: AxisLabels,
    cloud: &PointCloud,
    axes: &crate::data::axes::Axes,
) -> AxisLabels {
    let units = [&axes.x.unit, &axes.y.unit, &axes.z.unit];
    for label in labels.labels.iter_mut().filter(|l| l.title) {
        let text = std::mem::take(&mut label.text);
        label.text =
            titled_with_reference(cloud.meta.mode, label.axis, units[label.axis.min(2)], text);
    }
    labels
}

/// Tick labels and axis titles of `axes` for a box `[min, max]` in data space.
pub fn axis_labels_for_axes(axes: &crate::data::axes::Axes, min: Vec3, max: Vec3) -> AxisLabels {
    let mut labels = Vec::new();
    for (index, (axis, fallback)) in [(&axes.x, "x"), (&axes.y, "y"), (&axes.z, "z")]
        .into_iter()
        .enumerate()
    {
        for tick in axis.ticks(8) {
            labels.push(Label {
                axis: index,
                at: tick.at,
                text: tick.label,
                title: false,
            });
        }
        labels.push(Label {
            axis: index,
            at: 0.0,
            text: axis_title(axis, fallback),
            title: true,
        });
    }
    AxisLabels {
        box_min: min,
        box_max: max,
        labels,
    }
}

/// The box edge an axis is labelled on, as the two fixed coordinates of the other axes:
/// x and z along the lowest edge on screen, y along the leftmost vertical edge.
fn label_edge(labels: &AxisLabels, view: &FrameView, axis: usize) -> Option<Vec3> {
    let (min, max) = (labels.box_min, labels.box_max);
    let mid = (min + max) * 0.5;
    let mut best: Option<(f32, Vec3)> = None;
    for corner in 0..4u32 {
        let mut point = mid;
        let (a, b) = match axis {
            0 => (1, 2),
            1 => (0, 2),
            _ => (0, 1),
        };
        point[a] = if corner & 1 == 0 { min[a] } else { max[a] };
        point[b] = if corner & 2 == 0 { min[b] } else { max[b] };
        let Some(pixel) = view.project(point) else {
            continue;
        };
        // Lowest on screen for x and z, leftmost for y.
        let score = if axis == 1 { -pixel.x } else { pixel.y };
        if best.is_none_or(|(s, _)| score > s) {
            best = Some((score, point));
        }
    }
    best.map(|(_, p)| p)
}

/// The labels of `labels` laid out over a view occupying `rect` (points), projected through
/// `view`, in the ink of `background`, each on a plate of the background's colour.
///
/// Rules: a label whose anchor projects far outside the picture is left out, and so is a tick
/// label the picture's edge would cut; each title goes beyond its own axis's tick labels (left
/// of the level axis's ticks, below the others') where that stays in the picture, and where the
/// level axis's title has no room left of its ticks it goes above the axis's top end; a title
/// keeps [`TITLE_MARGIN`] inside the picture's edges, moving in, drawn smaller or, failing
/// that, cut with "…" rather than reaching them; titles are placed first and a tick label that
/// would overlap a label already placed is left out.
pub fn layout(
    rect: Rect,
    view: &FrameView,
    labels: &AxisLabels,
    background: Background,
) -> Annotation {
    layout_avoiding(rect, view, labels, background, &[])
}

/// As [`layout`], keeping clear of `occupied` (the boxes of what is drawn over the picture
/// first: its legend): a title takes a place clear of them, a tick label that meets one is left
/// out.
pub fn layout_avoiding(
    rect: Rect,
    view: &FrameView,
    labels: &AxisLabels,
    background: Background,
    occupied: &[Rect],
) -> Annotation {
    let scale = rect.width() / view.width.max(1) as f32;
    let edges: Vec<Option<Vec3>> = (0..3).map(|axis| label_edge(labels, view, axis)).collect();
    // Where a label's anchor lands in `rect`, for the normalized position `at` on its axis.
    let project = |axis: usize, at: f32| -> Option<[f32; 2]> {
        let mut anchor = edges[axis]?;
        let (lo, hi) = (labels.box_min[axis], labels.box_max[axis]);
        anchor[axis] = lo + (at + 1.0) * 0.5 * (hi - lo);
        let pixel = view.project(anchor)?;
        Some([rect.min[0] + pixel.x * scale, rect.min[1] + pixel.y * scale])
    };
    let inside = |p: [f32; 2]| rect.expand(40.0).contains(p);
    let ink = |title: bool| super::rgb(background.ink(title));
    // Every tick label that lands in the picture, per axis.
    let mut ticks: [Vec<Text>; 3] = Default::default();
    for label in labels.labels.iter().filter(|l| !l.title) {
        let axis = label.axis.min(2);
        let Some(pos) = project(axis, label.at).filter(|p| inside(*p)) else {
            continue;
        };
        let (offset, anchor) = tick_offset(axis);
        let pos = [pos[0] + offset[0], pos[1] + offset[1]];
        let text = Text::new(label.text.clone(), pos, anchor, TICK_SIZE, ink(false));
        // A tick label the view's edge would cut ("dB" of "-10 dB") is left out.
        if within(&text.rect, rect) {
            ticks[axis].push(text);
        }
    }
    let mut placed: Vec<Text> = Vec::new();
    for label in labels.labels.iter().filter(|l| l.title) {
        let axis = label.axis.min(2);
        let Some(pos) = project(axis, label.at).filter(|p| inside(*p)) else {
            continue;
        };
        let top_end = project(axis, 1.0);
        let title = place_title(
            &label.text,
            (axis, pos, top_end),
            &ticks[axis],
            rect,
            occupied,
            ink(true),
        );
        if !overlaps_any(&title.rect, &placed) && !meets(&title.rect, occupied) {
            placed.push(title);
        }
    }
    for tick in ticks.into_iter().flatten() {
        if !overlaps_any(&tick.rect, &placed) && !meets(&tick.rect, occupied) {
            placed.push(tick);
        }
    }
    let mut out = Annotation::default();
    for text in placed {
        // A plate of the background's colour under the text keeps it readable over bright
        // points, surfaces and the volume.
        out.push(Shape::Fill {
            rect: text.rect.expand2(3.0, 1.0),
            radius: 3.0,
            colour: label_plate(background),
        });
        out.push(Shape::Text(text));
    }
    out
}

/// A tick label's offset from its anchor and its anchor: left of the level axis, below the
/// others.
fn tick_offset(axis: usize) -> ([f32; 2], Anchor) {
    if axis == 1 {
        ([-10.0, 0.0], Anchor::RIGHT_CENTER)
    } else {
        ([0.0, 8.0], Anchor::CENTER_TOP)
    }
}

/// Whether `text` lies wholly in `rect` (half a point of rounding allowed).
fn within(text: &Rect, rect: Rect) -> bool {
    text.left() >= rect.left() - 0.5
        && text.right() <= rect.right() + 0.5
        && text.top() >= rect.top() - 0.5
        && text.bottom() <= rect.bottom() + 0.5
}

fn meets(rect: &Rect, occupied: &[Rect]) -> bool {
    occupied.iter().any(|o| o.expand(2.0).intersects(rect))
}

fn overlaps_any(rect: &Rect, placed: &[Text]) -> bool {
    placed.iter().any(|p| p.rect.expand(2.0).intersects(rect))
}

/// `text` moved by `(dx, dy)` (a unit step outward) until it clears every one of `ticks`
/// (with [`TITLE_GAP`]).
fn clear_of(mut text: Text, ticks: &[Text], dx: f32, dy: f32) -> Text {
    for _ in 0..=ticks.len() {
        let Some(tick) = ticks
            .iter()
            .find(|t| t.rect.expand(TITLE_GAP).intersects(&text.rect))
        else {
            break;
        };
        let grown = tick.rect.expand(TITLE_GAP);
        let step = if dx < 0.0 {
            text.rect.right() - grown.left()
        } else if dy > 0.0 {
            grown.bottom() - text.rect.top()
        } else {
            text.rect.bottom() - grown.top()
        };
        let step = step.max(1.0).ceil();
        text = text.moved(dx * step, dy * step);
    }
    text
}

/// Moved across so it lies within `rect` ([`TITLE_MARGIN`] in), where it fits.
fn within_width(text: Text, rect: Rect) -> Text {
    let dx = (rect.left() + TITLE_MARGIN - text.rect.left()).max(0.0)
        + (rect.right() - TITLE_MARGIN - text.rect.right()).min(0.0);
    text.moved(dx, 0.0)
}

/// The title of `axis`, its anchor at `pos` (the middle of the axis) and the axis's top end at
/// `top_end`, placed beyond the axis's tick labels `ticks`, clear of `occupied` where it can be
/// (see [`layout`]).
fn place_title(
    title: &str,
    (axis, pos, top_end): (usize, [f32; 2], Option<[f32; 2]>),
    ticks: &[Text],
    rect: Rect,
    occupied: &[Rect],
    colour: Rgba,
) -> Text {
    let (offset, anchor) = tick_offset(axis);
    let at = [pos[0] + offset[0] * 3.0, pos[1] + offset[1] * 3.0];
    // A title wider than the view is drawn smaller, or cut, to stay inside it.
    let (fitted, size) = fitted_title(title, rect.width() - 2.0 * TITLE_MARGIN);
    let text = Text::new(fitted, at, anchor, size, colour);
    if axis != 1 {
        // Below its ticks where that stays in the picture; else where it was (the ticks it
        // covers make way).
        let text = within_width(text, rect);
        let below = clear_of(text.clone(), ticks, 0.0, 1.0);
        if below.rect.bottom() <= rect.bottom() - TITLE_MARGIN && !meets(&below.rect, occupied) {
            return below;
        }
        let dy = (rect.bottom() - TITLE_MARGIN - text.rect.bottom()).min(0.0);
        return text.moved(0.0, dy);
    }
    // Left of the ticks, else above the axis's top end; where neither has room for the whole
    // title, its name and unit alone ("momentary loudness (LUFS)") are tried there too, and
    // stand in the picture in the last resort: they cover less of it.
    let short = abbreviated_title(title).map(|short| {
        let (short, size) = fitted_title(&short, rect.width() - 2.0 * TITLE_MARGIN);
        Text::new(short, at, anchor, size, colour)
    });
    let mut last = text.clone();
    for text in std::iter::once(text).chain(short) {
        if let Some(placed) = beside_or_above(text.clone(), ticks, rect, occupied, top_end) {
            return placed;
        }
        last = text;
    }
    let beside = clear_of(last, ticks, -1.0, 0.0);
    let inside = within_width(beside.clone(), rect);
    if meets(&inside.rect, occupied) {
        // Under what it meets (the legend, at the top), where that stays in the picture.
        let under = occupied
            .iter()
            .filter(|o| o.expand(2.0).intersects(&inside.rect))
            .map(|o| o.bottom())
            .fold(inside.rect.top(), f32::max);
        let moved = inside
            .clone()
            .moved(0.0, under + 2.0 + TITLE_GAP - inside.rect.top());
        if moved.rect.bottom() <= rect.bottom() - TITLE_MARGIN && !meets(&moved.rect, occupied) {
            return moved;
        }
        if beside.rect.left() >= rect.left() + TITLE_MARGIN {
            return beside;
        }
    }
    inside
}

/// The level axis's title `text` left of its axis's tick labels `ticks`, else above the axis's
/// top end `top_end` clear of its top tick, where either stays in `rect` clear of `occupied`.
fn beside_or_above(
    text: Text,
    ticks: &[Text],
    rect: Rect,
    occupied: &[Rect],
    top_end: Option<[f32; 2]>,
) -> Option<Text> {
    let (size, colour) = (text.size, text.colour);
    let title = text.text.clone();
    let beside = clear_of(text, ticks, -1.0, 0.0);
    if beside.rect.left() >= rect.left() + TITLE_MARGIN && !meets(&beside.rect, occupied) {
        return Some(beside);
    }
    let end = top_end?;
    let above = Text::new(
        title,
        [end[0], end[1] - 10.0],
        Anchor::CENTER_BOTTOM,
        size,
        colour,
    );
    let above = clear_of(within_width(above, rect), ticks, 0.0, -1.0);
    (above.rect.top() >= rect.top() + TITLE_MARGIN && !meets(&above.rect, occupied))
        .then_some(above)
}

/// How the y axis of `mode` is titled in pictures, with its reference: an older timeline's
/// "level" in dB is the frame's RMS level in dBFS (newer ones name their measure and unit,
/// e.g. LUFS, and pass through); a song's is each STFT bin's level in dB re a full-scale sine
/// (see docs/FORMAT.md). Other titles pass through.
pub fn titled_with_reference(mode: DataMode, axis: usize, unit: &str, title: String) -> String {
    if axis != 1 || unit != "dB" {
        return title;
    }
    let reference = match mode {
        DataMode::Timeline => "dBFS RMS",
        DataMode::Song => "dB re FS sine",
        DataMode::Generic => return title,
    };
    match title.strip_suffix(" (dB)") {
        Some("level") if mode == DataMode::Song => {
            format!("bin level ({reference})")
        }
        Some(name) => format!("{name} ({reference})"),
        None => title,
    }
}

#[cfg(test)]
mod title_tests {
    use super::*;

    #[test]
    fn a_clock_axis_is_titled_in_minutes_and_seconds() {
        let long = Axis::linear("time", "s", 0.0, 168.0);
        assert!(long.ticks(8).iter().any(|t| t.label.contains(':')));
        assert_eq!(axis_title(&long, "x"), "time (m:ss)");
        let short = Axis::linear("time", "s", 0.0, 30.0);
        assert_eq!(axis_title(&short, "x"), "time (s)");
        assert_eq!(axis_title(&Axis::linear("hp", "", 0.0, 1.0), "x"), "hp");
    }
}
