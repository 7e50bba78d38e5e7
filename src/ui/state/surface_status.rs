//! The active cloud's surface as the window sees it ([`SurfaceStatus`], the `surface` field of
//! `LoudscapeApp`): the last extraction's outcome (an error, no surface at the isovalue), the
//! extraction under way, and the level of detail a frame asks for, from the pace of the full
//! mesh's frames while the camera moves or the isovalue is dragged.

use crate::render::surface::SurfaceCounts;
use crate::render::surface::lod::{DetailPace, SurfaceDetail, detail_for};

#[derive(Default)]
pub(in crate::ui) struct SurfaceStatus {
    /// Why the surface could not be extracted, if it could not.
    pub(in crate::ui) error: Option<String>,
    /// The last extraction found no surface (the isovalue is above every voxel).
    pub(in crate::ui) empty: bool,
    /// A surface is being extracted in the background (the last one is shown meanwhile).
    pub(in crate::ui) busy: bool,
    /// Triangles of the active cloud's full surface.
    triangles: u32,
    /// The pace of the full surface's moving frames: whether the coarse one stands in.
    pace: DetailPace,
    /// The surface mesh the last frame asked for.
    detail: SurfaceDetail,
    /// The isovalue slider was dragged (or a scripted sweep set a value) since the last frame
    /// chose its detail: only that frame reads it.
    iso_dragged: bool,
}

impl SurfaceStatus {
    /// The last extraction: its triangle counts (None before one) and its error.
    pub(in crate::ui) fn extracted(
        &mut self,
        counts: Option<SurfaceCounts>,
        error: Option<String>,
    ) {
        self.error = error;
        self.empty = counts.is_some_and(|c| c.found_nothing());
    }

    /// This frame's surface: whether one is being extracted for the Surface view, and the
    /// counts of the last extraction (its full mesh's size).
    pub(in crate::ui) fn frame(&mut self, busy: bool, counts: Option<SurfaceCounts>) {
        self.busy = busy;
        self.triangles = counts.map_or(0, |c| c.triangles());
    }

    /// The isovalue is being dragged in this frame (the slider, or a scripted sweep's value).
    pub(in crate::ui) fn isovalue_dragged(&mut self) {
        self.iso_dragged = true;
    }

    /// The surface mesh the last frame asked for.
    pub(in crate::ui) fn detail(&self) -> SurfaceDetail {
        self.detail
    }

    /// The detail this frame of the Surface view asks for (`surface_view` false: another view,
    /// nothing chosen): the coarse mesh stands in while `moving` or dragging when frames of the
    /// full one are too slow. `frame_ms`: the last frame's time, None when it did not follow the
    /// one before at once. A drag counts for this frame only.
    pub(in crate::ui) fn choose_detail(
        &mut self,
        surface_view: bool,
        moving: bool,
        frame_ms: Option<f32>,
    ) -> SurfaceDetail {
        let dragging = std::mem::take(&mut self.iso_dragged);
        if surface_view {
            if moving || dragging {
                self.pace
                    .observe(frame_ms, self.detail == SurfaceDetail::Full, self.triangles);
            }
            self.detail = detail_for(self.pace.full_too_slow(), moving, dragging, self.busy);
        }
        self.detail
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A device on which the full mesh's moving frames take `ms`.
    fn paced(ms: f32) -> SurfaceStatus {
        let mut status = SurfaceStatus::default();
        for _ in 0..20 {
            status.choose_detail(true, true, Some(ms));
        }
        status
    }

    #[test]
    fn a_drag_counts_for_the_frame_that_reads_it_only() {
        let mut status = paced(400.0);
        assert_eq!(
            status.choose_detail(true, false, None),
            SurfaceDetail::Full,
            "at rest: full"
        );
        status.isovalue_dragged();
        assert_eq!(
            status.choose_detail(true, false, None),
            SurfaceDetail::CoarseUntilFull,
            "dragging on a slow device: coarse until the full one is there"
        );
        assert_eq!(
            status.choose_detail(true, false, None),
            SurfaceDetail::Full,
            "the next frame without a drag is at rest again"
        );
        status.isovalue_dragged();
        status.choose_detail(false, false, None);
        assert_eq!(
            status.choose_detail(true, false, None),
            SurfaceDetail::Full,
            "a drag read by a frame of another view is gone too"
        );
    }

    #[test]
    fn the_coarse_mesh_stands_in_only_on_a_slow_device() {
        let mut fast = paced(10.0);
        assert_eq!(
            fast.choose_detail(true, true, Some(10.0)),
            SurfaceDetail::Full
        );
        let mut slow = paced(400.0);
        assert_eq!(
            slow.choose_detail(true, true, Some(400.0)),
            SurfaceDetail::Coarse
        );
        slow.frame(true, None);
        assert_eq!(
            slow.choose_detail(true, false, None),
            SurfaceDetail::CoarseUntilFull,
            "extracting at rest"
        );
    }

    #[test]
    fn the_last_extraction_says_empty_only_when_it_fitted_and_found_nothing() {
        let counts = |vertices_needed, indices_needed| SurfaceCounts {
            method: crate::render::surface::SurfaceMethod::ALL[0],
            vertices_needed,
            indices_needed,
            vertex_capacity: 100,
            index_capacity: 300,
        };
        let mut status = SurfaceStatus::default();
        status.extracted(None, Some("the grid is too large".into()));
        assert_eq!(status.error.as_deref(), Some("the grid is too large"));
        assert!(!status.empty, "no counts: nothing said");
        status.extracted(Some(counts(0, 0)), None);
        assert_eq!(status.error, None);
        assert!(status.empty, "no triangles at this isovalue");
        status.extracted(Some(counts(200, 0)), None);
        assert!(!status.empty, "did not fit: not known to be empty");
        status.extracted(Some(counts(40, 60)), None);
        assert!(!status.empty);
        status.frame(false, Some(counts(40, 60)));
        assert_eq!(status.triangles, 20);
    }
}
