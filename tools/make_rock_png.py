#!/usr/bin/env python3
"""Writes models/hfield_rock.png, the height map of the rock in models/hfield_rock.xml: a
rounded boulder (a squashed dome over an ellipse of half-axes 0.95 and 0.75 of the field's
half-sizes, zero outside it) with a few gentle bumps on it (a sum of sines, deterministic,
+-6 % of the elevation). 8-bit grey, 61 x 61 pixels, lowest pixel 0 and highest 255, so that
MuJoCo's grey 0..255 -> 0..elevation (the hfield's size[2]) is the whole scale.

Usage: python3 tools/make_rock_png.py [OUT.png]   (only python3 and zlib)
"""
import math
import sys

from make_seabed_png import png  # the same 8-bit grey PNG writer

N = 61


def height(i, j):
    """Height in [0, 1] at column i (along x) and image row j, before the final scaling."""
    x, y = 2 * i / (N - 1) - 1, 2 * j / (N - 1) - 1  # -1..1 across the field
    r2 = (x / 0.95) ** 2 + (y / 0.75) ** 2
    if r2 >= 1:
        return 0.0
    dome = (1 - r2) ** 0.7
    bumps = 0.06 * (math.sin(2 * math.pi * (1.5 * x + 0.1)) * math.cos(2 * math.pi * 1.2 * y)
                    + 0.5 * math.sin(2 * math.pi * (2.5 * x - 1.7 * y)))
    return max(0.0, dome * (1 + bumps))


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else "models/hfield_rock.png"
    h = [[height(i, j) for i in range(N)] for j in range(N)]
    top = max(max(r) for r in h)
    rows = [[round(255 * v / top) for v in r] for r in h]
    with open(out, "wb") as f:
        f.write(png(N, N, rows))


if __name__ == "__main__":
    main()
