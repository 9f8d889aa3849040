#!/usr/bin/env python3
"""A hostile corpus for the release binary (issue 31; not part of the suite).

Runs `caustics` on several hundred hostile inputs and checks, for each:
- it ends within TIMEOUT seconds (no hang on a FIFO, no endless read);
- exit code 0, or 1 with exactly one line on stderr starting `error: `
  (no panic, no backtrace);
- on exit 1, no output file appeared; on exit 0, the EXR is finite;
- special files at the output path (a symlink, a FIFO, a device node made
  with mknod when run as root) are still what they were, and the file a
  symlink points to is unchanged;
- inputs are never overwritten (an output naming the scene's texture);
- nothing outside the scene's folder is read through a glTF URI (the
  canary file outside the folder is never named in a success).

    cargo build --release
    scripts/hostile-corpus.py [--binary target/release/caustics] [--limit N]

Prints one line per failed case and a summary; exits 1 if any case failed.
The cases: every number of three canonical scenes replaced by hostile
values (NaN, infinities, huge, negative, zero, wrong types), fields
removed, special files as the scene, a mesh, a glTF buffer and the output,
glTF URIs that leave the folder, and outputs that name inputs.
"""
import argparse
import json
import os
import re
import shutil
import stat
import subprocess
import sys
import tempfile
import time

TIMEOUT = 60
HOSTILE_NUMBERS = ["nan", "inf", "-inf", "1e300", "-1e300", "1e20", "-1", "0", "1e-30",
                   "9223372036854775807", "\"text\"", "[]"]


def run(binary, args, cwd):
    env = dict(os.environ)
    env.setdefault("VK_DRIVER_FILES", "/usr/share/vulkan/icd.d/lvp_icd.x86_64.json")
    env.pop("RUST_BACKTRACE", None)
    start = time.time()
    try:
        p = subprocess.run([binary] + args, cwd=cwd, env=env, capture_output=True,
                           text=True, timeout=TIMEOUT, stdin=subprocess.DEVNULL)
    except subprocess.TimeoutExpired:
        return None, "", f"timed out after {TIMEOUT} s", time.time() - start
    return p.returncode, p.stdout, p.stderr, time.time() - start


def finite_exr(path):
    try:
        import numpy as np
        import OpenEXR
    except ImportError:
        return True  # not checked without the Python EXR bindings
    channels = OpenEXR.File(str(path)).channels()
    return all(np.isfinite(np.asarray(c.pixels)).all() for c in channels.values())


class Corpus:
    def __init__(self, binary, root, limit):
        self.binary, self.root, self.limit = binary, root, limit
        self.cases = 0
        self.failures = []
        self.exits = {}

    def case(self, name, args, cwd, out, extra_check=None):
        if self.limit and self.cases >= self.limit:
            return
        self.cases += 1
        for f in [out, os.path.splitext(out)[0] + ".exr", os.path.splitext(out)[0] + ".png"]:
            if os.path.isfile(f) and not os.path.islink(f):
                os.remove(f)
        code, stdout, stderr, seconds = run(self.binary, args, cwd)
        self.exits[code] = self.exits.get(code, 0) + 1
        why = []
        if code is None:
            why.append(stderr)
        elif code == 0:
            exr = os.path.splitext(out)[0] + ".exr"
            if os.path.isfile(exr) and not finite_exr(exr):
                why.append("exit 0 with a non-finite EXR")
        elif code == 1:
            lines = stderr.strip("\n").split("\n")
            if len(lines) != 1 or not lines[0].startswith("error: "):
                why.append(f"exit 1 with {len(lines)} lines on stderr: {stderr[:300]!r}")
            for f in [os.path.splitext(out)[0] + ".exr", os.path.splitext(out)[0] + ".png"]:
                if os.path.isfile(f) and not os.path.islink(f) and "special" not in name:
                    why.append(f"exit 1 but {f} was written")
        else:
            why.append(f"exit {code}: {stderr[-300:]!r}")
        if "panicked" in stderr or "backtrace" in stderr:
            why.append("a panic")
        if extra_check:
            problem = extra_check(code, stdout, stderr)
            if problem:
                why.append(problem)
        if why:
            self.failures.append(f"{name}: {'; '.join(why)}")


def scene_mutations(text):
    """(name, text) for every number replaced by each hostile value, and
    every `key = value` line removed."""
    lines = text.split("\n")
    number = re.compile(r"(?<![\w.])-?\d+(\.\d+)?([eE][-+]?\d+)?(?![\w.])")
    for i, line in enumerate(lines):
        if line.strip().startswith("#") or "=" not in line:
            continue
        key, value = line.split("=", 1)
        matches = list(number.finditer(value))
        for m in matches[:1]:
            for h in HOSTILE_NUMBERS:
                v = value[:m.start()] + h + value[m.end():]
                yield f"line {i + 1} {key.strip()}={h}", "\n".join(lines[:i] + [key + "=" + v] + lines[i + 1:])
        yield f"line {i + 1} {key.strip()} removed", "\n".join(lines[:i] + lines[i + 1:])


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--binary", default="target/release/caustics")
    ap.add_argument("--limit", type=int, default=0, help="stop after N cases (0: all)")
    a = ap.parse_args()
    binary = os.path.abspath(a.binary)
    repo = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    root = tempfile.mkdtemp(prefix="caustics-hostile-")
    c = Corpus(binary, root, a.limit)
    small = ["--width", "8", "--height", "8"]
    out = os.path.join(root, "out.png")
    scenes_dir = os.path.join(root, "scenes")
    os.makedirs(scenes_dir)
    # The canonical scenes' meshes and textures, beside copies of the scenes.
    for sub in ["meshes", "textures", "environments"]:
        shutil.copytree(os.path.join(repo, "assets", sub), os.path.join(root, sub))

    # 1. Scene values.
    for scene in ["ball_lens", "ring_sky", "volume_box"]:
        text = open(os.path.join(repo, "assets", "scenes", scene + ".toml")).read()
        for n, (what, mutated) in enumerate(scene_mutations(text)):
            path = os.path.join(scenes_dir, f"{scene}_{n}.toml")
            with open(path, "w") as f:
                f.write(mutated)
            c.case(f"{scene}: {what}", ["render", "--scene", path, "--technique", "direct", "--out", out] + small, root, out)

    # 2. Special files as inputs.
    fifo = os.path.join(root, "fifo")
    os.mkfifo(fifo)
    for p in [fifo, "/dev/zero", root, "/dev/null"]:
        c.case(f"--scene {p}", ["render", "--scene", p, "--out", out] + small, root, out)
    mesh_scene = os.path.join(scenes_dir, "mesh_fifo.toml")
    with open(mesh_scene, "w") as f:
        f.write(open(os.path.join(repo, "assets", "scenes", "cup.toml")).read().replace("../meshes/cup.obj", "../fifo"))
    c.case("OBJ path is a FIFO", ["render", "--scene", mesh_scene, "--out", out] + small, root, out)
    for p in ["/dev/zero", fifo, root]:
        s = os.path.join(scenes_dir, "grid.toml")
        smoke = open(os.path.join(repo, "assets", "scenes", "smoke.toml")).read()
        with open(s, "w") as f:
            f.write(re.sub(r"(?m)^density = .*$", 'density = { grid = "' + p + '", dims = [4, 4, 4] }', smoke))
        c.case(f"density grid {p}", ["render", "--scene", s, "--out", out] + small, root, out)

    # 3. glTF URIs that leave the folder (a canary outside it).
    gltf_dir = os.path.join(root, "gltf")
    os.makedirs(gltf_dir)
    canary = os.path.join(root, "canary.bin")
    with open(canary, "wb") as f:
        f.write(b"\0" * 4096)
    os.symlink(canary, os.path.join(gltf_dir, "inside_link.bin"))
    uris = ["file://" + canary, canary, "../canary.bin", "%2e%2e/canary.bin", "%2E%2E%2Fcanary.bin",
            "sub/../../canary.bin", "inside_link.bin", "http://example.com/x.bin", "C:/x.bin", "/dev/zero", "../fifo"]
    for uri in uris:
        doc = {"asset": {"version": "2.0"}, "buffers": [{"uri": uri, "byteLength": 36}],
               "bufferViews": [{"buffer": 0, "byteLength": 36}],
               "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                              "min": [0, 0, 0], "max": [0, 0, 0]}],
               "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
               "nodes": [{"mesh": 0}], "scenes": [{"nodes": [0]}]}
        path = os.path.join(gltf_dir, "uri.gltf")
        with open(path, "w") as f:
            json.dump(doc, f)
        c.case(f"glTF buffer URI {uri}", ["render", "--scene", path, "--out", out] + small, root, out,
               lambda code, so, se: "read outside the glTF's folder" if code == 0 else None)
    for count in [2 ** 62, 2 ** 32 + 1, 2 ** 64 - 1]:
        doc["buffers"][0]["uri"] = "data:application/octet-stream;base64," + "A" * 48
        doc["accessors"][0]["count"] = count
        with open(path, "w") as f:
            json.dump(doc, f)
        c.case(f"glTF accessor count {count}", ["render", "--scene", path, "--out", out] + small, root, out)

    # 4. Special files and inputs as outputs.
    ball = os.path.join(repo, "assets", "scenes", "ball_lens.toml")
    target = os.path.join(root, "target.txt")
    with open(target, "w") as f:
        f.write("keep")
    specials = {}
    link = os.path.join(root, "special_link.png")
    os.symlink(target, link)
    specials[link] = "link"
    ofifo = os.path.join(root, "special_fifo.png")
    os.mkfifo(ofifo)
    specials[ofifo] = "fifo"
    if os.geteuid() == 0:
        dev = os.path.join(root, "special_full.png")
        os.mknod(dev, 0o666 | stat.S_IFCHR, os.makedev(1, 7))
        specials[dev] = "char"
    kinds = {"link": os.path.islink, "fifo": lambda p: stat.S_ISFIFO(os.lstat(p).st_mode),
             "char": lambda p: stat.S_ISCHR(os.lstat(p).st_mode)}
    for p, kind in specials.items():
        for command in (["render", "--scene", ball] + small, ["reference", "--scene", ball, "--photons", "4096"] + small):
            for o in [p, os.path.splitext(p)[0] + ".exr"]:
                c.case(f"special {kind} output {command[0]} {os.path.basename(o)}", command + ["--out", o], root, out,
                       lambda code, so, se, p=p, kind=kind: None if kinds[kind](p) and open(target).read() == "keep"
                       else f"{p} is no longer a {kind} or its target changed")
        c.case(f"special {kind} as bench --json", ["bench", "--scene", ball, "--frames", "1", "--json", p] + small,
               root, out, lambda code, so, se, p=p, kind=kind: None if kinds[kind](p) else f"{p} replaced")
    tiles = os.path.join(repo, "assets", "scenes", "pool_tiles.toml")
    tex = os.path.join(root, "scenes", "..", "textures", "pool_tiles.png")
    copy = os.path.join(scenes_dir, "tiles.toml")
    with open(copy, "w") as f:
        f.write(open(tiles).read())
    before = open(tex, "rb").read()
    for o in [tex, os.path.splitext(tex)[0] + ".exr"]:
        c.case(f"output names the texture ({os.path.basename(o)})", ["render", "--scene", copy, "--out", o] + small,
               root, out, lambda code, so, se: None if open(tex, "rb").read() == before else "the texture was overwritten")

    print(f"{c.cases} cases, {len(c.failures)} failed; exit codes: "
          + ", ".join(f"{k}: {v}" for k, v in sorted(c.exits.items(), key=lambda kv: str(kv[0]))))
    for f in c.failures:
        print("FAIL", f)
    shutil.rmtree(root, ignore_errors=True)
    sys.exit(1 if c.failures else 0)


if __name__ == "__main__":
    main()
