#!/usr/bin/env python3
"""Writes scenes/textures/bricks.png: a 512x512 8-bit grey paving-brick texture that tiles.

Running bond, 8 bricks of 64x32 texels per course and 16 courses, 4-texel mortar joints; each
brick has its own tone, every texel a little periodic value noise and speckle, and brick edges
are slightly darkened. Everything is periodic in 512, so the image repeats without a seam: the
scenes repeat it tens of times across a floor, where a seam would show as a line through the
image. Python's standard library only; the output is the same on every run (fixed seed).

    usage: scripts/make-bricks.py [OUTPUT]   (default: scenes/textures/bricks.png)
"""

import argparse
import math
import os
import random
import struct
import zlib

SIZE = 512
BRICK_W, BRICK_H, MORTAR = 64, 32, 4


def value_noise(rng, period, cells):
    """Smoothly interpolated random lattice with `cells` cells per `period` texels, periodic."""
    lattice = [[rng.random() for _ in range(cells)] for _ in range(cells)]
    step = period / cells

    def at(x, y):
        fx, fy = x / step, y / step
        i, j = int(math.floor(fx)), int(math.floor(fy))
        tx, ty = fx - i, fy - j
        tx, ty = tx * tx * (3 - 2 * tx), ty * ty * (3 - 2 * ty)
        i0, j0, i1, j1 = i % cells, j % cells, (i + 1) % cells, (j + 1) % cells
        a = lattice[j0][i0] + (lattice[j0][i1] - lattice[j0][i0]) * tx
        b = lattice[j1][i0] + (lattice[j1][i1] - lattice[j1][i0]) * tx
        return a + (b - a) * ty

    return at


def bricks(size=SIZE, seed=1994):
    rng = random.Random(seed)
    courses, per_course = size // BRICK_H, size // BRICK_W
    tone = [[rng.uniform(0.34, 0.58) for _ in range(per_course)] for _ in range(courses)]
    coarse = value_noise(rng, size, 32)
    fine = value_noise(rng, size, 128)
    speck = [[rng.random() for _ in range(size)] for _ in range(size)]
    rows = []
    for y in range(size):
        course, yin = divmod(y, BRICK_H)
        shift = (BRICK_W // 2) * (course % 2)
        row = bytearray()
        for x in range(size):
            xs = (x + shift) % size
            brick, xin = divmod(xs, BRICK_W)
            grain = 0.5 * coarse(x, y) + 0.3 * fine(x, y) + 0.2 * speck[y][x] - 0.5
            if yin < MORTAR or xin < MORTAR:
                v = 0.80 + 0.10 * grain
            else:
                # Distance to the nearest mortar joint, for the darkened edges.
                edge = min(yin - MORTAR, BRICK_H - 1 - yin, xin - MORTAR, BRICK_W - 1 - xin)
                v = tone[course][brick] * (1 + 0.35 * grain) * (0.8 + 0.2 * min(edge, 2) / 2)
            row.append(max(0, min(255, round(255 * v))))
        rows.append(bytes(row))
    return rows


def write_png(path, rows):
    height, width = len(rows), len(rows[0])

    def chunk(kind, data):
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body))

    raw = b"".join(b"\x00" + r for r in rows)
    header = struct.pack(">IIBBBBB", width, height, 8, 0, 0, 0, 0)  # 8-bit grey, no interlace
    png = (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(raw, 9))
           + chunk(b"IEND", b""))
    tmp = path + ".tmp"
    with open(tmp, "wb") as f:
        f.write(png)
    os.replace(tmp, path)


if __name__ == "__main__":
    here = os.path.dirname(os.path.abspath(__file__))
    parser = argparse.ArgumentParser(
        description="Writes a 512x512 grey paving-brick texture that tiles (a PNG).")
    parser.add_argument("output", nargs="?",
                        default=os.path.join(here, "..", "scenes", "textures", "bricks.png"),
                        help="the PNG to write (default: scenes/textures/bricks.png)")
    write_png(parser.parse_args().output, bricks())
