#!/usr/bin/env python3
"""Writes an equirectangular sky (Radiance .hdr, flat RGBE scanlines) for
timing frames whose environment goes through the SH product: a sky gradient
(horizon to zenith), a darker ground below the horizontal and a sun disc of
4 degrees, 40 degrees above the horizon. Standard library only, so that any
python3 runs it.

Usage: sky_hdr.py OUT.hdr
"""
import math
import sys

WIDTH, HEIGHT = 128, 64
ZENITH, HORIZON, GROUND = (0.25, 0.45, 0.9), (0.8, 0.85, 0.9), (0.25, 0.22, 0.18)
SUN_AZ, SUN_EL, SUN_RADIUS, SUN_RGB = 135.0, 40.0, 4.0, (40.0, 38.0, 34.0)


def radiance(elevation, azimuth):
    if elevation > 0.0:
        s = math.sin(elevation)
        rgb = [h + (z - h) * s for h, z in zip(HORIZON, ZENITH)]
    else:
        rgb = list(GROUND)
    sa, se = math.radians(SUN_AZ), math.radians(SUN_EL)
    sun = (math.cos(se) * math.cos(sa), math.cos(se) * math.sin(sa), math.sin(se))
    d = (math.cos(elevation) * math.cos(azimuth), math.cos(elevation) * math.sin(azimuth), math.sin(elevation))
    if sum(a * b for a, b in zip(d, sun)) > math.cos(math.radians(SUN_RADIUS)):
        rgb = [c + s for c, s in zip(rgb, SUN_RGB)]
    return rgb


def rgbe(rgb):
    m = max(rgb)
    if m < 1e-30:
        return bytes(4)
    mantissa, exponent = math.frexp(m)  # m = mantissa * 2^exponent, mantissa in [0.5, 1)
    scale = mantissa * 256.0 / m
    return bytes([min(255, int(c * scale)) for c in rgb] + [exponent + 128])


def main():
    if len(sys.argv) != 2:
        sys.exit("usage: sky_hdr.py OUT.hdr")
    rows = []
    for y in range(HEIGHT):
        elevation = (0.5 - (y + 0.5) / HEIGHT) * math.pi  # row 0 is the zenith's
        rows.append(b"".join(rgbe(radiance(elevation, (x + 0.5) / WIDTH * 2.0 * math.pi)) for x in range(WIDTH)))
    with open(sys.argv[1], "wb") as f:
        f.write(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y %d +X %d\n" % (HEIGHT, WIDTH))
        f.write(b"".join(rows))


if __name__ == "__main__":
    main()
