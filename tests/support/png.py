"""Reading a PNG into a numpy array with zlib alone (no imaging library is a dependency): the
8-bit, non-interlaced greyscale, RGB and RGBA images Chromium's screenshots are
(tests/support/browser.py), for the tests and tools that look at what a page drew."""

from __future__ import annotations

import struct
import zlib

import numpy as np


def decode_png(data: bytes) -> np.ndarray:
    """An 8-bit, non-interlaced greyscale, grey-and-alpha, RGB or RGBA PNG as a (height,
    width, channels) uint8 array.

    Raises:
        ValueError: not a PNG, or a kind this reader does not handle (palette, 16 bits,
            interlaced).
    """
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        raise ValueError("not a PNG")
    chunks: dict[bytes, bytes] = {}
    compressed = bytearray()
    position = 8
    while position + 8 <= len(data):
        length, kind = struct.unpack(">I4s", data[position : position + 8])
        body = data[position + 8 : position + 8 + length]
        if kind == b"IDAT":
            compressed += body
        else:
            chunks.setdefault(kind, body)
        position += 12 + length
    if b"IHDR" not in chunks:
        raise ValueError("a PNG without its IHDR chunk")
    width, height, depth, colour, _, _, interlace = struct.unpack(">IIBBBBB", chunks[b"IHDR"])
    channels = {0: 1, 2: 3, 4: 2, 6: 4}.get(colour)
    if depth != 8 or channels is None or interlace:
        raise ValueError(f"unsupported PNG: depth {depth}, colour type {colour}, {interlace=}")
    raw = np.frombuffer(zlib.decompress(bytes(compressed)), np.uint8)
    rows = raw.reshape(height, 1 + width * channels)
    image = np.zeros((height, width * channels), np.uint8)
    previous = np.zeros(width * channels, np.uint8)
    for y in range(height):
        image[y] = previous = _unfilter(int(rows[y, 0]), rows[y, 1:], previous, channels)
    result: np.ndarray = image.reshape(height, width, channels)
    return result


def _unfilter(kind: int, line: np.ndarray, above: np.ndarray, step: int) -> np.ndarray:
    if kind == 0:
        return line
    if kind == 2:
        return line + above  # uint8 arithmetic wraps, as PNG's does
    if kind == 1:  # Sub: a running sum along each channel
        sums = np.cumsum(line.reshape(-1, step).astype(np.int64), axis=0)
        return (sums % 256).astype(np.uint8).reshape(-1)
    # Average and Paeth depend on the byte just decoded: byte by byte
    out = bytearray(line.tobytes())
    up = above.tobytes()
    for i in range(len(out)):
        left = out[i - step] if i >= step else 0
        if kind == 3:
            out[i] = (out[i] + ((left + up[i]) >> 1)) & 255
        elif kind == 4:
            corner = up[i - step] if i >= step else 0
            p = left + up[i] - corner
            pa, pb, pc = abs(p - left), abs(p - up[i]), abs(p - corner)
            guess = left if pa <= pb and pa <= pc else up[i] if pb <= pc else corner
            out[i] = (out[i] + guess) & 255
        else:
            raise ValueError(f"unknown PNG filter {kind}")
    result: np.ndarray = np.frombuffer(bytes(out), np.uint8)
    return result
