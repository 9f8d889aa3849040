#!/usr/bin/env python3
"""Writes assets/scenes/meshes/cup.obj: a metal cup (Wand & Strasser 2003's
self-reflecting cup), a closed solid of revolution about +y standing on
y = 0: outer bottom disc, outer fillet and slightly flared wall, a flat rim,
the inner wall, a rounded inner corner and the inner bottom. 8 cm across,
9 cm tall, 3 mm wall. Smooth normals per profile point (the profile's own
normal, turned about y), flat ones on the discs and the rim, so the rim's
edges stay sharp; faces wind counter-clockwise seen from outside (checked:
the signed volume is positive). No MTL: the scene gives the material.

Run from the repository root: python3 scripts/cup-mesh.py
"""
import math

SEGMENTS = 64
HEIGHT = 0.09          # rim height, m
R_BOTTOM = 0.036       # outer radius at the foot
R_TOP = 0.040          # outer radius at the rim
WALL = 0.003           # wall thickness
FLOOR = 0.005          # bottom thickness
FILLET_OUT = 0.006     # outer foot rounding
FILLET_IN = 0.010      # inner corner rounding
FILLET_STEPS = 6


def outer_radius(y):
    return R_BOTTOM + (R_TOP - R_BOTTOM) * y / HEIGHT


def profile():
    """Profile points (r, y, nr, ny) from the outer bottom's centre over the
    rim to the inner bottom's centre, with each point's outward normal in
    the (r, y) plane, grouped in smooth runs (a new run starts a sharp edge)."""
    slope = (R_TOP - R_BOTTOM) / HEIGHT  # dr/dy of the walls
    wall_n = [1.0, -slope]
    length = math.hypot(*wall_n)
    wall_n = [wall_n[0] / length, wall_n[1] / length]
    runs = []
    # Outer bottom disc, facing down, out to where the foot fillet starts.
    runs.append([(0.0, 0.0, 0.0, -1.0), (R_BOTTOM - FILLET_OUT, 0.0, 0.0, -1.0)])
    # Foot fillet: a quarter circle from facing down to the wall's normal.
    cx, cy = R_BOTTOM - FILLET_OUT, FILLET_OUT
    end = math.atan2(wall_n[1], wall_n[0])
    fillet = []
    for k in range(FILLET_STEPS + 1):
        a = -math.pi / 2 + (end + math.pi / 2) * k / FILLET_STEPS
        fillet.append((cx + FILLET_OUT * math.cos(a), cy + FILLET_OUT * math.sin(a), math.cos(a), math.sin(a)))
    # Outer wall up to the rim.
    fillet.append((outer_radius(HEIGHT), HEIGHT, wall_n[0], wall_n[1]))
    runs.append(fillet)
    # Rim, facing up.
    runs.append([(outer_radius(HEIGHT), HEIGHT, 0.0, 1.0), (outer_radius(HEIGHT) - WALL, HEIGHT, 0.0, 1.0)])
    # Inner wall down to the inner fillet, normals pointing into the cup.
    inner = [(outer_radius(HEIGHT) - WALL, HEIGHT, -wall_n[0], -wall_n[1])]
    y0 = FLOOR + FILLET_IN
    ri = outer_radius(y0) - WALL
    inner.append((ri, y0, -wall_n[0], -wall_n[1]))
    # Inner fillet: from the wall's inward normal round to facing up.
    cx, cy = ri - FILLET_IN, y0
    for k in range(1, FILLET_STEPS + 1):
        a = (math.pi / 2) * k / FILLET_STEPS  # 0: toward -r (wall), pi/2: up
        inner.append((cx + FILLET_IN * math.cos(a), cy - FILLET_IN * math.sin(a), -math.cos(a), math.sin(a)))
    inner.append((0.0, FLOOR, 0.0, 1.0))
    runs.append(inner)
    return runs


def main():
    verts, normals, faces = [], [], []

    def ring(r, y, nr, ny):
        first = len(verts)
        if r == 0.0:
            verts.append((0.0, y, 0.0))
            normals.append((0.0, ny, 0.0))
            return [first] * SEGMENTS
        for s in range(SEGMENTS):
            phi = 2.0 * math.pi * s / SEGMENTS
            c, si = math.cos(phi), math.sin(phi)
            verts.append((r * c, y, r * si))
            normals.append((nr * c, ny, nr * si))
        return list(range(first, first + SEGMENTS))

    for run in profile():
        rings = [ring(*p) for p in run]
        for a, b in zip(rings, rings[1:]):
            for s in range(SEGMENTS):
                t = (s + 1) % SEGMENTS
                # Profile runs from a toward b; phi grows from +x toward +z.
                quad = [a[s], a[t], b[t], b[s]]
                tri = [quad[0], quad[1], quad[2]], [quad[0], quad[2], quad[3]]
                for f in tri:
                    if len(set(f)) == 3:
                        faces.append(f)

    # Winding check: the signed volume of a closed solid wound
    # counter-clockwise seen from outside is positive; flip all if not.
    def sub(p, q): return [p[i] - q[i] for i in range(3)]
    def cross(p, q): return [p[1]*q[2]-p[2]*q[1], p[2]*q[0]-p[0]*q[2], p[0]*q[1]-p[1]*q[0]]
    volume = sum(sum(verts[f[0]][i] * cross(verts[f[1]], verts[f[2]])[i] for i in range(3)) for f in faces) / 6.0
    if volume < 0.0:
        faces = [[f[0], f[2], f[1]] for f in faces]
        volume = -volume
    # Each face's winding normal agrees with its vertices' normals.
    for f in faces:
        n = cross(sub(verts[f[1]], verts[f[0]]), sub(verts[f[2]], verts[f[0]]))
        m = [sum(normals[v][i] for v in f) for i in range(3)]
        assert sum(n[i] * m[i] for i in range(3)) > 0.0, f
    with open("assets/scenes/meshes/cup.obj", "w") as out:
        out.write("# A metal cup: written by scripts/cup-mesh.py (do not edit).\n")
        out.write(f"# {len(verts)} vertices, {len(faces)} triangles, volume {volume * 1e6:.1f} cm^3.\n")
        for v in verts:
            out.write("v %.5f %.5f %.5f\n" % v)
        for n in normals:
            out.write("vn %.4f %.4f %.4f\n" % n)
        for f in faces:
            out.write("f " + " ".join(f"{i + 1}//{i + 1}" for i in f) + "\n")
    print(f"assets/scenes/meshes/cup.obj: {len(verts)} vertices, {len(faces)} triangles, {volume * 1e6:.1f} cm^3")


if __name__ == "__main__":
    main()
