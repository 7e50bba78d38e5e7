//! What is drawn over a view as a whole: its axis labels laid out clear of its legend.

use super::{Annotation, Rect, axes};

/// A view's axis labels laid out clear of `legend` (what else is drawn over the picture: its
/// name and colour key, titles), then `legend` over them.
pub fn labels_and_legend(
    rect: Rect,
    view: &crate::view::frame_view::FrameView,
    labels: Option<&axes::AxisLabels>,
    background: crate::render::colormap::Background,
    legend: Annotation,
) -> Annotation {
    let mut out = match labels {
        Some(labels) => axes::layout_avoiding(rect, view, labels, background, &legend.boxes()),
        None => Annotation::default(),
    };
    out.extend(legend);
    out
}
