//! A scripted isovalue sweep for the window tests: with `LOUDSCAPE_ISO_SWEEP=0.3,0.35,...` in a
//! `--screenshot` run in the Surface view, the window sets one isovalue a frame once the first
//! surface is shown (as a dragged slider does), waits until the surface of the last value is on
//! screen, and prints one line on stderr, `iso sweep: values=N frames=N busy_frames=N
//! longest_frame_ms=X installed=N coarse_installed=N shown_iso=X`: the frames it drew, how many
//! of them while an extraction ran, the longest frame on the UI thread, the extractions
//! installed (full and coarse surfaces of the level of detail) and the isovalue of the surface
//! shown. The screenshot is taken after it. The sweep's state (`IsoSweep`, read from the
//! environment) is `state/iso_sweep.rs`; here is its step, one a frame.

use std::time::Instant;

use crate::render::scene::ViewKind;
use crate::ui::bridge::{SurfaceProgress, ViewResources};
use crate::ui::state::LoudscapeApp;

impl LoudscapeApp {
    /// One frame of the sweep; true once it is over (or there is none).
    pub(super) fn step_iso_sweep(&mut self, frame: &eframe::Frame) -> bool {
        let Some(id) = self.active().map(|l| l.id) else {
            return self.iso_sweep.as_ref().is_none_or(|s| s.done);
        };
        let (Some(sweep), Some(render_state)) =
            (self.iso_sweep.as_mut(), frame.wgpu_render_state())
        else {
            return true;
        };
        if sweep.done {
            return true;
        }
        if self.settings.view != ViewKind::Surface {
            self.settings.view = ViewKind::Surface;
            return false;
        }
        let Some(SurfaceProgress {
            shown_iso_value: shown,
            extracting: busy,
            installed,
            coarse_installed: coarse,
        }) = ViewResources::read(render_state, |r| r.surface_progress(id)).flatten()
        else {
            return false;
        };
        let now = Instant::now();
        match sweep.next {
            None => {
                // Wait for the first surface (the grid build and first extraction are not part
                // of the sweep).
                if shown.is_some() && !busy {
                    sweep.next = Some(0);
                    sweep.installed_before = installed;
                    sweep.coarse_before = coarse;
                    sweep.last_frame = Some(now);
                }
                return false;
            }
            Some(_) => {
                if let Some(last) = sweep.last_frame {
                    let ms = (now - last).as_secs_f64() * 1e3;
                    sweep.longest_ms = sweep.longest_ms.max(ms);
                }
                sweep.last_frame = Some(now);
                sweep.frames += 1;
                sweep.busy_frames += u32::from(busy);
            }
        }
        let next = sweep.next.unwrap_or(0);
        if let Some(&value) = sweep.values.get(next) {
            self.settings.surface.iso_value = value;
            sweep.next = Some(next + 1);
            return false;
        }
        let last = sweep.values[sweep.values.len() - 1];
        if busy || shown != Some(last) {
            return false;
        }
        eprintln!(
            "iso sweep: values={} frames={} busy_frames={} longest_frame_ms={:.1} installed={} \
             coarse_installed={} shown_iso={}",
            sweep.values.len(),
            sweep.frames,
            sweep.busy_frames,
            sweep.longest_ms,
            installed - sweep.installed_before,
            coarse - sweep.coarse_before,
            shown.unwrap_or(f32::NAN),
        );
        sweep.done = true;
        true
    }
}
