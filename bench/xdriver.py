"""A small X11 driver for bench/bench_window.py: recorded input through XTest, painted frames
through the DAMAGE extension, pixels through XGetImage. ctypes over libX11, libXtst and
libXdamage (the system's X client libraries), so the benchmark needs no Python package.

A frame counts as painted when the window's contents changed on the X server: the Vulkan
swapchain's present (a put of the whole image under Xvfb) is what raises the damage, so this
times the app's real paint path, whatever it does inside.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import select
import time

_X_ERRORS: list[int] = []


def _load(name: str, soname: str) -> ctypes.CDLL:
    path = ctypes.util.find_library(name) or soname
    try:
        return ctypes.CDLL(path)
    except OSError as e:
        raise RuntimeError(f"cannot load {soname} (X client library): {e}") from e


class _XImage(ctypes.Structure):
    _fields_ = [
        ("width", ctypes.c_int),
        ("height", ctypes.c_int),
        ("xoffset", ctypes.c_int),
        ("format", ctypes.c_int),
        ("data", ctypes.c_void_p),
        ("byte_order", ctypes.c_int),
        ("bitmap_unit", ctypes.c_int),
        ("bitmap_bit_order", ctypes.c_int),
        ("bitmap_pad", ctypes.c_int),
        ("depth", ctypes.c_int),
        ("bytes_per_line", ctypes.c_int),
        ("bits_per_pixel", ctypes.c_int),
        ("red_mask", ctypes.c_ulong),
        ("green_mask", ctypes.c_ulong),
        ("blue_mask", ctypes.c_ulong),
        ("obdata", ctypes.c_void_p),
        ("create_image", ctypes.c_void_p),
        ("destroy_image", ctypes.CFUNCTYPE(ctypes.c_int, ctypes.c_void_p)),
    ]


_ERROR_HANDLER = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.c_void_p, ctypes.c_void_p)


@_ERROR_HANDLER
def _on_x_error(_display, event):
    # XErrorEvent: int type, Display*, XID resourceid, unsigned long serial, uchar error_code.
    _X_ERRORS.append(ctypes.cast(event, ctypes.POINTER(ctypes.c_ubyte))[32])
    return 0


class XDriver:
    """One connection to the X server: input, damage events and pixel reads."""

    def __init__(self, display: str):
        self.x11 = _load("X11", "libX11.so.6")
        self.xtst = _load("Xtst", "libXtst.so.6")
        self.xdamage = _load("Xdamage", "libXdamage.so.1")
        x11 = self.x11
        x11.XOpenDisplay.restype = ctypes.c_void_p
        x11.XOpenDisplay.argtypes = [ctypes.c_char_p]
        x11.XDefaultRootWindow.restype = ctypes.c_ulong
        x11.XDefaultRootWindow.argtypes = [ctypes.c_void_p]
        x11.XFlush.argtypes = [ctypes.c_void_p]
        x11.XSync.argtypes = [ctypes.c_void_p, ctypes.c_int]
        x11.XPending.argtypes = [ctypes.c_void_p]
        x11.XNextEvent.argtypes = [ctypes.c_void_p, ctypes.c_void_p]
        x11.XConnectionNumber.argtypes = [ctypes.c_void_p]
        x11.XGetImage.restype = ctypes.POINTER(_XImage)
        x11.XGetImage.argtypes = [
            ctypes.c_void_p,
            ctypes.c_ulong,
            ctypes.c_int,
            ctypes.c_int,
            ctypes.c_uint,
            ctypes.c_uint,
            ctypes.c_ulong,
            ctypes.c_int,
        ]
        x11.XSetErrorHandler(_on_x_error)
        self.xtst.XTestFakeMotionEvent.argtypes = [
            ctypes.c_void_p,
            ctypes.c_int,
            ctypes.c_int,
            ctypes.c_int,
            ctypes.c_ulong,
        ]
        self.xtst.XTestFakeButtonEvent.argtypes = [
            ctypes.c_void_p,
            ctypes.c_uint,
            ctypes.c_int,
            ctypes.c_ulong,
        ]
        self.xdamage.XDamageQueryExtension.argtypes = [
            ctypes.c_void_p,
            ctypes.POINTER(ctypes.c_int),
            ctypes.POINTER(ctypes.c_int),
        ]
        self.xdamage.XDamageCreate.restype = ctypes.c_ulong
        self.xdamage.XDamageCreate.argtypes = [ctypes.c_void_p, ctypes.c_ulong, ctypes.c_int]
        self.xdamage.XDamageSubtract.argtypes = [
            ctypes.c_void_p,
            ctypes.c_ulong,
            ctypes.c_ulong,
            ctypes.c_ulong,
        ]
        self.dpy = x11.XOpenDisplay(display.encode())
        if not self.dpy:
            raise RuntimeError(f"cannot open X display {display}")
        self.root = x11.XDefaultRootWindow(self.dpy)
        base, err = ctypes.c_int(), ctypes.c_int()
        if not self.xdamage.XDamageQueryExtension(self.dpy, ctypes.byref(base), ctypes.byref(err)):
            raise RuntimeError("the X server has no DAMAGE extension")
        self.damage_event = base.value  # XDamageNotify is event 0 of the extension
        self.damage = 0
        self.event = ctypes.create_string_buffer(192)  # sizeof(XEvent) on LP64
        self.frames: list[float] = []  # monotonic times of painted frames
        self.fd = x11.XConnectionNumber(self.dpy)

    def watch(self, window: int) -> None:
        """Starts counting painted frames of `window`."""
        # XDamageReportNonEmpty: one event until the damage is subtracted, so each event is
        # one or more puts since the last one (a frame's put may come in several requests).
        self.damage = self.xdamage.XDamageCreate(self.dpy, window, 3)
        self.x11.XSync(self.dpy, 0)

    def pump(self, timeout: float) -> int:
        """Collects painted frames for up to `timeout` seconds (returns early on the first);
        returns how many arrived."""
        self.x11.XFlush(self.dpy)
        got = 0
        if not self.x11.XPending(self.dpy):
            ready, _, _ = select.select([self.fd], [], [], max(timeout, 0.0))
            if not ready:
                return 0
        while self.x11.XPending(self.dpy):
            self.x11.XNextEvent(self.dpy, self.event)
            kind = ctypes.c_int.from_buffer(self.event).value
            if kind == self.damage_event:
                now = time.monotonic()
                self.xdamage.XDamageSubtract(self.dpy, self.damage, 0, 0)
                # Puts closer than 3 ms apart belong to one present.
                if not self.frames or now - self.frames[-1] > 0.003:
                    self.frames.append(now)
                    got += 1
        self.x11.XFlush(self.dpy)
        return got

    def pump_until(self, deadline: float) -> None:
        while (left := deadline - time.monotonic()) > 0:
            self.pump(left)

    def wait_quiet(self, quiet: float, timeout: float) -> bool:
        """Waits until no frame was painted for `quiet` seconds; False on `timeout`."""
        end = time.monotonic() + timeout
        last = time.monotonic()
        while time.monotonic() < end:
            if self.pump(min(quiet, end - time.monotonic())):
                last = time.monotonic()
            elif time.monotonic() - last >= quiet:
                return True
        return False

    def move(self, x: int, y: int) -> float:
        """Moves the pointer to (x, y) on the screen; returns the time the event was sent."""
        self.xtst.XTestFakeMotionEvent(self.dpy, -1, x, y, 0)
        self.x11.XFlush(self.dpy)
        return time.monotonic()

    def button(self, pressed: bool, button: int = 1) -> float:
        self.xtst.XTestFakeButtonEvent(self.dpy, button, int(pressed), 0)
        self.x11.XFlush(self.dpy)
        return time.monotonic()

    def grab(self, x: int, y: int, w: int, h: int) -> bytes | None:
        """The screen's pixels in a rectangle (root window coordinates), or None on an error."""
        _X_ERRORS.clear()
        image = self.x11.XGetImage(self.dpy, self.root, x, y, w, h, 0xFFFFFFFF, 2)  # ZPixmap
        if not image or _X_ERRORS:
            return None
        img = image.contents
        data = ctypes.string_at(img.data, img.bytes_per_line * img.height)
        img.destroy_image(ctypes.cast(image, ctypes.c_void_p))
        return data
