//! ALSA's own error printing, silenced while the audio output is opened. Probing the default
//! device on a machine without a sound card made libasound print eight "ALSA lib ..." lines on
//! every launch of the window (its default error handler writes to stderr). [`quietly`] installs
//! a thread-local ALSA error handler that counts those messages instead, for the duration of
//! the open only and on the opening thread only, so nothing else that writes to stderr is
//! hidden: our own messages and a failure to open (reported by rodio's error, shown in the
//! transport bar) still come through.

/// Runs `open` with ALSA's error messages on this thread counted instead of printed.
#[cfg(target_os = "linux")]
pub fn quietly<T>(open: impl FnOnce() -> T) -> T {
    use std::cell::Cell;
    use std::ffi::{c_char, c_int};

    thread_local! {
        static SILENCED: Cell<u32> = const { Cell::new(0) };
    }

    unsafe extern "C" fn count(
        _file: *const c_char,
        _line: c_int,
        _function: *const c_char,
        _err: c_int,
        _fmt: *const c_char,
        _args: *mut alsa_sys::__va_list_tag,
    ) {
        SILENCED.with(|n| n.set(n.get() + 1));
    }

    // SAFETY: the handler is thread-local in libasound and only counts; it is restored
    // (to the default) before this function returns.
    let previous = unsafe { alsa_sys::snd_lib_error_set_local(Some(count)) };
    let result = open();
    unsafe { alsa_sys::snd_lib_error_set_local(previous) };
    let silenced = SILENCED.with(|n| n.replace(0));
    if silenced > 0 {
        log::debug!("ALSA reported {silenced} messages while opening the audio output");
    }
    result
}

/// Elsewhere there is no ALSA to silence.
#[cfg(not(target_os = "linux"))]
pub fn quietly<T>(open: impl FnOnce() -> T) -> T {
    open()
}
