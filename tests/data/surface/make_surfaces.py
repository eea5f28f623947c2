#!/usr/bin/env python3
"""Writes the small height maps of tests/test_surface.c (this project's; run from this
folder: python3 make_surfaces.py). PNGs are written by hand (zlib, CRC32) to try each
colour type libpng converts: grey (2 and 8 bits), 16-bit RGB, a palette, RGBA interlaced."""
import struct, zlib

def chunk(kind, data):
    c = kind + data
    return struct.pack('>I', len(data)) + c + struct.pack('>I', zlib.crc32(c) & 0xffffffff)

def png(path, width, height, depth, colour, rows, palette=None, interlace=0, trns=None):
    """rows: lists of samples per row (already packed for depths below 8 by the caller
    as bytes)."""
    raw = b''.join(b'\x00' + r for r in rows)
    out = b'\x89PNG\r\n\x1a\n' + chunk(b'IHDR', struct.pack('>IIBBBBB', width, height, depth, colour, 0, 0, interlace))
    if palette: out += chunk(b'PLTE', bytes(v for rgb in palette for v in rgb))
    if trns: out += chunk(b'tRNS', trns)
    out += chunk(b'IDAT', zlib.compress(raw)) + chunk(b'IEND', b'')
    open(path, 'wb').write(out)

# grey, 8 bits, 4 x 3: a ramp
png('grey8.png', 4, 3, 8, 0, [bytes([0, 50, 100, 150]), bytes([200, 250, 255, 10]), bytes([30, 60, 90, 120])])
# grey, 2 bits, 5 x 2 (levels 0, 85, 170, 255)
def pack2(vals):
    vals = vals + [0] * (-len(vals) % 4)
    return bytes((vals[i] << 6) | (vals[i+1] << 4) | (vals[i+2] << 2) | vals[i+3] for i in range(0, len(vals), 4))
png('grey2.png', 5, 2, 2, 0, [pack2([0, 1, 2, 3, 1]), pack2([3, 3, 0, 2, 1])])
# RGB, 16 bits, 3 x 2: only the high bytes count
def rgb16(px): return b''.join(struct.pack('>HHH', *p) for p in px)
png('rgb16.png', 3, 2, 16, 2, [rgb16([(0xffff, 0, 0), (0, 0xff80, 0), (0, 0, 0x80ff)]),
                               rgb16([(0x1234, 0x5678, 0x9abc), (0xffff, 0xffff, 0xffff), (0x00ff, 0x00ff, 0x00ff)])])
# a palette of four colours, 8-bit indices, with a tRNS chunk (ignored), 3 x 3
png('palette.png', 3, 3, 8, 3, [bytes([0, 1, 2]), bytes([3, 2, 1]), bytes([1, 1, 0])],
    palette=[(255, 0, 0), (0, 255, 0), (0, 0, 255), (128, 128, 128)], trns=bytes([0, 128]))
# RGBA, 8 bits, Adam7 interlaced, 9 x 9 (the alpha is ignored)
W = H = 9
pix = [[((x * 29) % 256, (y * 31) % 256, ((x + y) * 17) % 256, (x * y * 7) % 256) for x in range(W)] for y in range(H)]
passes = [(0, 0, 8, 8), (4, 0, 8, 8), (0, 4, 4, 8), (2, 0, 4, 4), (0, 2, 2, 4), (1, 0, 2, 2), (0, 1, 1, 2)]
raw = b''
for x0, y0, dx, dy in passes:
    xs = list(range(x0, W, dx)); ys = list(range(y0, H, dy))
    if not xs or not ys: continue
    for y in ys:
        raw += b'\x00' + bytes(v for x in xs for v in pix[y][x])
out = b'\x89PNG\r\n\x1a\n' + chunk(b'IHDR', struct.pack('>IIBBBBB', W, H, 8, 6, 0, 0, 1))
out += chunk(b'IDAT', zlib.compress(raw)) + chunk(b'IEND', b'')
open('rgba-interlaced.png', 'wb').write(out)
