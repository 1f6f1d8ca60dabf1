#!/usr/bin/env python3
"""Whether two image files hold the same pixels: exit 0 if they do, 1 if not.

Used by bench/paired.sh and bench/whole_process.sh, whose binaries may encode the same pixels
into other bytes (another deflate level, another encoder). Files with the same bytes are the
same; otherwise:
- PNG (8-bit, not interlaced): the rows are inflated and unfiltered;
- OpenEXR (one part, scanlines, uncompressed or ZIP/ZIPS): each block's data is inflated, and a
  block stored raw is run through ZIP's byte split and predictor, so that both sides are
  compared in the one form whatever each encoder chose; the channel list and data window must
  match too. A bit-for-bit comparison of the floats, NaN payloads included.
Anything else is compared byte for byte.

    python3 bench/same_pixels.py A B
"""
import struct
import sys
import zlib


def png_pixels(data):
    at, idat = 8, b''
    while at < len(data):
        size, kind = struct.unpack('>I4s', data[at:at + 8])
        body = data[at + 8:at + 8 + size]
        if kind == b'IHDR':
            width, height, depth, colour, _, _, interlace = struct.unpack('>IIBBBBB', body[:13])
            if interlace:
                raise ValueError('interlaced PNG')
            channels = {0: 1, 2: 3, 4: 2, 6: 4}[colour]
        elif kind == b'IDAT':
            idat += body
        at += 12 + size
    raw, stride, rows = zlib.decompress(idat), width * channels * max(1, depth // 8), []
    step = channels * max(1, depth // 8)
    previous = bytearray(stride)
    for y in range(height):
        kind, line = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - step] if i >= step else 0
            b, c = previous[i], previous[i - step] if i >= step else 0
            if kind == 1: line[i] = (line[i] + a) & 255
            elif kind == 2: line[i] = (line[i] + b) & 255
            elif kind == 3: line[i] = (line[i] + (a + b) // 2) & 255
            elif kind == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        rows.append(bytes(line))
        previous = line
    return (width, height, depth, channels), rows


def zip_predicted(raw):
    """OpenEXR's ZIP predictor: even bytes, then odd ones, each then less the one before, + 128."""
    split = bytearray(raw[0::2] + raw[1::2])
    for i in range(len(split) - 1, 0, -1):
        split[i] = (split[i] - split[i - 1] + 128) & 255
    return bytes(split)


def exr_pixels(data):
    if data[:4] != b'\x76\x2f\x31\x01' or data[4] != 2 or data[5:8] != b'\0\0\0':
        raise ValueError('not a single-part scanline EXR')
    at, attributes = 8, {}
    while data[at] != 0:
        name_end = data.index(b'\0', at)
        type_end = data.index(b'\0', name_end + 1)
        size, = struct.unpack('<i', data[type_end + 1:type_end + 5])
        attributes[data[at:name_end]] = data[type_end + 5:type_end + 5 + size]
        at = type_end + 5 + size
    at += 1
    compression = attributes[b'compression'][0]
    x0, y0, x1, y1 = struct.unpack('<iiii', attributes[b'dataWindow'])
    width, height = x1 - x0 + 1, y1 - y0 + 1
    channels, chlist = [], attributes[b'channels']
    while chlist[0] != 0:
        name_end = chlist.index(b'\0')
        pixel_type, = struct.unpack('<i', chlist[name_end + 1:name_end + 5])
        channels.append((chlist[:name_end], pixel_type))
        chlist = chlist[name_end + 17:]
    if compression not in (0, 2, 3):
        raise ValueError(f'EXR compression {compression}')
    lines = {0: 1, 2: 1, 3: 16}[compression]
    pixel_bytes = sum(2 if pixel_type == 1 else 4 for _, pixel_type in channels)
    count = (height + lines - 1) // lines
    offsets = struct.unpack(f'<{count}Q', data[at:at + 8 * count])
    blocks = []
    for offset in offsets:
        y, size = struct.unpack('<ii', data[offset:offset + 8])
        body = data[offset + 8:offset + 8 + size]
        expected = min(lines, y1 + 1 - y) * width * pixel_bytes
        if compression == 0:
            blocks.append((y, body))
        else:
            blocks.append((y, zlib.decompress(body) if size < expected else zip_predicted(body)))
    return (width, height, x0, y0, tuple(channels)), sorted(blocks)


def pixels(path):
    data = open(path, 'rb').read()
    if data[:8] == b'\x89PNG\r\n\x1a\n':
        return png_pixels(data)
    if data[:4] == b'\x76\x2f\x31\x01':
        return exr_pixels(data)
    return data


def same(a, b):
    with open(a, 'rb') as first, open(b, 'rb') as second:
        if first.read() == second.read():
            return True
    return pixels(a) == pixels(b)


if __name__ == '__main__':
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    sys.exit(0 if same(sys.argv[1], sys.argv[2]) else 1)
