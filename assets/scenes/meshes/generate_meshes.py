#!/usr/bin/env python3
"""Generates the canonical meshes of assets/scenes/meshes (run from this folder).

gemstone.obj: a brilliant-cut-like gem (table, crown, girdle, pavilion),
  flat facets with one normal per face, no MTL (the scene gives the material).
glass.obj + glass.mtl: a goblet of revolution with a thick wall, quads and
  triangle fans, no normals (the loader computes smooth ones), MTL dielectric.
Faces wind counter-clockwise seen from outside; checked below.
"""
import math

def sub(a, b): return [a[i] - b[i] for i in range(3)]
def cross(a, b): return [a[1]*b[2]-a[2]*b[1], a[2]*b[0]-a[0]*b[2], a[0]*b[1]-a[1]*b[0]]
def dot(a, b): return sum(a[i]*b[i] for i in range(3))
def norm(a):
    l = math.sqrt(dot(a, a)); return [x / l for x in a]

def face_normal(verts, face):
    n = [0.0, 0.0, 0.0]
    for k in range(1, len(face) - 1):
        c = cross(sub(verts[face[k]], verts[face[0]]), sub(verts[face[k+1]], verts[face[0]]))
        n = [n[i] + c[i] for i in range(3)]
    return n

def signed_volume(verts, faces):
    v = 0.0
    for f in faces:
        for k in range(1, len(f) - 1):
            v += dot(verts[f[0]], cross(verts[f[k]], verts[f[k+1]])) / 6.0
    return v

def ring(n, r, y, phase=0.0):
    # x = cos, z = -sin: increasing angle turns counter-clockwise seen from +y.
    return [[r*math.cos(2*math.pi*(i+phase)/n), y, -r*math.sin(2*math.pi*(i+phase)/n)] for i in range(n)]

def gemstone(n=12):
    table = ring(n, 0.55, 0.42)
    girdle_top = ring(n, 1.0, 0.0)
    girdle_bot = ring(n, 1.0, -0.06)
    apex = [0.0, -0.9, 0.0]
    verts = table + girdle_top + girdle_bot + [apex]
    T, G, B, A = 0, n, 2*n, 3*n
    faces = [[T + i for i in range(n)]]  # the table: one n-gon
    for i in range(n):
        j = (i + 1) % n
        faces.append([T+i, G+i, G+j, T+j])      # crown
        faces.append([G+i, B+i, B+j, G+j])      # girdle
        faces.append([B+i, A, B+j])             # pavilion
    # Outward: every face normal points away from the centre (the gem is convex).
    for k, f in enumerate(faces):
        c = [sum(verts[v][i] for v in f) / len(f) for i in range(3)]
        if dot(face_normal(verts, f), sub(c, [0, 0, 0])) < 0:
            faces[k] = f[::-1]
    with open("gemstone.obj", "w") as out:
        out.write("# Brilliant-cut-like gemstone, %d-fold: table, crown, girdle, pavilion.\n" % n)
        out.write("# Flat facets: one normal per face. No MTL: the scene sets the material.\n")
        for v in verts:
            out.write("v %.6f %.6f %.6f\n" % tuple(v))
        for f in faces:
            out.write("vn %.6f %.6f %.6f\n" % tuple(norm(face_normal(verts, f))))
        for k, f in enumerate(faces):
            out.write("f " + " ".join("%d//%d" % (v + 1, k + 1) for v in f) + "\n")
    assert signed_volume(verts, faces) > 0

def goblet(n=48):
    # Profile (r, y) from the axis under the foot, out and up the outside,
    # over the rim and down the inside to the axis inside the bowl.
    profile = [(0.0, 0.0), (0.6, 0.0), (0.6, 0.04), (0.12, 0.12), (0.07, 0.3), (0.07, 0.65),
               (0.14, 0.78), (0.32, 0.9), (0.52, 1.1), (0.62, 1.4), (0.64, 1.7), (0.6, 2.0),
               (0.57, 2.0), (0.605, 1.7), (0.585, 1.4), (0.49, 1.12), (0.3, 0.95), (0.0, 0.9)]
    verts, index = [], {}
    for k, (r, y) in enumerate(profile):
        if r == 0.0:
            index[k] = [len(verts)] * n
            verts.append([0.0, y, 0.0])
        else:
            index[k] = list(range(len(verts), len(verts) + n))
            verts.extend(ring(n, r, y))
    faces = []
    for k in range(len(profile) - 1):
        a, b = index[k], index[k + 1]
        for i in range(n):
            j = (i + 1) % n
            quad = [a[i], a[j], b[j], b[i]]
            # Collapse the pole vertex of fans into triangles.
            dedup = [v for m, v in enumerate(quad) if v not in quad[:m]]
            faces.append(dedup)
    if signed_volume(verts, faces) < 0:
        faces = [f[::-1] for f in faces]
    assert signed_volume(verts, faces) > 0
    with open("glass.obj", "w") as out:
        out.write("# Goblet of revolution (%d segments), thick wall, closed surface.\n" % n)
        out.write("# No normals on purpose: the loader computes smooth, area-weighted ones.\n")
        out.write("mtllib glass.mtl\n")
        out.write("o goblet\n")
        for v in verts:
            out.write("v %.6f %.6f %.6f\n" % tuple(v))
        out.write("usemtl glass\n")
        for f in faces:
            out.write("f " + " ".join(str(v + 1) for v in f) + "\n")
    with open("glass.mtl", "w") as out:
        out.write("# Clear glass: illum 7 (refraction, Fresnel) with Ni the index of refraction.\n")
        out.write("newmtl glass\n")
        out.write("Kd 1.0 1.0 1.0\nKs 1.0 1.0 1.0\nNi 1.5\nd 0.1\nillum 7\n")

if __name__ == "__main__":
    gemstone()
    goblet()
