#!/usr/bin/env python3
"""Time to a given FLIP, our ground truth against Mitsuba 3's `ptracer`.

Both render assets/scenes/ball_lens.toml (point light 60 W/sr, glass
sphere n 1.5 r 1, 10x10 floor of albedo 0.8, the scene's camera) at SIZE^2.
Each renderer is judged against its own converged image (Mitsuba's sphere
is analytic, ours tessellated, so they are not compared with each other):
for a ladder of budgets, the wall time and the LDR-FLIP (flip-evaluator,
after the project's PNG tonemap: Reinhard x/(1+x), sRGB) to the converged
image. Prints a table and the time each needs to reach FLIP_TARGET.

    pip install mitsuba flip-evaluator openexr numpy
    cargo build --release
    scripts/reference-vs-mitsuba.py [SIZE] [FLIP_TARGET]

Mitsuba runs its `scalar_rgb` variant on every core (its `llvm_ad_rgb`
variant failed in LLVM 15 code generation on this machine).
"""
import subprocess
import sys
import time

import numpy as np
import OpenEXR
import flip_evaluator as flip
import mitsuba as mi

SIZE = int(sys.argv[1]) if len(sys.argv) > 1 else 128
FLIP_TARGET = float(sys.argv[2]) if len(sys.argv) > 2 else 0.1
BINARY = "target/release/caustics"


def tonemap(rgb):
    x = np.clip(rgb, 0.0, None)
    x = x / (1.0 + x)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1.0 / 2.4) - 0.055)


def flip_error(converged, image):
    return flip.evaluate(tonemap(converged), tonemap(image), "LDR", applyMagma=False)[1]


def read_exr(path):
    with OpenEXR.File(path) as f:
        channels = f.channels()
        if "RGBA" in channels or "RGB" in channels:
            key = "RGBA" if "RGBA" in channels else "RGB"
            return np.asarray(channels[key].pixels, dtype=np.float32)[..., :3]
        return np.stack([np.asarray(channels[c].pixels, dtype=np.float32) for c in "RGB"], -1)


def ours(photons, seed):
    out = f"/tmp/ref-vs-mitsuba-{seed}.exr"
    run = subprocess.run(
        [BINARY, "reference", "--width", str(SIZE), "--height", str(SIZE),
         "--photons", str(photons), "--seed", str(seed), "--out", out],
        check=True, capture_output=True, text=True)
    # The tracing time it reports (device start-up and pipeline compilation
    # excluded, as Mitsuba's JIT warm-up is).
    seconds = float(run.stdout.split(" s: ")[0].rsplit(" ", 1)[1])
    return seconds, read_exr(out)


def mitsuba_scene():
    mi.set_variant("scalar_rgb")
    return mi.load_dict({
        "type": "scene",
        "integrator": {"type": "ptracer", "max_depth": 130},
        "sensor": {
            "type": "perspective", "fov": 40.0, "fov_axis": "y",
            "to_world": mi.ScalarTransform4f().look_at(origin=[0, 5, 7], target=[0, 0.8, 0], up=[0, 1, 0]),
            "film": {"type": "hdrfilm", "width": SIZE, "height": SIZE, "rfilter": {"type": "box"}},
            "sampler": {"type": "independent"},
        },
        "light": {"type": "point", "position": [0, 8, 0], "intensity": {"type": "rgb", "value": [60, 60, 60]}},
        "lens": {
            "type": "sphere", "center": [0, 1.6, 0], "radius": 1.0,
            "bsdf": {"type": "dielectric", "int_ior": 1.5, "ext_ior": 1.0},
        },
        "floor": {
            "type": "rectangle",
            "to_world": mi.ScalarTransform4f().rotate([1, 0, 0], -90).scale([5, 5, 1]),
            "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.8, 0.8, 0.8]}},
        },
    })


def theirs(scene, spp, seed):
    start = time.time()
    image = mi.render(scene, spp=spp, seed=seed)
    image = np.asarray(image)[..., :3]
    return time.time() - start, image


def ladder(name, render, budgets, converged):
    rows = []
    for budget in budgets:
        seconds, image = render(budget)
        rows.append((budget, seconds, flip_error(converged, image)))
        print(f"{name:8} {budget:>12} {seconds:8.2f} s  FLIP {rows[-1][2]:.4f}", flush=True)
    return rows


def time_to(rows):
    for budget, seconds, error in rows:
        if error <= FLIP_TARGET:
            return budget, seconds
    return None, None


def main():
    scene = mitsuba_scene()
    theirs(scene, 1, 0)  # JIT warm-up
    _, m_converged = theirs(scene, 1024, 12345)
    _, o_converged = ours(1 << 27, 12345)
    o_rows = ladder("ours", lambda n: ours(n, 1), [1 << 20, 1 << 21, 1 << 22, 1 << 23, 1 << 24, 1 << 25, 1 << 26], o_converged)
    m_rows = ladder("mitsuba", lambda s: theirs(scene, s, 1), [1, 2, 4, 8, 16, 32, 64, 128], m_converged)
    ob, os_ = time_to(o_rows)
    mb, ms = time_to(m_rows)
    print(f"time to FLIP <= {FLIP_TARGET} at {SIZE}^2: ours {os_} s ({ob} photons), mitsuba ptracer {ms} s ({mb} spp)")
    if os_ and ms:
        print(f"ratio mitsuba / ours: {ms / os_:.2f}")


if __name__ == "__main__":
    main()
