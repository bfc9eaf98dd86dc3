#!/usr/bin/env python3
"""Writes the hostile EXR files of tests/sh/test_hostile.sh into the directory given (default: the
current one): chunks that store fewer or more bytes than their pixels take, each a well-formed
header and offset table whose chunk sizes lie; and headers naming a compression or a line order
that OpenEXR does not define, over chunks stored raw. The same files are seeds of the EXR fuzz corpus
(tests/fuzz/exr)."""
import os
import struct
import sys
import zlib


def attribute(name, kind, data):
    return name.encode() + b'\0' + kind.encode() + b'\0' + struct.pack('<i', len(data)) + data


def header(width, height, pixel_type, compression, tile=None, line_order=0):
    """A single-part header: channels B, G, R of pixel_type (1 half, 2 float), not subsampled."""
    channels = b''.join(name + b'\0' + struct.pack('<iB3xii', pixel_type, 0, 1, 1)
                        for name in (b'B', b'G', b'R')) + b'\0'
    box = struct.pack('<4i', 0, 0, width - 1, height - 1)
    attrs = (attribute('channels', 'chlist', channels) +
             attribute('compression', 'compression', bytes([compression])) +
             attribute('dataWindow', 'box2i', box) + attribute('displayWindow', 'box2i', box) +
             attribute('lineOrder', 'lineOrder', bytes([line_order])) +
             attribute('pixelAspectRatio', 'float', struct.pack('<f', 1)) +
             attribute('screenWindowCenter', 'v2f', struct.pack('<2f', 0, 0)) +
             attribute('screenWindowWidth', 'float', struct.pack('<f', 1)))
    if tile:
        attrs += attribute('tiles', 'tiledesc', struct.pack('<IIB', tile[0], tile[1], 0))
    return b'\x76\x2f\x31\x01' + struct.pack('<I', 2 | (0x200 if tile else 0)) + attrs + b'\0'


def scanline_file(width, height, pixel_type, compression, chunks, line_order=0):
    """chunks: (first row, stored bytes) in file order."""
    head = header(width, height, pixel_type, compression, line_order=line_order)
    offset, table, body = len(head) + 8 * len(chunks), b'', b''
    for y, data in chunks:
        table += struct.pack('<Q', offset + len(body))
        body += struct.pack('<ii', y, len(data)) + data
    return head + table + body


def tiled_file(width, height, pixel_type, compression, tile, chunks):
    """chunks: ((tile column, tile row), stored bytes) of level 0 in file order."""
    head = header(width, height, pixel_type, compression, tile)
    offset, table, body = len(head) + 8 * len(chunks), b'', b''
    for (tx, ty), data in chunks:
        table += struct.pack('<Q', offset + len(body))
        body += struct.pack('<5i', tx, ty, 0, 0, len(data)) + data
    return head + table + body


HALF, FLOAT = 1, 2
NONE, ZIP = 0, 3
ROW = 8 * 3 * 4                       # one row of 8 float RGB pixels: 96 bytes
grey = struct.pack('<f', 0.5) * (ROW // 4)
FILES = {
    # 8x6 uncompressed rows storing 12 of their 96 bytes: decoding them read memory never written
    'exr_rows_short.exr': scanline_file(8, 6, FLOAT, NONE, [(y, grey[:12]) for y in range(6)]),
    # 8x6 uncompressed, the first row storing 200 bytes for its 96
    'exr_rows_long.exr': scanline_file(8, 6, FLOAT, NONE,
                                       [(y, grey + grey if y == 0 else grey) for y in range(6)]),
    # 16384x4096 half pixels in one uncompressed tile of 100 bytes (a 500-byte file, 805 MB read)
    'exr_tile_short.exr': tiled_file(16384, 4096, HALF, NONE, (16384, 4096), [((0, 0), b'\x3c' * 100)]),
    # 32x32 float in 16x16 tiles, all whole but the last, which stores 3000 of its 3072 bytes
    'exr_last_tile_short.exr': tiled_file(
        32, 32, FLOAT, NONE, (16, 16),
        [((tx, ty), (grey * 32)[:3000 if (tx, ty) == (1, 1) else 3072])
         for ty in range(2) for tx in range(2)]),
    # 8x6 ZIP (one block of 16 rows) storing more bytes than its 576 uncompressed, and none
    'exr_zip_long.exr': scanline_file(8, 6, FLOAT, ZIP, [(0, zlib.compress(grey * 6) + b'\0' * 600)]),
    'exr_zip_empty.exr': scanline_file(8, 6, FLOAT, ZIP, [(0, b'')]),
    # 8x6 rows stored raw under compressions 10 and 255 and line order 9, none of which OpenEXR
    # defines: its C library read the raw rows
    'exr_compression_10.exr': scanline_file(8, 6, FLOAT, 10, [(y, grey) for y in range(6)]),
    'exr_compression_255.exr': scanline_file(8, 6, FLOAT, 255, [(y, grey) for y in range(6)]),
    'exr_line_order_9.exr': scanline_file(8, 6, FLOAT, NONE, [(y, grey) for y in range(6)], line_order=9),
}

if __name__ == '__main__':
    out = sys.argv[1] if len(sys.argv) > 1 else '.'
    for name, data in FILES.items():
        with open(os.path.join(out, name), 'wb') as f:
            f.write(data)
