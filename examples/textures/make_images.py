#!/usr/bin/env python3
"""Writes the example texture images (no dependencies beyond the Python standard library).

globe.png  256x128 lat-long chart: hue follows the longitude (u), brightness falls towards the
           poles, white lines every 30 degrees; shows where (u, v) come from on a projected blob.
tiles.png  128x128, 4x4 pastel tiles with dark grout and a white corner mark at each tile's top
           left, so a tile's orientation is visible under tri-planar projection.

Run from anywhere: python3 examples/textures/make_images.py
"""
import colorsys
import os
import struct
import zlib


def write_png(path, width, height, pixel):
    rows = bytearray()
    for y in range(height):
        rows.append(0)  # filter: none
        for x in range(width):
            rows.extend(max(0, min(255, round(c * 255))) for c in pixel(x, y))

    def chunk(kind, data):
        return (struct.pack(">I", len(data)) + kind + data +
                struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF))

    png = (b"\x89PNG\r\n\x1a\n" +
           chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)) +
           chunk(b"IDAT", zlib.compress(bytes(rows), 9)) + chunk(b"IEND", b""))
    with open(path, "wb") as f:
        f.write(png)


def globe(x, y, w=256, h=128):
    u, v = (x + 0.5) / w, (y + 0.5) / h
    if x % (w // 12) == 0 or y % (h // 6) == 0:
        return (1.0, 1.0, 1.0)
    brightness = 0.45 + 0.5 * (1 - abs(2 * v - 1))
    return colorsys.hsv_to_rgb(u, 0.75, brightness)


def tiles(x, y, n=4, size=32):
    tx, ty, px, py = x // size, y // size, x % size, y % size
    if px < 2 or py < 2 or px >= size - 2 or py >= size - 2:
        return (0.12, 0.12, 0.14)
    if (5 <= px < 17 and 5 <= py < 9) or (5 <= px < 9 and 5 <= py < 17):
        return (1.0, 1.0, 1.0)
    hue = ((tx * 7 + ty * 11) % 16) / 16
    return colorsys.hsv_to_rgb(hue, 0.45, 0.9)


if __name__ == "__main__":
    here = os.path.dirname(os.path.abspath(__file__))
    write_png(os.path.join(here, "globe.png"), 256, 128, globe)
    write_png(os.path.join(here, "tiles.png"), 128, 128, tiles)
