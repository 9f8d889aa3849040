#!/usr/bin/env python3
"""Writes assets/scenes/textures/pool_tiles.png, the floor texture of
assets/scenes/pool_tiles.toml: 8 x 8 square tiles in two blues with light
grout lines, 128 x 128 px (16 px per tile, 2 px grout), an 8-bit sRGB PNG.
Standard library only (zlib + struct), so it runs anywhere python3 does; the
output is deterministic, so rerunning it reproduces the committed file.

Usage: scripts/pool-tiles-texture.py [OUTPUT]
"""
import struct
import sys
import zlib

SIZE = 128
TILE = 16
GROUT = 2
# sRGB codes: grout off-white, tiles alternating two pool blues, each tile
# nudged by a fixed small offset so the floor does not look printed.
GROUT_RGB = (214, 218, 214)
BLUES = ((96, 170, 206), (70, 140, 186))
NUDGE = (0, 6, -5, 3, -3, 5, -6, 2)


def texel(x, y):
    if x % TILE < GROUT or y % TILE < GROUT:
        return GROUT_RGB
    tx, ty = x // TILE, y // TILE
    base = BLUES[(tx + ty) % 2]
    d = NUDGE[(3 * tx + 5 * ty) % len(NUDGE)]
    return tuple(max(0, min(255, c + d)) for c in base)


def png(width, height, pixel):
    rows = b"".join(
        b"\x00" + bytes(c for x in range(width) for c in pixel(x, y))
        for y in range(height)
    )

    def chunk(kind, data):
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body))

    header = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)  # 8-bit RGB
    # sRGB chunk (rendering intent 0): the codes are sRGB-encoded.
    return (
        b"\x89PNG\r\n\x1a\n"
        + chunk(b"IHDR", header)
        + chunk(b"sRGB", b"\x00")
        + chunk(b"IDAT", zlib.compress(rows, 9))
        + chunk(b"IEND", b"")
    )


if __name__ == "__main__":
    out = sys.argv[1] if len(sys.argv) > 1 else "assets/scenes/textures/pool_tiles.png"
    with open(out, "wb") as f:
        f.write(png(SIZE, SIZE, texel))
