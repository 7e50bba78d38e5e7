//! Closing the window from outside: when another client destroys the window (the window
//! manager's destroy, `xdotool windowclose`), winit 0.30 on X11 still asks the X server where
//! the window is on the next frame and unwraps the BadWindow error it gets, a panic inside
//! eframe's event loop that the close button never meets. [`run_until_window_gone`] runs the
//! event loop, recognises that one panic by where it comes from and what it says, keeps it off
//! stderr and ends the run as a close does; any other panic goes on as it would have.

use std::panic::{AssertUnwindSafe, PanicHookInfo};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

/// Whether a panic at `file` saying `message` is winit finding the window gone: an X11
/// `BadWindow` error (`error_kind: Window`) unwrapped inside winit.
pub(super) fn is_window_gone(file: &str, message: &str) -> bool {
    // BadWindow, or BadDrawable from asking a destroyed window's geometry (GetGeometry takes
    // a drawable): both say the window is gone.
    file.contains("winit")
        && message.contains("X11Error")
        && (message.contains("error_kind: Window") || message.contains("error_kind: Drawable"))
}

fn message(info: &PanicHookInfo<'_>) -> String {
    let payload = info.payload();
    payload
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_default()
}

/// Runs `run` (the window's event loop); `None` when it ended because the window was destroyed
/// from outside, as a close.
pub(super) fn run_until_window_gone<T>(run: impl FnOnce() -> T) -> Option<T> {
    let gone = Arc::new(AtomicBool::new(false));
    let flag = gone.clone();
    let previous = Arc::new(std::panic::take_hook());
    let chained = previous.clone();
    std::panic::set_hook(Box::new(move |info| {
        let file = info.location().map_or("", |l| l.file());
        if std::thread::current().name() == Some("main") && is_window_gone(file, &message(info)) {
            flag.store(true, Ordering::SeqCst);
            log::info!("the window was destroyed from outside: closing");
            return;
        }
        chained(info);
    }));
    let result = std::panic::catch_unwind(AssertUnwindSafe(run));
    // The hook before, for whatever runs after the window.
    let _ = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| previous(info)));
    match result {
        Ok(value) => Some(value),
        Err(_) if gone.load(Ordering::SeqCst) => None,
        Err(payload) => std::panic::resume_unwind(payload),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_winit_finding_the_window_gone_counts() {
        let file =
            "/root/.cargo/registry/src/index/winit-0.30.13/src/platform_impl/linux/x11/window.rs";
        let bad_window = "called `Result::unwrap()` on an `Err` value: X11(X11Error { error_kind: \
                          Window, error_code: 3, request_name: Some(\"TranslateCoordinates\") })";
        assert!(is_window_gone(file, bad_window));
        assert!(!is_window_gone("src/ui/app.rs", bad_window), "not winit");
        assert!(
            !is_window_gone(file, "index out of bounds"),
            "another panic"
        );
        // Seen when the window was closed while an export repainted it: GetGeometry's
        // BadDrawable.
        let bad_drawable = "called `Result::unwrap()` on an `Err` value: X11(X11Error { \
                            error_kind: Drawable, error_code: 9, major_opcode: 14 })";
        assert!(is_window_gone(file, bad_drawable));
        let other = bad_window.replace("error_kind: Window", "error_kind: Match");
        assert!(!is_window_gone(file, &other), "another X11 error");
    }
}
