#!/usr/bin/env python3
"""Where users look (issue #28): every technique in every view against the
ground truth, component by component, as one Markdown table.

    cargo build --release
    scripts/views-table.py [--size 128] [--photons 8388608] [--views a,b]
        [--out out/views] [--caustics target/release/caustics]

Runs `caustics compare` once per view (a scene file, or a scene file with
its camera moved, below) with `--techniques all`, so each technique that
applies is rendered per component and compared with the reference's
matching single-bounce component, and reads each report.json
(docs/REPORTS.md). References are cached by `compare`, so a rerun after a
change to a technique traces nothing.

A cell is `energy / FLIP` (energy: relative total, FLIP: LDR-FLIP mean);
`n/a` where the technique does not model the component on this scene
(`compare`'s "not applicable": it renders the component only in part, or
not at all while the reference has light there); `-` where neither image
holds any light (a scene without media has no airlight). `frame`: the
full frame against the reference's; `modelled`: with components not
applicable, both frames without them (`=`: the same as the frame), bold
where it meets issue #28's goal, FLIP at most 0.10 and energy within 5%.
The table goes to stdout and to OUT/table.md.
"""
import argparse
import json
import os
import re
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCENES = os.path.join(ROOT, "assets", "scenes")

# (label, scene file, camera override or None). The pool from below is
# water_pool with the camera of tests/suite/water_photons.rs's
# `pool_caustics_from_below_match_the_reference`.
VIEWS = [
    ("ball_lens", "ball_lens.toml", None),
    ("ball_lens_top", "ball_lens_top.toml", None),
    ("mirror_caustic", "mirror_caustic.toml", None),
    ("water_pool", "water_pool.toml", None),
    (
        "water_pool_below",
        "water_pool.toml",
        {"eye": [0.5, 0.9, 2.6], "target": [-0.3, 0.0, -1.0], "fov_y": 60.0},
    ),
    ("ring_sky", "ring_sky.toml", None),
    ("still_life", "still_life.toml", None),
    ("light_shaft", "light_shaft.toml", None),
    ("mesh_glass", "mesh_glass.toml", None),
    ("gemstone", "gemstone.toml", None),
]

COMPONENTS = ["direct", "surface_caustics", "airlight", "volume_caustics"]
GOAL_FLIP, GOAL_ENERGY = 0.10, 0.05


def moved_camera(scene_file, camera, out_dir):
    """A copy of `scene_file` in out_dir with its [camera] table replaced
    and every relative `path` made absolute (the copy lives elsewhere)."""
    text = open(scene_file).read()
    block = "[camera]\n" + "".join(f"{k} = {json.dumps(v)}\n" for k, v in camera.items())
    text, n = re.subn(r"^\[camera\]\n(?:[^\[\n][^\n]*\n|\n)*?(?=^\[|\Z)", block + "\n", text, flags=re.M)
    if n != 1:
        sys.exit(f"{scene_file}: no [camera] table to replace")
    folder = os.path.dirname(os.path.abspath(scene_file))
    text = re.sub(
        r'^(\s*path\s*=\s*)"([^"/][^"]*)"',
        lambda m: f'{m.group(1)}"{os.path.join(folder, m.group(2))}"',
        text,
        flags=re.M,
    )
    path = os.path.join(out_dir, os.path.basename(scene_file).replace(".toml", "_moved.toml"))
    os.makedirs(out_dir, exist_ok=True)
    with open(path, "w") as f:
        f.write(text)
    return path


def cell(metrics):
    return f"{metrics['energy']:+.1%} / {metrics['flip']:.3f}"


def rows(label, report):
    noise = report["reference"]["noise"]
    noise = f"{noise['flip']:.3f}" if noise else "?"
    for t in report["techniques"]:
        comps = {c["component"]: c["metrics"] for c in t["components"]}
        na = {c["component"] for c in t.get("not_applicable", [])}
        cells = []
        for c in COMPONENTS:
            if c in na:
                cells.append("n/a")
            elif c not in comps or (comps[c]["rmse"] == 0.0 and comps[c]["flip"] == 0.0):
                cells.append("-")
            else:
                cells.append(cell(comps[c]))
        modelled = t.get("modelled") or t["full"]
        claimed = cell(modelled) if t.get("modelled") else "="
        if modelled["flip"] <= GOAL_FLIP and abs(modelled["energy"]) <= GOAL_ENERGY:
            claimed = f"**{claimed}**"
        ms = t["timing"]["frame_ms"]
        yield (f"| `{label}` | {t['technique']} | " + " | ".join(cells)
               + f" | {cell(t['full'])} | {claimed} | {noise} | {ms:.0f} |")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--size", type=int, default=128)
    ap.add_argument("--photons", type=int, default=1 << 23)
    ap.add_argument("--views", help="comma-separated labels (default: all)")
    ap.add_argument("--out", default=os.path.join(ROOT, "out", "views"))
    ap.add_argument("--caustics", default=os.path.join(ROOT, "target", "release", "caustics"))
    args = ap.parse_args()
    wanted = set(args.views.split(",")) if args.views else None
    unknown = (wanted or set()) - {v[0] for v in VIEWS}
    if unknown:
        sys.exit(f"unknown views: {', '.join(sorted(unknown))} (known: {', '.join(v[0] for v in VIEWS)})")
    header = [
        f"{args.size}², reference {args.photons} photons; cells: energy / FLIP against the reference's matching component",
        "",
        "| view | technique | direct | surface caustics | airlight | volume caustics | frame | modelled | reference noise (FLIP) | ms/frame |",
        "| --- | --- | --- | --- | --- | --- | --- | --- | ---: | ---: |",
    ]
    lines = list(header)
    for label, scene, camera in VIEWS:
        if wanted and label not in wanted:
            continue
        scene_file = os.path.join(SCENES, scene)
        extra = []
        if camera:
            scene_file = moved_camera(scene_file, camera, os.path.join(args.out, "scenes"))
            extra = ["--allow-paths", SCENES]
        out = os.path.join(args.out, label)
        cmd = [args.caustics, "compare", "--scene", scene_file, "--techniques", "all",
               "--width", str(args.size), "--height", str(args.size),
               "--photons", str(args.photons), "--out", out] + extra
        print("+", " ".join(cmd), file=sys.stderr, flush=True)
        subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
        with open(os.path.join(out, "report.json")) as f:
            lines.extend(rows(label, json.load(f)))
        print(lines[-1], file=sys.stderr, flush=True)
    table = "\n".join(lines) + "\n"
    os.makedirs(args.out, exist_ok=True)
    with open(os.path.join(args.out, "table.md"), "w") as f:
        f.write(table)
    print(table)


if __name__ == "__main__":
    main()
