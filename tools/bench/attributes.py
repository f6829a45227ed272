"""Attributes: what static attributes (§6.11) and the faces' given order (§6.10) cost, against
zstd-19 of the raw arrays and Draco's UV coding.

No shared sequence carries UVs, so each is given the attributes a textured character has, made
from its first frame: UVs projected on its two widest axes, float32, indexed per corner, with a
seam across the median of the widest axis (the corners of faces past it get rows of their own);
area-weighted vertex normals, float32; a material per face (seven runs of faces, as face sets).
For each:

* the ATTR section of the UVs, of the normals, and the FSET section, against zstd level 19 of
  the raw arrays (values as float32, indices and material numbers as int32): the issue's
  bound is 1.3x;
* the UVs in bits per corner beside Draco's (DracoPy, the same UVs on the mesh split at the
  seam, sequential encoding off, its default prediction), at 12 and 16 quantization bits: Draco
  quantizes (lossy) where tuckercodec keeps every bit;
* the ORDER section (the given face order) against the FACE section it restores, and FACE's
  faces-delta size, the other way to keep the order;
* the normals a writer recomputes from the decoded positions (every frame but the first, whose
  stored normals are written as they are) against the same normals of the original positions,
  as a DCC bakes them: the angle between them in degrees, over every frame and vertex, for the
  sequence encoded at the default KG error.

    python -m tools.bench attributes
    python -m tools.bench attributes ../shared/data/cloth-vellum.npz
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import zstandard

import tuckercodec
from tools import common
from tuckercodec import internal

DEFAULT_SEQUENCES = ("cloth-vellum.npz", "chicken.npz", "samba.npz")
DRACO_BITS = (12, 16)
MATERIALS = 7


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The attributes suite's options."""
    parser.add_argument(
        "sequences",
        nargs="*",
        help=f"the .npz sequences (default: {', '.join(DEFAULT_SEQUENCES)} of "
        f"{common.SHARED_DATA})",
    )


def zstd19(*arrays: np.ndarray) -> int:
    """Bytes of zstd level 19 on the arrays' raw bytes, back to back."""
    raw = b"".join(np.ascontiguousarray(a).tobytes() for a in arrays)
    return len(zstandard.ZstdCompressor(level=19).compress(raw))


def textured(points: np.ndarray, faces: np.ndarray) -> tuple[tuckercodec.Attribute, ...]:
    """The UVs (indexed per corner, a seam across the median) and the vertex normals."""
    axes = np.argsort(np.ptp(points, axis=0))[::-1][:2]
    flat = points[:, axes] - points[:, axes].min(axis=0)
    per_vertex = (flat / np.ptp(points[:, axes], axis=0).max()).astype(np.float32)
    corners = faces[faces >= 0]
    past = points[faces].mean(axis=1)[:, axes[0]] > np.median(points[:, axes[0]])
    keys = corners + np.repeat(past, faces.shape[1]) * len(points)
    rows, indices = np.unique(keys, return_inverse=True)
    uv = tuckercodec.Attribute("st", "corner", per_vertex[rows % len(points)], indices, "uv")
    area = np.cross(
        points[faces[:, 1]] - points[faces[:, 0]], points[faces[:, 2]] - points[faces[:, 0]]
    )
    summed = np.zeros_like(points)
    for corner in range(3):
        np.add.at(summed, faces[:, corner], area)
    length = np.linalg.norm(summed, axis=1, keepdims=True)
    normals = (summed / np.where(length > 0, length, 1.0)).astype(np.float32)
    return uv, tuckercodec.Attribute("N", "vertex", normals, None, "normal")


def draco_uv_bits(
    points: np.ndarray, faces: np.ndarray, uv: tuckercodec.Attribute, bits: int
) -> float | None:
    """Draco's bits per corner for the UVs (the file with them less the file without), or
    None without DracoPy."""
    try:
        import DracoPy
    except ImportError:
        return None
    assert uv.indices is not None
    first_use = np.unique(uv.indices, return_index=True)[1]
    corners = faces[faces >= 0]
    split = np.asarray(points[corners[first_use]], dtype=np.float32)  # a position per UV row
    triangles = uv.indices.reshape(-1, 3)
    with_uv = DracoPy.encode(
        split,
        triangles,
        tex_coord=uv.values.astype(np.float64),
        quantization_bits=14,
        tex_coord_quantization_bits=bits,
    )
    without = DracoPy.encode(split, triangles, quantization_bits=14)
    return 8.0 * (len(with_uv) - len(without)) / uv.indices.size


def measure(path: Path) -> list[str]:
    """The table's rows for one sequence."""
    with np.load(path, allow_pickle=False) as data:
        points, faces = np.asarray(data["V"][0], dtype=np.float64), data["F"].astype(np.int64)
    uv, normals = textured(points, faces)
    mesh = internal.attributes.Mesh(len(points), faces)
    rows = []
    assert uv.indices is not None
    for attribute, raw in (
        (uv, (uv.values, uv.indices.astype(np.int32))),
        (normals, (normals.values,)),
    ):
        _, payload = internal.attributes.encode_attribute(attribute, mesh, 19)
        per_corner = 8.0 * len(payload) / faces.size
        baseline = zstd19(*raw)
        rows.append(
            f"| {path.stem} | {attribute.name} ({attribute.domain}) | {len(payload):,} | "
            f"{baseline:,} | {len(payload) / baseline:.2f} | {per_corner:.2f} |"
        )
    material = np.arange(len(faces)) * MATERIALS // len(faces)
    sets = [
        tuckercodec.FaceSet(f"m{n}", np.flatnonzero(material == n), "materialBind")
        for n in range(MATERIALS)
    ]
    sequence = tuckercodec.MeshSequence(points[None], faces, face_sets=sets)
    report = tuckercodec.encode_with_report(sequence, target_kg=1.0).report
    fset = report.section_bytes.get("FSET", 0)
    rows.append(
        f"| {path.stem} | face sets ({MATERIALS} materials) | {fset:,} | "
        f"{zstd19(material.astype(np.int32)):,} | "
        f"{fset / zstd19(material.astype(np.int32)):.2f} | {8.0 * fset / faces.size:.2f} |"
    )
    draco = [draco_uv_bits(points, faces, uv, bits) for bits in DRACO_BITS]
    draco_text = ", ".join(
        f"{bits}-bit {value:.2f}" for bits, value in zip(DRACO_BITS, draco, strict=True) if value
    )
    order = report.section_bytes.get("ORDER", 0)
    _, delta_payload = internal.faces.encode_faces(faces, 19)
    rows.append(
        f"| {path.stem} | Draco UVs, bits per corner (lossy) | {draco_text or 'no DracoPy'} | | | |"
    )
    rows.append(
        f"| {path.stem} | ORDER (given face order) | {order:,} | "
        f"FACE {report.section_bytes['FACE']:,} | faces-delta {len(delta_payload):,} | "
        f"{8.0 * order / len(faces):.2f} per face |"
    )
    return rows


def normal_angles(path: Path) -> str:
    """The row of the normals' angle error after an encode at the default target."""
    with np.load(path, allow_pickle=False) as data:
        vertices, faces = np.asarray(data["V"], dtype=np.float64), data["F"].astype(np.int64)
    _, stored = textured(vertices[0], faces)
    decoded = tuckercodec.decode(tuckercodec.encode(tuckercodec.MeshSequence(vertices, faces)))
    angles = np.concatenate(
        [
            internal.normals.angle_error_degrees(
                internal.normals.recomputed_normals(original, faces, stored),
                internal.normals.recomputed_normals(approximate, faces, stored),
            )
            for original, approximate in zip(vertices, decoded.vertices, strict=True)
        ]
    )
    angles = angles[np.isfinite(angles)]
    median, high = np.percentile(angles, [50, 99]).tolist()
    worst = float(angles.max())
    return (
        f"| {path.stem} | normals recomputed after KG {internal.DEFAULT_TARGET_KG:g} | "
        f"median {median:.3f} deg | 99th percentile {high:.3f} deg | max {worst:.2f} deg | |"
    )


def run(args: argparse.Namespace) -> int:
    """Measure and print; the exit status."""
    paths = [Path(p) for p in args.sequences] or [
        common.SHARED_DATA / name for name in DEFAULT_SEQUENCES
    ]
    print(f"machine: {common.machine()}")
    print(f"command: {args.command}")
    print(
        "| sequence | what | tuckercodec bytes | zstd-19 of the raw arrays | ratio "
        "| bits per corner |"
    )
    print("|---|---|---|---|---|---|")
    for path in paths:
        if not path.exists():
            print(f"| {path.name} | absent | | | | |")
            continue
        for row in measure(path):
            print(row, flush=True)
        print(normal_angles(path), flush=True)
    return 0
