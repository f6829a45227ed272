"""A mesh sequence written as a glTF morph animation, which every glTF viewer plays.

The mesh is frame 0; frame t (t >= 1) is morph target t-1 holding ``frame t - frame 0``; a
``weights`` animation (LINEAR) has one keyframe per frame at its time in seconds
(:meth:`MeshSequence.seconds`), all weights 0 but target t-1's, which is 1. Between two
keyframes a viewer blends the two neighbouring frames linearly.

Precision: positions are float32. At its keyframe a viewer evaluating in float64 gets
``fl32(x_0) + fl32(x_t - fl32(x_0))``, which differs from ``x_t`` by at most one rounding of the
target, ``|x_t - fl32(x_0)| · 2^-24`` per coordinate (on top of rounding ``x_0`` to float32 for
frame 0): the round trip is exact to within that float32 rounding of base + target, not bit for
bit. Faces are triangles: polygons are split into fans from their first corner (a point
sequence is written as POINTS). Frame rate, time codes and frame names are kept in the
asset's ``extras`` and read back by :func:`.reader.read_gltf`.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from ...errors import InputError
from ...model.sequence import MeshSequence, float32_seconds
from ...system.atomic import write_atomic
from .accessors import ARRAY_BUFFER, BufferBuilder
from .document import add_triangles, file_bytes, new_gltf
from .reader import EXTRAS_KEY


def sequence_gltf_bytes(seq: MeshSequence, path: Path) -> bytes:
    """The bytes of the file (a .glb, or a .gltf when ``path`` says so)."""
    builder = BufferBuilder()
    frames = seq.vertices
    base32 = _float32(frames[0], 0, path)
    primitive: dict[str, Any] = {
        "attributes": {
            "POSITION": builder.add_accessor(
                base32, target=ARRAY_BUFFER, bounds=True, vertex_attribute=True
            )
        },
    }
    add_triangles(builder, primitive, seq.triangles(), seq.vertex_count)
    mesh: dict[str, Any] = {"name": "sequence", "primitives": [primitive]}
    gltf = new_gltf()
    record: dict[str, Any] = {"frame_rate": seq.frame_rate, "frame_names": list(seq.frame_names)}
    if seq.time_codes is not None:
        record["time_codes"] = [float(code) for code in seq.time_codes]
    gltf["asset"]["extras"] = {EXTRAS_KEY: record}
    node: dict[str, Any] = {"name": "sequence", "mesh": 0}
    if seq.frame_count > 1:
        # the target as float32, from the float32 base: base + target then rounds only once
        deltas = _float32(frames[1:] - base32.astype(np.float64), 1, path)
        primitive["targets"] = [
            {
                "POSITION": builder.add_accessor(
                    delta, target=ARRAY_BUFFER, bounds=True, vertex_attribute=True
                )
            }
            for delta in deltas
        ]
        mesh["weights"] = [0.0] * (seq.frame_count - 1)
        mesh["extras"] = {"targetNames": list(seq.frame_names[1:])}
        weights = np.eye(seq.frame_count, seq.frame_count - 1, k=-1, dtype=np.float32)
        times = float32_seconds(seq, path)
        gltf["animations"] = [
            {
                "name": "frames",
                "samplers": [
                    {
                        "input": builder.add_accessor(times, bounds=True),
                        "output": builder.add_accessor(weights.reshape(-1)),
                        "interpolation": "LINEAR",
                    }
                ],
                "channels": [{"sampler": 0, "target": {"node": 0, "path": "weights"}}],
            }
        ]
    gltf.update({"scene": 0, "scenes": [{"nodes": [0]}], "nodes": [node], "meshes": [mesh]})
    return file_bytes(gltf, builder, path)


def _float32(values: np.ndarray, first_frame: int, path: Path) -> np.ndarray:
    """``values`` (a frame, or the targets of frames ``first_frame``...) as float32; a value
    float32 cannot hold is an InputError naming its frame, not an infinity that JSON's
    bounds and every viewer would refuse."""
    with np.errstate(over="ignore"):
        single = values.astype(np.float32)
    bad = ~np.isfinite(single)
    if bad.any():
        where = np.argwhere(bad)[0]
        frame = first_frame + (int(where[0]) if single.ndim == 3 else 0)
        raise InputError(
            f"vertex {int(where[-2])} is beyond the range of float32, which {path.name} stores "
            "(as a position or as its offset from frame 0)",
            frame=frame,
        )
    return single


def write_sequence_gltf(seq: MeshSequence, path: Path, overwrite: bool = False) -> None:
    """Write ``seq`` as a glTF morph animation at ``path`` (.glb or .gltf), atomically."""
    write_atomic(path, sequence_gltf_bytes(seq, path), overwrite=overwrite)
