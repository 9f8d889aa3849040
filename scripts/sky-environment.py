#!/usr/bin/env python3
"""Writes assets/scenes/environments/sky.hdr: a 256x128 equirectangular sky
(Radiance RGBE, flat scanlines) from the Preetham, Shirley & Smits analytic
daylight model ("A Practical Analytic Model for Daylight", SIGGRAPH 1999:
the Perez distribution, Eq. 3, with the turbidity fits of Appendix A.2 for
luminance Y and chromaticity x, y, and the zenith values of Eq. A.2-A.3),
plus a sun disc. Plain Python, no dependencies, nothing downloaded.

Units: Preetham's luminance is in kcd/m^2; it becomes radiance in
W m^-2 sr^-1 by the candela's 683 lm/W (the project's glTF convention), and
Yxy -> XYZ -> linear sRGB (D65). The sun is a disc of angular radius
SUN_RADIUS_DEG (3 degrees, enlarged from the real 0.27 so that the
256x128 table resolves it over a few texels), supersampled 8x8 per texel,
of radiance E / (2 pi (1 - cos alpha)) so that a surface facing it receives
SUN_IRRADIANCE. Below the horizon: a dim ground of 0.3 x the mean horizon
radiance. Image frame as docs/SCENES.md: u = phi / 2pi from +x toward +z,
v = theta / pi from +y, row 0 straight up.

Usage: scripts/sky-environment.py [OUT.hdr]
"""
import math
import struct
import sys

W, H = 256, 128
TURBIDITY = 3.0
SUN_ELEVATION_DEG = 25.0
SUN_PHI_DEG = 180.0  # the sun toward -x
SUN_RADIUS_DEG = 3.0
SUN_IRRADIANCE = (700.0, 650.0, 580.0)  # W/m^2 on a surface facing the sun
LUMENS_PER_WATT = 683.0


def perez(theta, gamma, a, b, c, d, e):
    return (1.0 + a * math.exp(b / max(math.cos(theta), 1e-3))) * (
        1.0 + c * math.exp(d * gamma) + e * math.cos(gamma) ** 2
    )


def coefficients(t):
    y = (0.1787 * t - 1.4630, -0.3554 * t + 0.4275, -0.0227 * t + 5.3251,
         0.1206 * t - 2.5771, -0.0670 * t + 0.3703)
    x = (-0.0193 * t - 0.2592, -0.0665 * t + 0.0008, -0.0004 * t + 0.2125,
         -0.0641 * t - 0.8989, -0.0033 * t + 0.0452)
    yc = (-0.0167 * t - 0.2608, -0.0950 * t + 0.0092, -0.0079 * t + 0.2102,
          -0.0441 * t - 1.6537, -0.0109 * t + 0.0529)
    return y, x, yc


def zenith(t, theta_s):
    chi = (4.0 / 9.0 - t / 120.0) * (math.pi - 2.0 * theta_s)
    y_z = (4.0453 * t - 4.9710) * math.tan(chi) - 0.2155 * t + 2.4192
    th = (theta_s ** 3, theta_s ** 2, theta_s, 1.0)
    tt = (t * t, t, 1.0)
    mx = ((0.00166, -0.00375, 0.00209, 0.0),
          (-0.02903, 0.06377, -0.03202, 0.00394),
          (0.11693, -0.21196, 0.06052, 0.25886))
    my = ((0.00275, -0.00610, 0.00317, 0.0),
          (-0.04214, 0.08970, -0.04153, 0.00516),
          (0.15346, -0.26756, 0.06670, 0.26688))
    x_z = sum(tt[i] * sum(mx[i][j] * th[j] for j in range(4)) for i in range(3))
    yc_z = sum(tt[i] * sum(my[i][j] * th[j] for j in range(4)) for i in range(3))
    return y_z, x_z, yc_z


def direction(u, v):
    theta, phi = math.pi * v, 2.0 * math.pi * u
    return (math.sin(theta) * math.cos(phi), math.cos(theta), math.sin(theta) * math.sin(phi))


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else "assets/scenes/environments/sky.hdr"
    theta_s = math.radians(90.0 - SUN_ELEVATION_DEG)
    sun = direction(math.radians(SUN_PHI_DEG) / (2 * math.pi), theta_s / math.pi)
    cy, cx, cyc = coefficients(TURBIDITY)
    y_z, x_z, yc_z = zenith(TURBIDITY, theta_s)
    norm = [perez(0.0, theta_s, *c) for c in (cy, cx, cyc)]

    def sky(d):
        theta = math.acos(max(-1.0, min(1.0, d[1])))
        gamma = math.acos(max(-1.0, min(1.0, sum(a * b for a, b in zip(d, sun)))))
        lum = y_z * perez(theta, gamma, *cy) / norm[0]
        x = x_z * perez(theta, gamma, *cx) / norm[1]
        y = yc_z * perez(theta, gamma, *cyc) / norm[2]
        big_y = lum * 1000.0 / LUMENS_PER_WATT
        big_x, big_z = x / y * big_y, (1.0 - x - y) / y * big_y
        r = 3.2406 * big_x - 1.5372 * big_y - 0.4986 * big_z
        g = -0.9689 * big_x + 1.8758 * big_y + 0.0415 * big_z
        b = 0.0557 * big_x - 0.2040 * big_y + 1.0570 * big_z
        return [max(r, 0.0), max(g, 0.0), max(b, 0.0)]

    cos_alpha = math.cos(math.radians(SUN_RADIUS_DEG))
    sun_l = [e / (2.0 * math.pi * (1.0 - cos_alpha)) for e in SUN_IRRADIANCE]
    horizon = [sky(direction((i + 0.5) / W, 0.4999)) for i in range(W)]
    ground = [0.3 * sum(h[c] for h in horizon) / W for c in range(3)]
    rows = []
    for j in range(H):
        row = []
        for i in range(W):
            d = direction((i + 0.5) / W, (j + 0.5) / H)
            l = sky(d) if d[1] > 0.0 else list(ground)
            # The sun disc, supersampled where it may touch the texel.
            near = sum(a * b for a, b in zip(d, sun)) > math.cos(math.radians(SUN_RADIUS_DEG + 2.0))
            if near:
                n, inside = 8, 0
                for a in range(n):
                    for b in range(n):
                        ds = direction((i + (a + 0.5) / n) / W, (j + (b + 0.5) / n) / H)
                        if sum(p * q for p, q in zip(ds, sun)) >= cos_alpha:
                            inside += 1
                # Texel area varies with sin(theta) inside it; fine at 1.4 degrees.
                l = [l[c] + sun_l[c] * inside / (n * n) for c in range(3)]
            row.append(l)
        rows.append(row)
    with open(out, "wb") as f:
        f.write(b"#?RADIANCE\n# Preetham 1999 sky, T = %.1f, sun elevation %.1f deg (scripts/sky-environment.py)\n"
                % (TURBIDITY, SUN_ELEVATION_DEG))
        f.write(b"FORMAT=32-bit_rle_rgbe\n\n-Y %d +X %d\n" % (H, W))
        for row in rows:
            for r, g, b in row:
                v = max(r, g, b)
                if v < 1e-32:
                    f.write(b"\0\0\0\0")
                    continue
                m, e = math.frexp(v)
                scale = m * 256.0 / v
                f.write(struct.pack("BBBB", int(r * scale), int(g * scale), int(b * scale), e + 128))
    print(f"wrote {out}: {W}x{H}, zenith {y_z * 1000 / LUMENS_PER_WATT:.2f} W m^-2 sr^-1 (luminance), sun L {sun_l[0]:.0f}")


if __name__ == "__main__":
    main()
