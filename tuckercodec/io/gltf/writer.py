"""A mesh sequence written as a glTF morph animation, which every glTF viewer plays.

The mesh is frame 0; frame t (t >= 1) is morph target t-1 holding ``frame t - frame 0``; a
``weights`` animation (LINEAR) has one keyframe per frame at its time in seconds
(:meth:`MeshSequence.seconds`), all weights 0 but target t-1's, which is 1. Between two
keyframes a viewer blends the two neighbouring frames linearly.

Precision: positions are float32. At its keyframe a viewer evaluating in float64 gets
``fl32(x_0) + fl32(x_t - fl32(x_0))``, which differs from ``x_t`` by at most one rounding of the
target, ``|x_t - fl32(x_0)| · 2^-24`` per coordinate (on top of rounding ``x_0`` to float32 for
frame 0): the round trip is exact to within that float32 rounding of base + target, not bit for
bit. Faces are triangles, in the sequence's face order: polygons are split into fans from their
first corner (a point sequence is written as POINTS). Frame rate, time codes and frame names
are kept in the asset's ``extras`` and read back by :func:`.reader.read_gltf`.

What the sequence carries beside positions:

* Attributes become vertex attributes (:mod:`.attribute_writing`: semantics, value types, the
  names recorded in the mesh's ``extras``). glTF has no corners: per-corner and per-face
  attributes split vertices (:mod:`.split`), one glTF vertex per vertex and combination of
  values, each with its vertex's positions in every frame; the file read back then has more
  vertices than the sequence (K' >= K), and the per-corner values at the corners of its faces.
* The normal written as NORMAL: frame 0 holds the stored normals; each frame's morph target
  holds, as its NORMAL offset, the normals recomputed from that frame's positions with the same
  hard edges (:mod:`.normals`) minus the stored ones, so a viewer lights every keyframe as its
  shape is (a second float32 array per frame: the file grows by about as much as the positions'
  targets take).
* Face sets of family ``materialBind`` become one primitive per material (a material of that
  name), in the order of their first faces, faces in no material one primitive without one;
  the faces read back are in that order (the sequence's own when each material's faces are
  consecutive). Other face sets and animated fields are not written
  (:func:`.attribute_writing.cannot_keep` lists what is lost).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from ...errors import InputError
from ...model.attributes import MATERIAL_FAMILY, VERTEX, Attribute
from ...model.sequence import MeshSequence, float32_seconds
from ...system.atomic import write_atomic
from .accessors import ARRAY_BUFFER, BufferBuilder
from .attribute_writing import semantics, stored_values
from .document import add_triangles, file_bytes, new_gltf
from .normals import recomputed_corner_normals
from .reader import EXTRAS_KEY
from .scene_attributes import RECORD_KEY
from .split import SplitLayout, split_vertices


def sequence_gltf_bytes(seq: MeshSequence, path: Path) -> bytes:
    """The bytes of the file (a .glb, or a .gltf when ``path`` says so)."""
    builder = BufferBuilder()
    layout = split_vertices(seq.faces, seq.vertex_count, seq.attributes)
    frames = seq.vertices[:, layout.vertex_of]
    base32 = _float32(frames[0], 0, path)
    attributes: dict[str, Any] = {
        "POSITION": builder.add_accessor(
            base32, target=ARRAY_BUFFER, bounds=True, vertex_attribute=True
        )
    }
    named = semantics(seq.attributes)
    for attribute in seq.attributes:
        values = stored_values(attribute, layout.expanded(attribute, seq.faces))
        attributes[named.by_name[attribute.name]] = builder.add_accessor(
            values, target=ARRAY_BUFFER, vertex_attribute=True
        )
    triangles, face_of = fan_triangles(layout.faces)
    primitives = []
    for material, picked in _material_groups(seq, face_of):
        primitive: dict[str, Any] = {"attributes": attributes}
        add_triangles(builder, primitive, triangles[picked], layout.count)
        if material is not None:
            primitive["material"] = material
        primitives.append(primitive)
    mesh: dict[str, Any] = {"name": "sequence", "primitives": primitives}
    if named.record:
        mesh["extras"] = {RECORD_KEY: {"attributes": named.record}}
    gltf = new_gltf()
    record: dict[str, Any] = {"frame_rate": seq.frame_rate, "frame_names": list(seq.frame_names)}
    if seq.time_codes is not None:
        record["time_codes"] = [float(code) for code in seq.time_codes]
    gltf["asset"]["extras"] = {EXTRAS_KEY: record}
    materials = [s.name for s in seq.face_sets if s.family == MATERIAL_FAMILY]
    if materials:
        gltf["materials"] = [{"name": name} for name in materials]
    node: dict[str, Any] = {"name": "sequence", "mesh": 0}
    if seq.frame_count > 1:
        targets = _morph_targets(builder, seq, layout, frames, base32, path)
        for primitive in primitives:
            primitive["targets"] = targets
        mesh["weights"] = [0.0] * (seq.frame_count - 1)
        mesh.setdefault("extras", {})["targetNames"] = list(seq.frame_names[1:])
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


def _morph_targets(
    builder: BufferBuilder,
    seq: MeshSequence,
    layout: SplitLayout,
    frames: np.ndarray,
    base32: np.ndarray,
    path: Path,
) -> list[dict[str, int]]:
    """Frame t's target (t >= 1): its POSITION offset from frame 0 and, where the sequence has
    a normal written as NORMAL, the offset of the normals recomputed from frame t's positions
    from the stored ones."""
    # the target as float32, from the float32 base: base + target then rounds only once
    deltas = _float32(frames[1:] - base32.astype(np.float64), 1, path)
    normal = _written_normal(seq)
    if normal is not None:
        stored = layout.expanded(normal, seq.faces).astype(np.float32).astype(np.float64)
        fallback = _vertex_fallback(normal, seq)
    targets = []
    for t, delta in enumerate(deltas, start=1):
        target = {
            "POSITION": builder.add_accessor(
                delta, target=ARRAY_BUFFER, bounds=True, vertex_attribute=True
            )
        }
        if normal is not None:
            per_corner = recomputed_corner_normals(seq.vertices[t], seq.faces, normal)
            fresh = layout.corner_expanded(per_corner, fallback)
            target["NORMAL"] = builder.add_accessor(
                (fresh - stored).astype(np.float32), target=ARRAY_BUFFER, vertex_attribute=True
            )
        targets.append(target)
    return targets


def _written_normal(seq: MeshSequence) -> Attribute | None:
    """The attribute written as NORMAL, if any."""
    named = semantics(seq.attributes).by_name
    for attribute in seq.attributes:
        if named[attribute.name] == "NORMAL":
            return attribute
    return None


def _vertex_fallback(normal: Attribute, seq: MeshSequence) -> np.ndarray:
    """A per-vertex normal for vertices no face uses: the authored one, else zeros (their
    target offsets are then zero too, as the corner-domain value of such a vertex is)."""
    if normal.domain == VERTEX:
        return normal.element_values().astype(np.float64)
    return np.zeros((seq.vertex_count, 3))


def _material_groups(seq: MeshSequence, face_of: np.ndarray) -> list[tuple[int | None, np.ndarray]]:
    """The primitives: (material index or None, the triangles it holds), one per material in
    the order of its first face; a face in several materials goes to the first."""
    material_of = np.full(seq.faces.shape[0], -1, dtype=np.int64)
    number = 0
    for face_set in seq.face_sets:
        if face_set.family != MATERIAL_FAMILY:
            continue
        free = face_set.faces[material_of[face_set.faces] < 0]
        material_of[free] = number
        number += 1
    per_triangle = material_of[face_of]
    order = list(dict.fromkeys(per_triangle.tolist()))
    if not order:
        order = [-1]  # no faces: one primitive of points
    return [(None if m < 0 else m, np.flatnonzero(per_triangle == m)) for m in order]


def fan_triangles(faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The faces (M, n) as triangles (T, 3) in face order, each polygon a fan from its first
    corner, and the face of each triangle (T,)."""
    faces = np.asarray(faces)
    if faces.shape[1] == 3:
        return faces.copy(), np.arange(faces.shape[0], dtype=np.int64)
    fans = np.stack([faces[:, [0, c, c + 1]] for c in range(1, faces.shape[1] - 1)], axis=1)
    face_of = np.repeat(np.arange(faces.shape[0]), fans.shape[1])
    fans = fans.reshape(-1, 3)
    real = fans[:, 2] >= 0
    return fans[real], face_of[real]


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
