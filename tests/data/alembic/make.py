"""Writes tests/data/alembic/polygons-last-sample-cut.abc (README.md says what it is and why).
Needs alembic3d (``pip install 'tuckercodec[alembic]'``); run from anywhere:

    python tests/data/alembic/make.py

The archive holds the date it was written and tuckercodec's version, so each run writes other
bytes; the damage is found by walking the file's Ogawa groups, not at a fixed offset.
"""

from __future__ import annotations

import struct
import tempfile
from pathlib import Path

import numpy as np

from tuckercodec import MeshSequence, save_sequence

HERE = Path(__file__).parent
DATA = 1 << 63  # an Ogawa child whose offset has this bit set is data, not a group


def polygons() -> MeshSequence:
    """7 vertices, 2 quads and 2 triangles, 5 frames at uneven times (test_io_alembic's)."""
    faces = np.array([[0, 1, 2, 3], [1, 4, 2, -1], [4, 5, 6, 2], [6, 3, 2, -1]])
    codes = np.array([-2.0, 0.5, 1.0, 7.25, 100.0])
    vertices = np.random.default_rng(2).standard_normal((len(codes), 7, 3))
    return MeshSequence(vertices, faces, frame_rate=30000 / 1001, time_codes=codes)


def groups(data: bytes) -> list[tuple[int, tuple[int, ...]]]:
    """Every Ogawa group of the archive: (its offset, its children's offsets)."""
    found, pending = [], [struct.unpack_from("<Q", data, 8)[0]]  # the root, after the header
    while pending:
        offset = pending.pop()
        (count,) = struct.unpack_from("<Q", data, offset)
        children = struct.unpack_from(f"<{count}Q", data, offset + 8)
        found.append((offset, children))
        pending += [child for child in children if child and not child & DATA]
    return found


def size(data: bytes | bytearray, child: int) -> int:
    """The size of a data child (0 for the empty one)."""
    offset = child & ~DATA
    return struct.unpack_from("<Q", data, offset)[0] if offset else 0


def main() -> None:
    with tempfile.TemporaryDirectory() as scratch:
        path = Path(scratch) / "polygons.abc"
        save_sequence(polygons(), path)
        data = bytearray(path.read_bytes())
    # the positions: 5 samples, each a 100-byte data child (a 16-byte key and 7 x 3 float32)
    # and an empty one (its dimensions)
    [offset] = [
        offset
        for offset, children in groups(bytes(data))
        if len(children) == 10 and [size(data, c) for c in children[::2]] == [100] * 5
    ]
    struct.pack_into("<Q", data, offset, 9)  # the last sample's dimensions cut off
    (HERE / "polygons-last-sample-cut.abc").write_bytes(bytes(data))
    print(f"the child count at byte {offset}: 10 -> 9")


if __name__ == "__main__":
    main()
