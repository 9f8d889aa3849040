#!/usr/bin/env python3
"""Mitsuba 3 translations of our scene files, to check the ground truth
(`caustics reference`) against an independent renderer.

    import mitsuba as mi
    mi.set_variant("llvm_ad_rgb")          # or "scalar_rgb"
    import mitsuba_scenes
    d = mitsuba_scenes.scene("medium_box", 64, "volpath", 64)
    image = mi.render(mi.load_dict(d), spp=256)

`scene(name, size, integrator_type, max_depth, **kw)` reads
assets/scenes/<name>.toml (or the file `toml=PATH`) and returns a scene
dict for `mi.load_dict`. It translates the subset of the format the
comparison scenes use (docs/SCENES.md), with our radiometry (GUIDE §2):

- camera: a pinhole (`perspective`, `fov_axis` "y" = our `fov_y`), from
  `eye` to `target` with `up`; a box pixel filter (our reference averages
  its samples over the pixel); row 0 at the top in both.
- `point` lights: `intensity` in W/sr. `rect` lights: a `rectangle` with an
  `area` emitter of `radiance` (W m^-2 sr^-1). Mitsuba's area emitter is
  one-sided like ours, emitting to the side of the shape's normal, which is
  our `normal`; our rect is also an object with a black diffuse material
  (its back absorbs), so the rectangle gets a black `diffuse` BSDF
  (without one Mitsuba would give it a 0.5 grey one).
- `diffuse`: Lambertian `reflectance` = our `albedo`. `dielectric`: a
  smooth `dielectric`, `int_ior` our `ior`, `ext_ior` 1 (the medium does
  not change the index). Mitsuba's diffuse BSDF is one-sided (black seen
  from behind), ours is two-sided: every plane must face the camera's side
  (walls facing inward), which the comparison scenes do.
- `plane`: a `rectangle` with our tessellation's corners (tangent as
  `shapes::basis` picks it). `sphere`: by default our exact tessellation
  (UV sphere, `segments` around y, `segments / 2` pole to pole, smooth
  normals, the same two triangles per quad), written to a PLY file; with
  `analytic_sphere=True` Mitsuba's analytic sphere, which is slightly
  larger than the inscribed mesh (at 64 segments the mesh's volume is
  about 0.5% smaller).
- `[medium]` (homogeneous, constant density only): `sigma_t` = sigma_s +
  sigma_a, `albedo` = sigma_s / sigma_t, `isotropic` or `hg` phase with
  our `g` (untested: Mitsuba's sign convention for g is the usual one,
  g > 0 forward). A Mitsuba medium lives between shapes, not in a box, so
  the scene's `bounds` must be the region enclosed by its walls (a closed
  box like medium_box); the medium is attached to both sides of every
  plane (they are opaque, and their normals face inward, so the box's
  interior is each wall's *exterior* in Mitsuba's convention), to the
  exterior of every other shape and light, and to the sensor. The inside
  of a dielectric has no medium, as in our reference. `medium=False` drops
  it (and a scene without `[medium]` has none).

Options (**kw): `toml` (a scene file instead of `name`), `width`/`height`
(default `size`), `medium` (bool), `drop` (object names to leave out),
`analytic_sphere` (bool), `rr_depth` (default: above `max_depth`, so no
Russian roulette truncates anything), `sampler` ("independent"),
`hide_emitters` (bool), `integrator` (extra integrator keys).

Mitsuba's `max_depth` counts path segments: 1 = emitters seen directly,
2 = direct light, k + 2 = k diffuse bounces (our `--diffuse-bounces k`)
when no specular surface or medium is in the way. It counts specular and
medium vertices too; our reference limits diffuse bounces alone (specular
and medium events up to 128).
"""
import math
import os
import struct
import tempfile
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SCENES = ROOT / "assets" / "scenes"
MEDIUM_ID = "medium"


def _norm(v):
    n = math.sqrt(sum(c * c for c in v))
    return [c / n for c in v]


def _cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def _dot(a, b):
    return sum(x * y for x, y in zip(a, b))


def _rgb(value):
    if isinstance(value, (int, float)):
        return [float(value)] * 3
    return [float(c) for c in value]


def _basis(w):
    """src/scene/shapes.rs `basis`: the tangent a plane gets by default."""
    helper = [1.0, 0.0, 0.0] if abs(w[0]) < 0.9 else [0.0, 0.0, 1.0]
    d = _dot(w, helper)
    u = _norm([h - c * d for h, c in zip(helper, w)])
    return u, _cross(w, u)


def _plane_transform(mi, center, normal, size, tangent=None):
    """Mitsuba's rectangle ([-1, 1]^2 in xy, normal +z) onto our plane."""
    n = _norm(normal)
    if tangent is None:
        u, _ = _basis(n)
    else:
        t = _norm(tangent)
        u = _norm([a - b * _dot(n, t) for a, b in zip(t, n)])
    v = _cross(n, u)
    hu = [c * size[0] * 0.5 for c in u]
    hv = [c * size[1] * 0.5 for c in v]
    m = [[hu[i], hv[i], n[i], center[i]] for i in range(3)] + [[0.0, 0.0, 0.0, 1.0]]
    return mi.ScalarTransform4f(m)


def sphere_ply(center, radius, segments=64):
    """Our UV sphere (src/scene/shapes.rs `sphere`) as a binary PLY file with
    vertex normals; returns its path (cached in the temporary directory)."""
    slices = max(segments, 3)
    stacks = max(segments // 2, 2)
    key = "_".join(f"{c:.9g}" for c in [*center, radius, segments])
    path = Path(tempfile.gettempdir()) / f"caustics-sphere-{key}.ply"
    if path.exists():
        return str(path)
    positions, normals = [], []
    for j in range(stacks + 1):
        theta = math.pi * j / stacks
        st, ct = math.sin(theta), math.cos(theta)
        for i in range(slices + 1):
            phi = 2.0 * math.pi * (i % slices) / slices
            if j == 0:
                d = (0.0, 1.0, 0.0)
            elif j == stacks:
                d = (0.0, -1.0, 0.0)
            else:
                d = (st * math.cos(phi), ct, st * math.sin(phi))
            positions.append(tuple(c + radius * x for c, x in zip(center, d)))
            normals.append(d)
    faces = []
    stride = slices + 1
    for j in range(stacks):
        for i in range(slices):
            a = j * stride + i
            b, c, d = a + 1, a + 1 + stride, a + stride
            for tri in ((a, b, c), (a, c, d)):
                p = [positions[k] for k in tri]
                if p[0] != p[1] and p[1] != p[2] and p[0] != p[2]:
                    faces.append(tri)
    header = (
        "ply\nformat binary_little_endian 1.0\n"
        f"element vertex {len(positions)}\n"
        "property float x\nproperty float y\nproperty float z\n"
        "property float nx\nproperty float ny\nproperty float nz\n"
        f"element face {len(faces)}\n"
        "property list uchar int vertex_indices\nend_header\n"
    )
    body = bytearray(header.encode("ascii"))
    for p, n in zip(positions, normals):
        body += struct.pack("<6f", *p, *n)
    for f in faces:
        body += struct.pack("<B3i", 3, *f)
    tmp = path.with_suffix(f".{os.getpid()}.tmp")
    tmp.write_bytes(bytes(body))
    tmp.replace(path)
    return str(path)


def _bsdf(material):
    kind = material.get("kind", "diffuse")
    if kind == "diffuse":
        if "albedo_texture" in material:
            raise ValueError(f"material {material['name']}: textures are not translated")
        albedo = _rgb(material.get("albedo", 0.8))
        return {"type": "diffuse", "reflectance": {"type": "rgb", "value": albedo}}
    if kind == "dielectric":
        if any(a != 0.0 for a in _rgb(material.get("absorption", 0.0))):
            raise ValueError(f"material {material['name']}: absorption is not translated")
        return {"type": "dielectric", "int_ior": float(material.get("ior", 1.5)), "ext_ior": 1.0}
    if kind == "mirror":
        return {"type": "conductor", "material": "none",
                "specular_reflectance": {"type": "rgb", "value": _rgb(material.get("reflectance", 1.0))}}
    raise ValueError(f"material {material['name']}: kind {kind} is not translated")


def _medium(medium):
    if "density" in medium and not isinstance(medium["density"], (int, float)):
        raise ValueError("only a constant medium density is translated")
    density = float(medium.get("density", 1.0))
    s = [density * c for c in _rgb(medium["sigma_s"])]
    a = [density * c for c in _rgb(medium.get("sigma_a", 0.0))]
    t = [x + y for x, y in zip(s, a)]
    albedo = [x / y if y > 0.0 else 0.0 for x, y in zip(s, t)]
    g = float(medium.get("g", 0.0))
    phase = {"type": "isotropic"} if g == 0.0 else {"type": "hg", "g": g}
    return {
        "type": "homogeneous",
        "sigma_t": {"type": "rgb", "value": t},
        "albedo": {"type": "rgb", "value": albedo},
        "scale": 1.0,
        "phase": phase,
    }


def scene(name, size, integrator_type="path", max_depth=8, **kw):
    """A Mitsuba 3 scene dict of assets/scenes/<name>.toml (see the module's
    docstring). Call `mi.set_variant` first."""
    import mitsuba as mi

    path = Path(kw.get("toml") or SCENES / f"{name}.toml")
    with open(path, "rb") as f:
        toml = tomllib.load(f)
    width = int(kw.get("width", size))
    height = int(kw.get("height", size))
    drop = set(kw.get("drop", ()))
    medium = toml.get("medium") if kw.get("medium", True) else None
    ref = {"type": "ref", "id": MEDIUM_ID}

    integrator = {"type": integrator_type, "max_depth": int(max_depth),
                  "rr_depth": int(kw.get("rr_depth", max_depth + 1))}
    if kw.get("hide_emitters"):
        integrator["hide_emitters"] = True
    integrator.update(kw.get("integrator", {}))
    out = {"type": "scene", "integrator": integrator}
    if medium is not None:
        out[MEDIUM_ID] = _medium(medium)

    cam = toml["camera"]
    sensor = {
        "type": "perspective",
        "fov": float(cam.get("fov_y", 45.0)),
        "fov_axis": "y",
        "near_clip": 1e-3,
        "to_world": mi.ScalarTransform4f().look_at(
            origin=cam["eye"], target=cam["target"], up=cam.get("up", [0.0, 1.0, 0.0])),
        "film": {"type": "hdrfilm", "width": width, "height": height,
                 "pixel_format": "rgb", "rfilter": {"type": "box"}},
        "sampler": {"type": kw.get("sampler", "independent")},
    }
    if medium is not None:
        sensor["medium"] = ref
    out["sensor"] = sensor

    black = {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.0, 0.0, 0.0]}}
    for i, light in enumerate(toml.get("light", [])):
        kind = light["kind"]
        if kind == "point":
            out[f"light_{i}"] = {"type": "point", "position": light["position"],
                                 "intensity": {"type": "rgb", "value": _rgb(light["intensity"])}}
        elif kind == "rect":
            shape = {
                "type": "rectangle",
                "to_world": _plane_transform(mi, light["center"], light["normal"], light["size"],
                                             light.get("tangent")),
                "bsdf": dict(black),
                "emitter": {"type": "area", "radiance": {"type": "rgb", "value": _rgb(light["radiance"])}},
            }
            if medium is not None:
                shape["exterior"] = ref
            out[f"light_{i}"] = shape
        else:
            raise ValueError(f"light[{i}]: kind {kind} is not translated")

    materials = {m["name"]: m for m in toml.get("material", [])}
    for i, obj in enumerate(toml["object"]):
        if obj.get("name") in drop:
            continue
        material = materials[obj["material"]]
        bsdf = _bsdf(material)
        shape_kind = obj.get("shape")
        if shape_kind == "plane":
            shape = {"type": "rectangle",
                     "to_world": _plane_transform(mi, obj.get("center", [0.0, 0.0, 0.0]),
                                                  obj.get("normal", [0.0, 1.0, 0.0]), obj["size"],
                                                  obj.get("tangent"))}
            if medium is not None:
                shape["interior"] = ref
                shape["exterior"] = ref
        elif shape_kind == "sphere":
            center = obj.get("center", [0.0, 0.0, 0.0])
            if kw.get("analytic_sphere"):
                shape = {"type": "sphere", "center": center, "radius": float(obj["radius"])}
            else:
                shape = {"type": "ply", "filename": sphere_ply(center, float(obj["radius"]),
                                                               int(obj.get("segments", 64)))}
            if medium is not None:
                shape["exterior"] = ref
        else:
            raise ValueError(f"object[{i}]: shape {shape_kind} is not translated")
        shape["bsdf"] = bsdf
        out[f"object_{i}"] = shape
    return out


if __name__ == "__main__":
    import sys

    import mitsuba as mi

    mi.set_variant("scalar_rgb")
    for n in sys.argv[1:] or ["ball_lens", "ball_lens_top", "medium_box"]:
        mi.load_dict(scene(n, 64, "volpath" if n == "medium_box" else "path", 8))
        print(n, "loads")
