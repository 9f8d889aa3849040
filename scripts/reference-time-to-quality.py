#!/usr/bin/env python3
"""Time to quality of the ground truth (issue #27): the wall time
`caustics reference` needs to reach an LDR-FLIP of 0.10 and 0.05 against a
converged image of the same scene, per scene, for one or more builds of it
(and Mitsuba 3 where scripts/mitsuba_scenes.py translates the scene).

    cargo build --release
    scripts/reference-time-to-quality.py [--size 128] [--scenes ball_lens,...]
        [--binary 'LABEL=PATH [OPTIONS]' ...] [--converged-seconds 240]

For each scene: a converged image, traced once by the first binary for
--converged-seconds with its own seed and kept under
target/tmp/time-to-quality/ (delete it to trace again); then, per binary,
a ladder of runs with `--seconds 1, 2, 4, ...` (another seed; `--first`
sets the first rung, `--extra "--pass-photons 16384"` smaller passes) until the
FLIP falls below 0.05 or the ladder reaches --cap seconds. The seconds are
the tracing time the binary reports (device start-up and pipeline
compilation excluded, as Mitsuba's JIT warm-up is). The time to a FLIP is
interpolated log-log between the two rungs around it. FLIP: the
flip-evaluator package's LDR-FLIP mean after the project's PNG tonemap
(exposure, Reinhard x/(1+x), sRGB).

    pip install flip-evaluator openexr numpy   # mitsuba too, for --mitsuba

--mitsuba runs Mitsuba's `llvm_ad_rgb`, which aborts with Debian 12's
LLVM 15: unpack LLVM 19 beside it (`apt-get download libllvm19 && dpkg -x
libllvm19_*.deb /tmp/llvm19/root`; that path is the default) or point
DRJIT_LIBLLVM_PATH at a libLLVM.so.19.
"""
import argparse
import math
import os
import re
import subprocess
import sys
import tomllib

import numpy as np
import OpenEXR
import flip_evaluator as flip

SCENES = ["ball_lens", "ball_lens_top", "water_pool", "volume_cone", "still_life", "medium_box"]
TARGETS = [0.10, 0.05]
CACHE = "target/tmp/time-to-quality"


def exposure(scene):
    with open(f"assets/scenes/{scene}.toml", "rb") as f:
        return float(tomllib.load(f).get("output", {}).get("exposure", 1.0))


def tonemap(rgb, scale):
    x = np.clip(rgb * scale, 0.0, None)
    x = x / (1.0 + x)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1.0 / 2.4) - 0.055).astype(np.float32)


def flip_error(converged, image, scale):
    return float(flip.evaluate(tonemap(converged, scale), tonemap(image, scale), "LDR", applyMagma=False)[1])


def read_exr(path):
    with OpenEXR.File(path) as f:
        channels = f.channels()
        key = "RGBA" if "RGBA" in channels else "RGB" if "RGB" in channels else None
        if key:
            return np.asarray(channels[key].pixels, dtype=np.float32)[..., :3]
        return np.stack([np.asarray(channels[c].pixels, dtype=np.float32) for c in "RGB"], -1)


def ours(binary, scene, size, seconds, seed, out, extra):
    run = subprocess.run(
        [binary, "reference", "--scene", f"assets/scenes/{scene}.toml", "--width", str(size),
         "--height", str(size), "--seconds", str(seconds), "--seed", str(seed), "--out", out, *extra],
        check=True, capture_output=True, text=True)
    traced = re.search(r"traced (\d+) photons in \d+ passes, ([0-9.]+) s", run.stdout)
    return float(traced.group(2)), int(traced.group(1)), read_exr(out)


def time_to(target, rungs):
    """Seconds to reach FLIP `target`, log-log between the rungs around it."""
    for (t0, f0), (t1, f1) in zip(rungs, rungs[1:]):
        if f0 > target >= f1 and f0 > f1:
            a = math.log(f0 / target) / math.log(f0 / f1)
            return math.exp(math.log(t0) + a * math.log(t1 / t0))
    if rungs and rungs[0][1] <= target:
        return rungs[0][0]  # at or below it from the first rung on
    return None


# Mitsuba 3's applicable integrator per scene: a point light's caustic
# through glass needs light tracing (`path` cannot hit a point light through
# a dielectric); the medium box has an area light (`volpath`).
MITSUBA_INTEGRATORS = {
    "ball_lens": ("ptracer", 130, {}),
    "ball_lens_top": ("ptracer", 130, {}),
    "medium_box": ("volpath", 1000, {"rr_depth": 5}),
}
# Our options per scene (the medium box: 6 diffuse bounces, issue #27).
OUR_OPTIONS = {"medium_box": ["--diffuse-bounces", "6"]}


def mitsuba_measure(scene, size):
    """Mitsuba's converged image (16384 samples per pixel, once) and a
    measure(spp) for the ladder, in its fastest variant that runs here
    (`llvm_ad_rgb` with Debian's LLVM 19 unpacked, GUIDE §8, on every core).
    Each rung renders twice and times the second (JIT compilation excluded)."""
    import time
    os.environ.setdefault("DRJIT_LIBLLVM_PATH", "/tmp/llvm19/root/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1")
    import mitsuba as mi
    import mitsuba_scenes  # scripts/, beside this file
    mi.set_variant("llvm_ad_rgb")
    integrator, depth, options = MITSUBA_INTEGRATORS[scene]
    loaded = mi.load_dict(mitsuba_scenes.scene(scene, size, integrator, depth, **options))
    path = f"{CACHE}/{scene}-{size}-mitsuba-converged.npy"
    if not os.path.exists(path):
        total = np.zeros((size, size, 3))
        for k in range(4):
            total += np.asarray(mi.render(loaded, spp=4096, seed=1000 + k))[..., :3]
        np.save(path, total / 4)
    converged = np.load(path)

    def measure(spp):
        mi.render(loaded, spp=spp, seed=7)
        start = time.perf_counter()
        image = np.asarray(mi.render(loaded, spp=spp, seed=8))[..., :3]
        return time.perf_counter() - start, f"{spp} spp", image

    return converged, measure


def ladder(name, measure, converged, scale, first, cap):
    rungs = []
    budget = first
    while True:
        seconds, detail, image = measure(budget)
        rungs.append((seconds, flip_error(converged, image, scale)))
        print(f"  {name}: {detail}, {seconds:.1f} s, FLIP {rungs[-1][1]:.4f}", flush=True)
        if rungs[-1][1] < min(TARGETS) or budget * 2 > cap:
            return rungs
        budget *= 2


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--size", type=int, default=128)
    p.add_argument("--scenes", default=",".join(SCENES))
    p.add_argument("--binary", action="append", default=[],
                   help="'LABEL=PATH [OPTIONS]' (repeatable): OPTIONS go to that binary's runs only")
    p.add_argument("--converged-seconds", type=float, default=240)
    p.add_argument("--cap", type=float, default=256, help="longest rung (s)")
    p.add_argument("--first", type=float, default=1, help="first rung (s; with small --pass-photons below 1)")
    p.add_argument("--mitsuba", action="store_true", help="also Mitsuba 3 (scripts/mitsuba_scenes.py)")
    p.add_argument("--extra", default="", help="more `caustics reference` options for every run")
    a = p.parse_args()
    binaries = [(label, *rest.split()) for label, rest in (b.split("=", 1) for b in a.binary)]
    binaries = binaries or [("ours", "target/release/caustics")]
    os.makedirs(CACHE, exist_ok=True)
    results = []
    for scene in a.scenes.split(","):
        scale = exposure(scene)
        extra = a.extra.split() + OUR_OPTIONS.get(scene, [])
        path = f"{CACHE}/{scene}-{a.size}-converged.exr"
        if not os.path.exists(path):
            print(f"{scene}: converging with {binaries[0][1]} for {a.converged_seconds} s", flush=True)
            ours(binaries[0][1], scene, a.size, a.converged_seconds, 1000, path, extra + list(binaries[0][2:]))
        converged = read_exr(path)
        for label, binary, *options in binaries:
            def measure(seconds, binary=binary, options=options):
                t, photons, image = ours(binary, scene, a.size, seconds, 7, f"/tmp/ttq-{label}.exr", extra + options)
                return t, f"{photons / 1e6:.1f} M photons", image
            rungs = ladder(f"{scene} {label}", measure, converged, scale, a.first, a.cap)
            results.append((scene, label, rungs))
        if a.mitsuba and scene in MITSUBA_INTEGRATORS:
            mi_converged, measure = mitsuba_measure(scene, a.size)
            rungs = ladder(f"{scene} mitsuba", measure, mi_converged, scale, 1, 1 << 16)
            results.append((scene, f"Mitsuba `{MITSUBA_INTEGRATORS[scene][0]}`", rungs))
    print()
    print("| scene | renderer | " + " | ".join(f"s to FLIP {t:.2f}" for t in TARGETS) + " | last rung |")
    print("| --- | --- | " + " | ".join("---:" for _ in TARGETS) + " | ---: |")
    for scene, label, rungs in results:
        cells = []
        for target in TARGETS:
            t = time_to(target, rungs)
            cells.append(f"{t:.1f}" if t is not None else f"> {rungs[-1][0]:.0f}")
        print(f"| `{scene}` | {label} | " + " | ".join(cells) + f" | {rungs[-1][0]:.1f} s: {rungs[-1][1]:.4f} |")


if __name__ == "__main__":
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    main()
