"""Draco on each frame (DracoPy), quantization bits 8-16, compression level 10 (the smallest).

``draco-mesh`` encodes each frame as a mesh, so every frame carries the connectivity, plus one
permutation back to the input's vertex order (log2(K!) bits; see :func:`_run_draco`);
``draco-points`` encodes each frame as a point cloud with ``preserve_order`` and the faces once.
"""

from __future__ import annotations

import math

import numpy as np

from tools.bench.peers.base import (
    FRAME_LENGTH_BYTES,
    Context,
    Trial,
    faces_once,
    match_vertices,
    timed_trial,
)
from tuckercodec import MeshSequence


def _run_draco(sequence: MeshSequence, context: Context, *, with_faces: bool) -> list[Trial]:
    import DracoPy

    name = "draco-mesh" if with_faces else "draco-points"
    vertices = sequence.vertices.astype(np.float32)
    triangles = sequence.triangles().astype(np.uint32)
    if with_faces and not triangles.size:
        return []  # a point cloud has no mesh to encode; draco-points covers it
    # An animation cache binds vertices by index, so the input order must come back. A point
    # cloud keeps it with preserve_order; a mesh so encoded loses Draco's connectivity coding
    # (4-7 times larger on chicken), so the mesh keeps Draco's own order, which its traversal of
    # the fixed connectivity makes the same in every frame (up to vertices at equal positions,
    # which are interchangeable), and pays once for the permutation back: log2(K!) bits, the
    # least any coding of a permutation can take.
    permutation_bytes = (
        math.ceil(math.lgamma(sequence.vertex_count + 1) / math.log(2) / 8) if with_faces else 0
    )

    def trial_at(bits: int) -> Trial:
        def encode() -> tuple[int, int | None, list[bytes]]:
            buffers = [
                DracoPy.encode(
                    frame,
                    triangles if with_faces else None,
                    quantization_bits=bits,
                    compression_level=10,
                    preserve_order=not with_faces,
                )
                for frame in vertices
            ]
            total = (
                sum(len(b) for b in buffers) + FRAME_LENGTH_BYTES * len(buffers) + permutation_bytes
            )
            faces = None
            if not with_faces:
                faces = len(faces_once(sequence))
                total += faces
            return total, faces, buffers

        def decode_(buffers: list[bytes]) -> list[np.ndarray]:
            return [
                np.asarray(DracoPy.decode(buffer).points, dtype=np.float64) for buffer in buffers
            ]

        def in_input_order(frames: list[np.ndarray]) -> np.ndarray:
            if not with_faces:  # kept in order: nothing to match, and no reordering is allowed
                return np.stack(frames)
            return np.stack(
                [match_vertices(vertices[f], points, name) for f, points in enumerate(frames)]
            )

        return timed_trial(name, f"{bits} bits", encode, decode_, untimed=in_input_order)

    return [trial_at(bits) for bits in context.bits]


def run_draco_mesh(sequence: MeshSequence, targets: list[float], context: Context) -> list[Trial]:
    return _run_draco(sequence, context, with_faces=True)


def run_draco_points(sequence: MeshSequence, targets: list[float], context: Context) -> list[Trial]:
    return _run_draco(sequence, context, with_faces=False)
