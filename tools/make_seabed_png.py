#!/usr/bin/env python3
"""Writes models/seabed_hfield.png, the height map of models/seabed_hfield.xml: a seabed
sloping up along +x (a rise of 60 % of the elevation across the field) with rough ground on it
(a sum of a few sines, deterministic, +-15 % of the elevation). 8-bit grey, 65 x 65 pixels;
MuJoCo scales grey 0..255 to 0..elevation (the hfield's size[2]).

Usage: python3 tools/make_seabed_png.py [OUT.png]   (only python3 and zlib)
"""
import math
import struct
import sys
import zlib

N = 65


def height(i, j):
    """Height in [0, 1] at column i (along x) and image row j."""
    u, v = i / (N - 1), j / (N - 1)
    slope = 0.15 + 0.6 * u
    rough = 0.15 * (0.5 * math.sin(2 * math.pi * (3 * u + 0.2)) * math.cos(2 * math.pi * 2 * v)
                    + 0.3 * math.sin(2 * math.pi * (7 * u + 5 * v))
                    + 0.2 * math.cos(2 * math.pi * (11 * v - 4 * u)))
    return min(1.0, max(0.0, slope + rough))


def png(width, height_, rows):
    def chunk(kind, data):
        c = struct.pack(">I", len(data)) + kind + data
        return c + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)
    raw = b"".join(b"\x00" + bytes(r) for r in rows)  # filter 0 on every row
    return (b"\x89PNG\r\n\x1a\n"
            + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height_, 8, 0, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else "models/seabed_hfield.png"
    rows = [[round(255 * height(i, j)) for i in range(N)] for j in range(N)]
    with open(out, "wb") as f:
        f.write(png(N, N, rows))


if __name__ == "__main__":
    main()
