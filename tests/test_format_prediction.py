"""Prediction (spec/FORMAT.md §6.2): residuals along a forest of parents and their sums back,
on any forest and on a mesh whose breadth-first walk is 2**18 levels deep;
tuckercodec/format/prediction.py. (The parents of a mesh are tests/test_topology.py's.)"""

from __future__ import annotations

import time

import numpy as np
from conftest import IDENTITY_U2, deadline

from tuckercodec import Decoder
from tuckercodec.format.container import pack_container
from tuckercodec.format.faces import encode_faces
from tuckercodec.format.prediction import accumulate, residuals
from tuckercodec.format.streams import compress, pack_integers
from tuckercodec.topology import mesh_parents


def test_accumulate_inverts_residuals_on_any_forest():
    rng = np.random.default_rng(3)
    for count in (1, 2, 17, 500):
        # a random forest: parents anywhere (earlier or later), never a cycle
        order = rng.permutation(count)
        parents = np.full(count, -1)
        for position in range(1, count):
            if rng.random() < 0.9:
                parents[order[position]] = order[rng.integers(0, position)]
        values = rng.integers(-1000, 1000, size=(count, 4))
        np.testing.assert_array_equal(accumulate(residuals(values, parents), parents), values)
        np.testing.assert_array_equal(accumulate(residuals(values, None), None), values)
        # in place: the same sums, in the array given
        stored = residuals(values, parents)
        assert accumulate(stored, parents, in_place=True) is stored
        np.testing.assert_array_equal(stored, values)
    # a chain 100 000 deep takes about 17 passes, not 100 000 (pointer jumping: too many levels
    # for a loop over them); a chain 4000 deep is restored level by level
    for depth in (100_000, 4_000):
        chain = np.arange(-1, depth - 1)
        values = rng.integers(-5, 5, size=(depth, 2))
        np.testing.assert_array_equal(accumulate(residuals(values, chain), chain), values)
        stored = residuals(values, chain)
        accumulate(stored, chain, in_place=True)
        np.testing.assert_array_equal(stored, values)


def test_a_deep_strip_of_faces_decodes_quickly():
    """A valid 866-byte file whose 2**19 vertices form one strip: the breadth-first walk of
    §6.2 is 2**18 levels deep (one Python pass per level took 5 s; minutes at 2**26)."""
    count = 2**19
    row = np.arange(count - 2)
    faces = np.stack([row, row + 1, row + 2], 1)
    face_params, face_payload = encode_faces(faces)
    q = np.zeros((count, 1), np.int64)
    q[0] = 1
    payload, planes = pack_integers(
        np.ascontiguousarray(residuals(q, mesh_parents(faces, count)).T)
    )
    one = np.ones(1, "<f4").tobytes()
    sections = [
        ({"id": "FACE", "critical": True, "codec": "faces-delta", **face_params}, face_payload),
        (
            {
                "id": "U1",
                "critical": True,
                "codec": "qmat",
                "shape": [count, 1],
                "planes": planes,
                "steps": one,
                "predict": b"\x01",
            },
            payload,
        ),
        (
            {
                "id": "U3",
                "critical": True,
                "codec": "qmat",
                "shape": [1, 1],
                "planes": 1,
                "steps": one,
                "predict": b"\x00",
            },
            compress(b"\x02"),
        ),
        (
            {
                "id": "CORE",
                "critical": True,
                "codec": "qmat",
                "shape": [3, 1],
                "planes": 1,
                "steps": one,
                "predict": b"\x00",
            },
            compress(b"\x02\x00\x00"),
        ),
        (
            {
                "id": "CENT",
                "critical": True,
                "codec": "qmat",
                "shape": [1, 3],
                "planes": 1,
                "steps": np.ones(3, "<f4").tobytes(),
                "predict": b"\x00\x00\x00",
            },
            compress(b"\x00\x00\x00"),
        ),
    ]
    data = pack_container(
        {"vertices": count, "frames": 1, "ranks": [1, 1], "u2": IDENTITY_U2}, sections
    )
    started = time.perf_counter()
    with deadline(10.0):
        decoder = Decoder(data)
    assert time.perf_counter() - started < 2.0
    expected = np.zeros((count, 1))
    expected[0] = 1
    np.testing.assert_array_equal(decoder.u1, expected)  # every residual summed along the strip
    assert decoder.frame(0)[0].tolist() == [1.0, 0.0, 0.0]
