"""OBJ frames written with their attributes and face sets: the format's frame writer.

What a folder of OBJ frames keeps beside positions and faces (what :mod:`.obj_attributes`
reads back):

* the sequence's first ``uv`` attribute as the ``vt`` table and the ``f`` lines' texture
  indices, and its first ``normal`` attribute as ``vn`` and normal indices (``f a/t/n``,
  ``f a/t``, ``f a//n``). An indexed corner attribute is written as it is (its rows, unused ones
  too, and its indices), so that it reads back bit for bit in float64; an attribute of another
  domain (per vertex, per face, or per corner without indices) is written as a table and an
  index per corner, which reads back as a corner attribute with the same value at every corner.
  float32 values are written as the float64 text of the same number (``0.10000000149011612``),
  exact for a float64 reader and a float32 one alike;
* face sets of family ``materialBind`` as ``usemtl`` statements, each before a run of faces
  of that material in the sequence's face order (a face in two materials gets the first
  listed; a run of faces in none, after one in a material, gets a bare ``usemtl``);
* face sets of family ``group`` as ``g`` statements (a face in several groups: ``g a b``; a
  run in none after one in a group: a bare ``g``).

An animated sequence's normals: frame 0 gets the stored normals as they are (so that a folder
read back has the very same attribute), every later frame the normals of its own positions,
recomputed in the stored attribute's layout (:func:`~tuckercodec.model.normals.recomputed_normals`:
the same split into hard and smooth edges, the same ``f`` lines in every frame). A single
frame gets the stored normals.

What OBJ cannot keep (:func:`cannot_keep`, which the registry's format entry lists): animated
fields, attributes other than one UV set and one set of normals (colours included: the
``v x y z r g b`` extension is neither written nor read, its readers disagree on the range),
face sets of other families, names OBJ's whitespace-separated statements cannot hold, and
non-finite UVs or normals (which OBJ readers refuse). They are left out of the file.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from itertools import pairwise
from pathlib import Path

import numpy as np

from ..model.attributes import (
    CORNER,
    FACE,
    GROUP_FAMILY,
    MATERIAL_FAMILY,
    NORMAL,
    UV,
    VERTEX,
    Attribute,
    FaceSet,
    corner_faces,
    corner_vertices,
    face_corner_starts,
)
from ..model.normals import recomputed_normals
from ..model.sequence import MeshSequence
from ..system.atomic import write_atomic, write_staged
from . import obj
from .common.float_text import vertex_text
from .obj import _check_writable, _vertex_lines
from .registry import WriteOptions


@dataclass(eq=False)
class _Plan:
    """What a sequence's OBJ frames hold beside positions and faces, and what they drop."""

    uv: Attribute | None = None
    normal: Attribute | None = None
    materials: list[FaceSet] = field(default_factory=list)
    groups: list[FaceSet] = field(default_factory=list)
    dropped: list[str] = field(default_factory=list)

    @property
    def plain(self) -> bool:
        """Whether there is nothing to write beyond positions and faces."""
        return not (self.uv or self.normal or self.materials or self.groups)


def cannot_keep(seq: MeshSequence) -> list[str]:
    """What of ``seq`` a folder of OBJ frames leaves out, one item each (``field
    'velocity'``...): the registry's ``cannot_keep`` hook."""
    return _plan(seq).dropped


def obj_frame_writer(seq: MeshSequence, options: WriteOptions) -> Callable[[Path, int], None]:
    """The writer of ``seq``'s frames as OBJ files (the registry's ``write_frame``): what
    every frame shares (``vt`` lines, ``f`` lines with their ``usemtl`` and ``g``) is made
    once, here; the function returned writes frame ``index`` to ``path``."""
    plan = _plan(seq)
    if plan.plain:

        def write_plain(path: Path, index: int) -> None:
            obj.write_obj(  # looked up at call time: one place writes a frame's file
                path,
                seq.vertices[index],
                seq.faces,
                precision=options.precision,
                overwrite=options.overwrite,
                staged=options.staged,
            )

        return write_plain

    _check_writable(seq.vertices[0], seq.faces, options.precision)
    uv_text = b""
    uv_rows = normal_rows = None
    if plan.uv is not None:
        uv_table, uv_rows = _corner_rows(plan.uv, seq.faces)
        uv_text = _table_text("vt", uv_table, options.precision)
    if plan.normal is not None:
        normal_rows = _corner_rows(plan.normal, seq.faces)[1]
    body = _face_block(seq.faces, uv_rows, normal_rows, plan)

    def write(path: Path, index: int) -> None:
        vertices = seq.vertices[index]
        _check_writable(vertices, np.zeros((0, 3), dtype=np.int64), options.precision)
        chunks = [_table_text("v", vertices, options.precision), uv_text]
        if plan.normal is not None:
            normals = _frame_normals(seq, plan.normal, index)
            chunks.append(_table_text("vn", normals, options.precision))
        chunks.append(body)
        _write(path, chunks, options)

    return write


def _write(path: Path, chunks: list[bytes], options: WriteOptions) -> None:
    if options.staged:
        write_staged(path, chunks)
    else:
        write_atomic(path, lambda handle: handle.writelines(chunks), overwrite=options.overwrite)


def _plan(seq: MeshSequence) -> _Plan:
    """Which attributes and face sets the frames hold, and the items they drop."""
    plan = _Plan()
    plan.dropped.extend(f"field {item.name!r}" for item in seq.fields)
    for attribute in seq.attributes:
        slot = {UV: "uv", NORMAL: "normal"}.get(attribute.role)
        if slot is None:
            plan.dropped.append(f"{attribute.role} attribute {attribute.name!r}")
        elif getattr(plan, slot) is not None:
            plan.dropped.append(f"a second {attribute.role} attribute, {attribute.name!r}")
        elif not np.isfinite(attribute.values).all():
            plan.dropped.append(
                f"{attribute.role} attribute {attribute.name!r} (non-finite values)"
            )
        else:
            setattr(plan, slot, attribute)
    for face_set in seq.face_sets:
        label = f"face set {face_set.name!r} of family {face_set.family!r}"
        if face_set.family not in (MATERIAL_FAMILY, GROUP_FAMILY):
            plan.dropped.append(label)
        elif not _writable_name(face_set.name, face_set.family == MATERIAL_FAMILY):
            plan.dropped.append(f"{label} (a name OBJ cannot write)")
        elif face_set.faces.size == 0:
            plan.dropped.append(f"{label} (no faces)")
        elif face_set.family == MATERIAL_FAMILY:
            plan.materials.append(face_set)
        else:
            plan.groups.append(face_set)
    _note_overlapping_materials(plan, int(seq.faces.shape[0]))
    return plan


def _writable_name(name: str, words: bool) -> bool:
    """Whether a name reads back the same from ``usemtl name`` (``words``: several words
    joined by single spaces are) or from ``g name``."""
    if "#" in name or name.endswith("\\"):
        return False
    split = name.encode("utf-8").split()
    return b" ".join(split) == name.encode("utf-8") if words else len(split) == 1


def _note_overlapping_materials(plan: _Plan, face_count: int) -> None:
    """A face has one material in OBJ: note the sets whose faces an earlier set takes."""
    taken = np.zeros(face_count, dtype=bool)
    for face_set in plan.materials:
        if taken[face_set.faces].any():
            plan.dropped.append(
                f"material {face_set.name!r} on faces also in an earlier material (they keep "
                "that one)"
            )
        taken[face_set.faces] = True


def _corner_rows(attribute: Attribute, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(table, row of every corner): an attribute of any domain as OBJ's indexed corners."""
    if attribute.domain == CORNER:
        elements = np.arange(int((faces >= 0).sum()), dtype=np.int64)
    elif attribute.domain == VERTEX:
        elements = corner_vertices(faces)
    else:
        assert attribute.domain == FACE
        elements = corner_faces(faces)
    rows = elements if attribute.indices is None else attribute.indices[elements]
    return attribute.values, rows


def _frame_normals(seq: MeshSequence, normal: Attribute, index: int) -> np.ndarray:
    """The normal table of frame ``index``: the stored one for frame 0 (and a single frame),
    recomputed from the frame's positions for the others."""
    if index == 0 or seq.frame_count == 1:
        return normal.values
    return recomputed_normals(seq.vertices[index], seq.faces, normal)


def _table_text(keyword: str, table: np.ndarray, precision: int | None) -> bytes:
    """``keyword x y [z]`` lines of a table, every number the text of its float64 value
    (exact, ``repr``) or ``precision`` significant digits."""
    values = np.asarray(table, dtype=np.float64)
    if len(values) == 0:
        return b""
    if values.shape[1] == 3:
        if precision is None:
            text = vertex_text(values)  # "v x y z" lines
        else:
            text = "".join(line + "\n" for line in _vertex_lines(values, precision)).encode()
        if keyword == "v":
            return text
        name = keyword.encode()
        return name + text[1:].replace(b"\nv ", b"\n" + name + b" ")
    form = repr if precision is None else f"%.{precision}g".__mod__
    numbers = list(map(form, values.reshape(-1).tolist()))
    each = iter(numbers)
    columns = [each] * values.shape[1]
    return "".join(f"{keyword} {' '.join(row)}\n" for row in zip(*columns, strict=True)).encode()


def _face_block(
    faces: np.ndarray, uv_rows: np.ndarray | None, normal_rows: np.ndarray | None, plan: _Plan
) -> bytes:
    """The ``f`` lines with their corners' indices, and ``usemtl`` and ``g`` statements where
    a run of faces of other sets starts."""
    vertices = (corner_vertices(faces) + 1).tolist()
    textures = None if uv_rows is None else (uv_rows + 1).tolist()
    normals = None if normal_rows is None else (normal_rows + 1).tolist()
    if textures is not None and normals is not None:
        corners = list(map("%d/%d/%d".__mod__, zip(vertices, textures, normals, strict=True)))
    elif textures is not None:
        corners = list(map("%d/%d".__mod__, zip(vertices, textures, strict=True)))
    elif normals is not None:
        corners = list(map("%d//%d".__mod__, zip(vertices, normals, strict=True)))
    else:
        corners = list(map(str, vertices))
    starts = face_corner_starts(faces).tolist()
    lines = ["f " + " ".join(corners[start:stop]) for start, stop in pairwise(starts)]
    statements = _set_statements(len(lines), plan)
    text = []
    for face, line in enumerate(lines):
        if face in statements:
            text.extend(statements[face])
        text.append(line)
    return ("\n".join(text) + "\n").encode("utf-8") if text else b""


def _set_statements(face_count: int, plan: _Plan) -> dict[int, list[str]]:
    """The ``usemtl`` and ``g`` statements to write before each face that starts a run."""
    material = np.full(face_count, -1, dtype=np.int64)
    for number, face_set in reversed(list(enumerate(plan.materials))):
        material[face_set.faces] = number  # the first listed wins: written last
    groups: list[list[int]] = [[] for _ in range(face_count)]
    for number, face_set in enumerate(plan.groups):
        for face in face_set.faces.tolist():
            groups[face].append(number)
    statements: dict[int, list[str]] = {}
    previous_material, previous_groups = -1, list[int]()
    for face in range(face_count):
        here: list[str] = []
        if groups[face] != previous_groups:
            names = " ".join(plan.groups[number].name for number in groups[face])
            here.append(f"g {names}".rstrip())
            previous_groups = groups[face]
        if material[face] != previous_material:
            name = plan.materials[material[face]].name if material[face] >= 0 else ""
            here.append(f"usemtl {name}".rstrip())
            previous_material = int(material[face])
        if here:
            statements[face] = here
    return statements
