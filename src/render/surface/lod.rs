//! The Surface view's level of detail: besides the full surface, each cloud keeps a coarse one,
//! extracted with the same method and isovalue from its grid downsampled [`COARSE_LEVELS`] times
//! (src/render/grid/downsample.rs), by the same background worker, before the full one. On a
//! device where frames of the full mesh are too slow while the camera moves (a software
//! rasterizer, whose cost per triangle does not shrink with the resolution), the view draws the
//! coarse mesh while the camera moves and while the isovalue slider is dragged; at rest it draws
//! the full mesh, so a settled picture is the same as without a level of detail.
//!
//! Three pure rules, each unit-tested: [`DetailPace`] (is the full mesh too slow while moving,
//! from the pace of such frames), [`detail_for`] (which detail a frame asks for) and
//! [`choose_mesh`] (which of the meshes at hand that frame draws).

/// How many times the grid is halved for the coarse surface: 128^3 -> 64^3 -> 32^3. Measured in
/// the window on lavapipe (docs/PERFORMANCE.md): one level orbited the demo at 12.9 fps and swept
/// the isovalue at 4.7 updates/s, two at 15.9 fps and 7.0 updates/s; a sphere's coarse area stays
/// within half a percent of the full one at two levels (tests/it/surface/lod.rs).
pub const COARSE_LEVELS: u32 = 2;

/// While the camera moves, a frame of the full mesh should take at most this long (the moving
/// frames' budget of src/ui/app.rs); slower, and the coarse mesh stands in.
pub const MOVING_FRAME_MS: f32 = 45.0;

/// Which mesh a frame of the Surface view asks for.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SurfaceDetail {
    /// The full surface (before there is one, the renderer draws the points).
    #[default]
    Full,
    /// The coarse surface (the camera moves on a slow device).
    Coarse,
    /// The full surface when it is the one of the current settings, the coarse one until then
    /// (the isovalue is being changed on a slow device).
    CoarseUntilFull,
}

/// One of the two meshes of a surface.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Level {
    Full,
    Coarse,
}

/// Which mesh to draw for `detail`: `full` and `coarse` say whether each exists and, if so,
/// whether it is the surface of the current settings (method, isovalue, grid). None: nothing to
/// draw.
pub fn choose_mesh(
    detail: SurfaceDetail,
    full: Option<bool>,
    coarse: Option<bool>,
) -> Option<Level> {
    let has = |level: Option<bool>| level.is_some();
    match detail {
        SurfaceDetail::Full if has(full) => Some(Level::Full),
        SurfaceDetail::CoarseUntilFull if full == Some(true) => Some(Level::Full),
        SurfaceDetail::Coarse | SurfaceDetail::CoarseUntilFull if has(coarse) => {
            Some(Level::Coarse)
        }
        _ if has(full) => Some(Level::Full),
        _ if has(coarse) => Some(Level::Coarse),
        _ => None,
    }
}

/// The detail a frame asks for: full unless the full mesh is too slow while moving
/// (`full_too_slow`, from [`DetailPace`]); then coarse while the camera moves, coarse until the
/// full mesh of the new settings is there while the isovalue is dragged or being extracted, and
/// full at rest.
pub fn detail_for(
    full_too_slow: bool,
    moving: bool,
    dragging: bool,
    extracting: bool,
) -> SurfaceDetail {
    if !full_too_slow {
        SurfaceDetail::Full
    } else if moving {
        SurfaceDetail::Coarse
    } else if dragging || extracting {
        SurfaceDetail::CoarseUntilFull
    } else {
        SurfaceDetail::Full
    }
}

/// The pace of frames that drew the full mesh while the camera moved or the isovalue was
/// dragged, as the moving divisor of src/ui/app.rs follows the pace of moving frames: the full
/// mesh is too slow once such frames average over [`MOVING_FRAME_MS`]. A real GPU never gets
/// there and keeps full detail. The measure is forgotten when the full mesh changes size by more
/// than half (another isovalue may give a mesh that is fast enough).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct DetailPace {
    /// Mean time of the full mesh's moving frames (ms), None before one was measured.
    full_ms: Option<f32>,
    /// The full mesh's triangles when it was measured.
    triangles: u32,
}

impl DetailPace {
    /// Whether the coarse mesh should stand in while moving.
    pub fn full_too_slow(&self) -> bool {
        self.full_ms.is_some_and(|ms| ms > MOVING_FRAME_MS)
    }

    /// After a frame drawn while moving or dragging: `frame_ms` its time (None: it did not
    /// follow the last frame at once, so it says nothing about the device), `drew_full` whether
    /// it asked for the full mesh, `triangles` the full mesh's size.
    pub fn observe(&mut self, frame_ms: Option<f32>, drew_full: bool, triangles: u32) {
        let (small, large) = (triangles.min(self.triangles), triangles.max(self.triangles));
        if self.full_ms.is_some() && u64::from(small) * 2 < u64::from(large) {
            // Another mesh: measure it again.
            self.full_ms = None;
        }
        let Some(ms) = frame_ms.filter(|_| drew_full) else {
            return;
        };
        self.full_ms = Some(match self.full_ms {
            None => ms,
            Some(mean) => 0.5 * mean + 0.5 * ms,
        });
        self.triangles = triangles;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use SurfaceDetail::{Coarse, CoarseUntilFull, Full};

    /// At rest the full mesh is drawn whenever there is one (today's picture), the coarse one
    /// only before the first full one; moving, the coarse one whenever there is one; dragging,
    /// the full one only once it is the current value's.
    #[test]
    fn the_mesh_drawn_follows_the_detail_asked_and_what_is_ready() {
        for full in [Some(true), Some(false)] {
            for coarse in [None, Some(true), Some(false)] {
                assert_eq!(choose_mesh(Full, full, coarse), Some(Level::Full));
            }
        }
        assert_eq!(choose_mesh(Full, None, Some(false)), Some(Level::Coarse));
        assert_eq!(
            choose_mesh(Coarse, Some(true), Some(true)),
            Some(Level::Coarse)
        );
        assert_eq!(
            choose_mesh(Coarse, Some(true), Some(false)),
            Some(Level::Coarse)
        );
        assert_eq!(choose_mesh(Coarse, Some(true), None), Some(Level::Full));
        assert_eq!(
            choose_mesh(CoarseUntilFull, Some(true), Some(true)),
            Some(Level::Full)
        );
        assert_eq!(
            choose_mesh(CoarseUntilFull, Some(false), Some(true)),
            Some(Level::Coarse)
        );
        assert_eq!(
            choose_mesh(CoarseUntilFull, Some(false), None),
            Some(Level::Full)
        );
        for detail in [Full, Coarse, CoarseUntilFull] {
            assert_eq!(choose_mesh(detail, None, None), None);
        }
    }

    #[test]
    fn coarse_only_where_the_full_mesh_is_too_slow_and_never_at_rest() {
        for (moving, dragging, extracting) in [
            (true, false, false),
            (false, true, false),
            (false, false, true),
            (false, false, false),
        ] {
            assert_eq!(detail_for(false, moving, dragging, extracting), Full);
        }
        assert_eq!(detail_for(true, true, false, false), Coarse);
        assert_eq!(detail_for(true, true, true, true), Coarse);
        assert_eq!(detail_for(true, false, true, false), CoarseUntilFull);
        assert_eq!(detail_for(true, false, false, true), CoarseUntilFull);
        assert_eq!(detail_for(true, false, false, false), Full);
    }

    /// A GPU's fast frames keep full detail; lavapipe's slow ones switch to coarse; frames that
    /// did not follow at once, or drew the coarse mesh, say nothing about the full one; a much
    /// smaller full mesh is measured again.
    #[test]
    fn the_pace_of_full_frames_decides() {
        let mut pace = DetailPace::default();
        assert!(!pace.full_too_slow(), "unmeasured: full");
        for _ in 0..50 {
            pace.observe(Some(8.0), true, 2_000_000);
        }
        assert!(!pace.full_too_slow(), "fast frames keep full detail");
        pace.observe(Some(MOVING_FRAME_MS * 1.5), true, 2_000_000);
        assert!(
            !pace.full_too_slow(),
            "one slow frame among fast ones is not enough"
        );

        let mut pace = DetailPace::default();
        pace.observe(Some(250.0), true, 2_000_000);
        assert!(pace.full_too_slow());
        // Coarse frames are fast, but say nothing about the full mesh.
        for _ in 0..50 {
            pace.observe(Some(20.0), false, 2_000_000);
        }
        assert!(pace.full_too_slow());
        pace.observe(None, true, 2_000_000);
        assert!(pace.full_too_slow(), "idle frames say nothing");
        // The same mesh, a little smaller: still too slow.
        pace.observe(None, false, 1_500_000);
        assert!(pace.full_too_slow());
        // A mesh of a tenth: measured again, and fast.
        pace.observe(None, false, 200_000);
        assert!(!pace.full_too_slow());
        pace.observe(Some(30.0), true, 200_000);
        assert!(!pace.full_too_slow());
    }
}
