#!/usr/bin/env python3
"""Manual smoke test of the demo's keys and mouse under Xvfb, through XTest
(libX11 + libXtst via ctypes; no Python packages needed).

    Xvfb :57 -screen 0 800x600x24 & export DISPLAY=:57
    scripts/demo-input.py 4 & cargo run --release -- demo --validate
    # exits 0 after the script presses Esc; watch stdout for each key's effect

Without a window manager nothing gives the window keyboard focus, so the
script focuses the window under the pointer. It presses P (screenshot),
2 (image_space), C three times (direct alone, surface caustics alone, all),
9 (no such technique: ignored), Space, R, 1, Space, drags with the
left (orbit) and right (pan) buttons, scrolls, holds W, drags with L held
(moves the light), then Esc.
"""
import ctypes
import sys
import time

x = ctypes.CDLL("libX11.so.6")
t = ctypes.CDLL("libXtst.so.6")
x.XOpenDisplay.restype = ctypes.c_void_p
x.XDefaultRootWindow.restype = ctypes.c_ulong
d = ctypes.c_void_p(x.XOpenDisplay(None))
if not d:
    sys.exit("cannot open the X display (set DISPLAY)")


def key(name, down=None):
    code = x.XKeysymToKeycode(d, x.XStringToKeysym(name.encode()))
    for state in ([1, 0] if down is None else [down]):
        t.XTestFakeKeyEvent(d, code, state, 0)
        x.XFlush(d)
        time.sleep(0.05)
    time.sleep(0.6)


def move(px, py):
    t.XTestFakeMotionEvent(d, -1, px, py, 0)
    x.XFlush(d)
    time.sleep(0.1)


def button(b, down):
    t.XTestFakeButtonEvent(d, b, down, 0)
    x.XFlush(d)
    time.sleep(0.1)


time.sleep(float(sys.argv[1]) if len(sys.argv) > 1 else 4.0)
move(200, 200)
root = ctypes.c_ulong(x.XDefaultRootWindow(d))
r, c = ctypes.c_ulong(), ctypes.c_ulong()
i, m = ctypes.c_int(), ctypes.c_uint()
x.XQueryPointer(d, root, ctypes.byref(r), ctypes.byref(c), ctypes.byref(i),
                ctypes.byref(i), ctypes.byref(i), ctypes.byref(i), ctypes.byref(m))
if not c.value:
    sys.exit("no window under the pointer at (200, 200)")
x.XSetInputFocus(d, c, 2, 0)
x.XFlush(d)
for k in ["P", "2", "c", "c", "c", "9", "space", "R", "1", "space"]:
    key(k)
button(1, 1); move(250, 220); move(300, 240); button(1, 0)  # orbit
button(3, 1); move(280, 230); button(3, 0)  # pan
button(4, 1); button(4, 0); button(5, 1); button(5, 0)  # wheel
key("w", 1); time.sleep(0.5); key("w", 0)  # fly
key("l", 1); button(1, 1); move(220, 200); move(180, 190); button(1, 0); key("l", 0)  # light
time.sleep(1.0)
key("Escape")
