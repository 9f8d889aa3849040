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
  canary file outside the folder is never named in a success);
- nothing outside a TOML scene's folder tree is read through any path it
  names (mesh, mtllib, map_Kd, albedo_texture, environment, density grid,
  glTF object) unless --allow-paths names the folder: without the flag
  each is refused by the path rule, with it each renders.

    cargo build --release
    scripts/hostile-corpus.py [--binary target/release/caustics] [--limit N]

Prints one line per failed case and a summary; exits 1 if any case failed.
The cases: every number of three canonical scenes replaced by hostile
values (NaN, infinities, huge, negative, zero, wrong types), fields
removed, special files as the scene, a mesh, a glTF buffer and the output,
glTF URIs that leave the folder, TOML paths that leave the scene's tree
(with and without --allow-paths), and outputs that name inputs.
"""
import argparse
import base64
import json
import os
import re
import shutil
import stat
import struct
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
        shutil.copytree(os.path.join(repo, "assets", "scenes", sub), os.path.join(scenes_dir, sub))

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
    # Special files inside the scene's tree (read only if the path rule
    # lets them through), and outside it (refused by the rule first).
    inner_fifo = os.path.join(scenes_dir, "fifo.obj")
    os.mkfifo(inner_fifo)
    inner_dir = os.path.join(scenes_dir, "folder")
    os.makedirs(inner_dir)
    cup = open(os.path.join(repo, "assets", "scenes", "cup.toml")).read()
    for p in ["fifo.obj", "../fifo", "folder"]:
        mesh_scene = os.path.join(scenes_dir, "mesh_fifo.toml")
        with open(mesh_scene, "w") as f:
            f.write(cup.replace("meshes/cup.obj", p))
        c.case(f"OBJ path {p}", ["render", "--scene", mesh_scene, "--out", out] + small, root, out)
    smoke = open(os.path.join(repo, "assets", "scenes", "smoke.toml")).read()
    for p, allow in [("/dev/zero", []), (fifo, []), (root, []), ("fifo.obj", []), ("folder", []),
                     ("/dev/zero", ["--allow-paths", "/dev"]), (fifo, ["--allow-paths", root])]:
        s = os.path.join(scenes_dir, "grid.toml")
        with open(s, "w") as f:
            f.write(re.sub(r"(?m)^density = .*$", 'density = { grid = "' + p + '", dims = [4, 4, 4] }', smoke))
        c.case(f"density grid {p} {' '.join(allow)}", ["render", "--scene", s, "--out", out] + small + allow, root, out)

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

    # 4. TOML paths that leave the scene's tree: valid files outside it,
    # named by every kind of reference in every spelling. Without
    # --allow-paths each must be refused by the path rule (the message
    # names it); with the folder allowed, the real files render.
    outside = os.path.join(root, "outside")
    os.makedirs(outside)
    shutil.copy(os.path.join(scenes_dir, "meshes", "cup.obj"), os.path.join(outside, "cup.obj"))
    shutil.copy(os.path.join(scenes_dir, "textures", "pool_tiles.png"), os.path.join(outside, "tiles.png"))
    shutil.copy(os.path.join(scenes_dir, "environments", "sky.hdr"), os.path.join(outside, "sky.hdr"))
    with open(os.path.join(outside, "x.mtl"), "w") as f:
        f.write("newmtl m\nKd 0.5 0.5 0.5\n")
    with open(os.path.join(outside, "grid.raw"), "wb") as f:
        f.write(b"\0" * 4 * 64)
    # Its buffer inline: a link to the file resolves its URIs beside the link.
    triangle = base64.b64encode(struct.pack("<9f", 0, 0, 0, 1, 0, 0, 0, 0, 1)).decode()
    gltf_doc = {"asset": {"version": "2.0"},
                "buffers": [{"uri": "data:application/octet-stream;base64," + triangle, "byteLength": 36}],
                "bufferViews": [{"buffer": 0, "byteLength": 36}],
                "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                               "min": [0, 0, 0], "max": [1, 0, 1]}],
                "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
                "nodes": [{"mesh": 0}], "scenes": [{"nodes": [0]}]}
    with open(os.path.join(outside, "m.gltf"), "w") as f:
        json.dump(gltf_doc, f)
    tree = os.path.join(root, "tree")
    os.makedirs(os.path.join(tree, "sub"))
    os.symlink(outside, os.path.join(tree, "linked_dir"))
    head = ('[camera]\neye = [0.0, 2.0, 4.0]\ntarget = [0.0, 0.0, 0.0]\n\n'
            '[[light]]\nkind = "point"\nposition = [0.0, 3.0, 0.0]\nintensity = 10.0\n\n'
            '[[material]]\nname = "white"\nkind = "diffuse"\nalbedo = 0.5\n\n'
            '[[object]]\nshape = "plane"\nsize = [4.0, 4.0]\nmaterial = "white"\n\n')
    kinds = {
        "cup.obj": lambda p: f'[[object]]\nshape = "mesh"\npath = "{p}"\nmaterial = "white"\n',
        "tiles.png": lambda p: f'[[material]]\nname = "t"\nkind = "diffuse"\nalbedo_texture = "{p}"\n',
        "sky.hdr": lambda p: f'[[light]]\nkind = "environment"\npath = "{p}"\nscale = 0.001\n',
        "grid.raw": lambda p: ('[medium]\nsigma_s = 0.1\nbounds = { min = [-1.0, 0.0, -1.0], max = [1.0, 1.0, 1.0] }\n'
                               f'density = {{ grid = "{p}", dims = [4, 4, 4] }}\n'),
        "m.gltf": lambda p: f'[[object]]\nshape = "gltf"\npath = "{p}"\n',
        # An OBJ inside the tree whose mtllib, or whose MTL's map_Kd, leaves it.
        "x.mtl": lambda p: '[[object]]\nshape = "mesh"\npath = "inner.obj"\n',
        "tiles.png (map_Kd)": lambda p: '[[object]]\nshape = "mesh"\npath = "inner_kd.obj"\n',
    }
    tri = "v 0 0 0\nv 1 0 0\nv 0 0 1\nvt 0 0\nvt 1 0\nvt 0 1\n"
    spellings = {  # name -> (reference to outside/F from tree/, a real file there)
        "parent": (lambda f: "../outside/" + f, True),
        "absolute": (lambda f: os.path.join(outside, f), True),
        "climb from sub": (lambda f: "sub/../../outside/" + f, True),
        "dot parent": (lambda f: "./../outside/" + f, True),
        "linked folder": (lambda f: "linked_dir/" + f, True),
        "linked file": (lambda f: "link_" + f.replace(" (map_Kd)", ""), True),
        "encoded": (lambda f: "%2e%2e/outside/" + f, False),
    }
    for kind, snippet in kinds.items():
        name = kind.replace(" (map_Kd)", "")
        link = os.path.join(tree, "link_" + name)
        if not os.path.lexists(link):
            os.symlink(os.path.join(outside, name), link)
        for spelling, (ref, real) in spellings.items():
            p = ref(name)
            with open(os.path.join(tree, "inner.obj"), "w") as f:
                f.write(f"mtllib {p}\n{tri}usemtl m\nf 1/1 2/2 3/3\n")
            with open(os.path.join(tree, "inner.mtl"), "w") as f:
                f.write(f"newmtl m\nKd 1 1 1\nmap_Kd {p}\n")
            with open(os.path.join(tree, "inner_kd.obj"), "w") as f:
                f.write(f"mtllib inner.mtl\n{tri}usemtl m\nf 1/1 2/2 3/3\n")
            s = os.path.join(tree, "s.toml")
            with open(s, "w") as f:
                f.write(head + snippet(p))
            args = ["render", "--scene", s, "--technique", "direct", "--out", out] + small
            # A real file outside must be refused by the path rule itself;
            # a name that does not exist (`%2e%2e` is no escape in a path) just fails.
            c.case(f"TOML {kind} {spelling}", args, root, out,
                   lambda code, so, se, real=real: "read outside the scene's tree" if code == 0
                   else f"refused, but not by the path rule: {se.strip()}" if real and "--allow-paths" not in se
                   else None)
            if real:
                c.case(f"TOML {kind} {spelling} --allow-paths", args + ["--allow-paths", outside], root, out,
                       lambda code, so, se: None if code == 0 else "refused with its folder allowed")

    # 5. Special files and inputs as outputs.
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
    tex = os.path.join(scenes_dir, "textures", "pool_tiles.png")
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
