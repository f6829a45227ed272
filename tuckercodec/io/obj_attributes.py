"""The OBJ statements beside positions and faces: texture coordinates (``vt``), normals
(``vn``), materials (``usemtl``) and groups (``g``), read into attributes and face sets.

:mod:`.obj` reads the ``v`` positions and the ``f`` faces (and its fast parsers skip every other
statement); this module reads the rest of a frame, and :func:`read_obj_frame` is the format's
frame reader that puts the two together:

* ``vt u [v [w]]`` lines make the table of a corner-domain attribute ``uv`` (role ``uv``,
  float64, rows as the file gives them, unused ones kept; ``v`` is 0 when absent, ``w`` is
  read past) whose index per corner is the ``f`` lines' texture index (``a/t``, ``a/t/n``);
* ``vn x y z`` lines likewise make ``normal`` (role ``normal``), indexed by ``a//n``, ``a/t/n``;
* ``usemtl name`` puts the faces below it, up to the next ``usemtl``, in the face set ``name``
  of family ``materialBind`` (the name is the rest of the line, its words joined by a space;
  a bare ``usemtl`` ends the material: the faces below have none);
* ``g a b`` puts the faces below it, up to the next ``g``, in the face sets ``a`` and ``b``
  of family ``group`` (a bare ``g``: in no group).

Face sets are listed materials first, then groups, each in the order of their first face;
a name no face follows makes no set. Texture and normal indices are 1-based, or negative to
count back from the last ``vt`` (``vn``) above the face's line, as OBJ says. A table that only
some corners index (objects with and without UVs in one file) has no value for the others'
corners, which an attribute cannot say: it is not read, and the positions and faces are, as
they always were. Without any face using them, ``vt`` and ``vn`` lines make no attribute.
``o``, ``s``, ``mtllib`` and the rest are not read.

Only the first frame of a sequence gives attributes and face sets (a sequence's static
attributes are frame 0's, normals included when they change). A later frame
whose ``f`` lines are its text for text the first frame's has the same indices; any other has
them parsed and compared, and an InputError names the first corner whose index differs.

These statements are read by the Python walk of :mod:`.obj`'s careful parser, after the
positions parser (the compiled core's, or the fast or careful Python one) has accepted the file,
so its errors come first. A file without them is screened out in a few byte searches
(:func:`may_have_attributes`), so that it is read as fast as before.
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..model.attributes import (
    CORNER,
    GROUP_FAMILY,
    MATERIAL_FAMILY,
    NORMAL,
    UV,
    Attribute,
    FaceSet,
    checked_name,
    face_corner_starts,
)
from .obj import _INTEGER, _MAX_INDEX_DIGITS, _number, _short, _statements, read_obj_frame_text
from .obj_attributes_fast import Found, read_extras_fast
from .registry import MeshFrame, ReadOptions

#: The names of the attributes made of ``vt`` and ``vn`` (OBJ names neither).
UV_NAME, NORMAL_NAME = "uv", "normal"

# A statement this module reads, at a line's start (after any indentation): only where the
# bytes screen of may_have_attributes lets the text through.
_STATEMENT = re.compile(rb"(?m)^[ \t\x0b\x0c]*(?:vt|vn|usemtl|g)(?![^ \t\x0b\x0c\n#\\])")
# Bytes one of those statements (or a corner's "/") needs: a file of plain v and f lines has
# none of them, and a search for a byte that is absent takes microseconds.
_SCREEN = (b"/", b"t", b"n", b"u", b"g")
# What each index of a corner refers to, for messages: (what, keyword).
_TEXTURE = ("texture coordinate", "vt")
_NORMAL = ("normal", "vn")


@dataclass(eq=False)
class ObjExtras:
    """What :func:`read_extras` finds: the attributes and face sets, and the line of every
    face (for errors about a corner)."""

    attributes: list[Attribute] = field(default_factory=list)
    face_sets: list[FaceSet] = field(default_factory=list)
    face_lines: list[int] = field(default_factory=list)


def read_obj_frame(
    path: str | os.PathLike[str],
    reference: MeshFrame | None = None,
    options: ReadOptions | None = None,
) -> MeshFrame:
    """One OBJ frame with its attributes and face sets: the format's frame reader
    (``options``: nothing in an OBJ file is compressed, so none applies).

    The first frame (no ``reference``) gets the attributes and face sets; a later one is
    checked against the first: vertex count and faces (:func:`.obj.read_obj_frame`), and the
    texture and normal indices of every corner.

    Raises:
        InputError: as :func:`.obj.read_obj_frame`; a bad ``vt``, ``vn``, ``usemtl`` or ``g``
            line or corner index (naming the file and line); a later frame whose corners index
            their ``vt`` or ``vn`` otherwise than the first frame's.
    """
    path = Path(path)
    frame, data = read_obj_frame_text(path, reference)
    if reference is None:
        if may_have_attributes(data):
            extras = read_extras(data, path, frame.faces)
            frame.attributes, frame.face_sets = extras.attributes, extras.face_sets
        return frame
    same_text = frame.face_text is not None and frame.face_text == reference.face_text
    if not same_text:
        extras = read_extras(data, path, frame.faces) if may_have_attributes(data) else ObjExtras()
        _check_same_indices(extras, frame.faces, reference, path)
    return frame


def may_have_attributes(data: bytes) -> bool:
    """Whether the text may hold a ``vt``, ``vn``, ``usemtl`` or ``g`` statement or a corner
    with more than a vertex index (never False when it does)."""
    if not any(byte in data for byte in _SCREEN):
        return False
    return b"/" in data or _STATEMENT.search(data) is not None


def read_extras(data: bytes, path: Path, faces: np.ndarray) -> ObjExtras:
    """The attributes and face sets of an OBJ text whose positions and ``faces`` (the
    position parser's table) are read; InputError naming the line of a bad statement."""
    found = read_extras_fast(data, faces)
    return _extras(found if found is not None else read_extras_careful(data, path, faces))


def read_extras_careful(data: bytes, path: Path, faces: np.ndarray) -> Found:
    """What :func:`read_extras` reads, line by line: the reference, and the one that names
    errors."""
    reader = _ExtrasReader(path)
    for number, tokens in _statements(data):
        reader.statement(number, tokens)
    return reader.finish(faces)


class _ExtrasReader:
    """The walk of :func:`read_extras`, one statement at a time."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.tables: dict[str, list[tuple[float, ...]]] = {"vt": [], "vn": []}
        self.indices: dict[str, list[int]] = {"vt": [], "vn": []}
        self.index_lines: dict[str, list[int]] = {"vt": [], "vn": []}
        # (has texture indices, has normal indices, line) of the first face
        self.first_face: tuple[bool, bool, int] | None = None
        self.face_lines: list[int] = []
        # the tables some corners index and others do not: left out (see _check_kind)
        self.partial: set[str] = set()
        self.material: str | None = None
        self.groups: tuple[str, ...] = ()
        self.materials: dict[str, list[int]] = {}
        self.group_faces: dict[str, list[int]] = {}

    def statement(self, number: int, tokens: list[bytes]) -> None:
        keyword = tokens[0]
        if keyword == b"vt":
            self.tables["vt"].append(self._texture(tokens[1:], number))
        elif keyword == b"vn":
            self.tables["vn"].append(self._normal(tokens[1:], number))
        elif keyword == b"f":
            self._face(tokens[1:], number)
        elif keyword == b"usemtl":
            words = [self._name(token, "a material", number) for token in tokens[1:]]
            self.material = self._name(" ".join(words), "a material", number) if words else None
        elif keyword == b"g":
            names = (self._name(token, "a group", number) for token in tokens[1:])
            self.groups = tuple(dict.fromkeys(names))

    def _texture(self, numbers: list[bytes], line: int) -> tuple[float, ...]:
        """u and v of a ``vt`` line (``vt u [v [w]]``, v 0 when absent)."""
        if not 1 <= len(numbers) <= 3:
            raise InputError(
                f"a 'vt' line needs u [v [w]], got {len(numbers)} value(s)",
                path=self.path,
                line=line,
            )
        values = [_number(token, self.path, line) for token in numbers[:2]]
        if not all(np.isfinite(values)):
            shown = " ".join(_short(token) for token in numbers[:2])
            raise InputError(f"non-finite texture coordinate: {shown}", path=self.path, line=line)
        return (values[0], values[1] if len(values) > 1 else 0.0)

    def _normal(self, numbers: list[bytes], line: int) -> tuple[float, ...]:
        """x y z of a ``vn`` line."""
        if len(numbers) != 3:
            raise InputError(
                f"a 'vn' line needs x y z, got {len(numbers)} value(s)", path=self.path, line=line
            )
        values = [_number(token, self.path, line) for token in numbers]
        if not all(np.isfinite(values)):
            shown = " ".join(_short(token) for token in numbers)
            raise InputError(f"non-finite normal: {shown}", path=self.path, line=line)
        return (values[0], values[1], values[2])

    def _face(self, corners: list[bytes], line: int) -> None:
        """The texture and normal index of each corner, and the face's sets."""
        face = len(self.face_lines)
        for corner in corners:
            parts = corner.split(b"/")
            if len(parts) > 3:
                raise InputError(
                    f"face corner {_short(corner)!r} has more than vertex/texture/normal",
                    path=self.path,
                    line=line,
                )
            texture = parts[1] if len(parts) > 1 else b""
            normal = parts[2] if len(parts) > 2 else b""
            self._check_kind(corner, bool(texture), bool(normal), line)
            for text, keyword, (what, _) in ((texture, "vt", _TEXTURE), (normal, "vn", _NORMAL)):
                if text:
                    so_far = len(self.tables[keyword])
                    self.indices[keyword].append(self._index(text, corner, so_far, what, line))
                    self.index_lines[keyword].append(line)
        self.face_lines.append(line)
        if self.material is not None:
            self.materials.setdefault(self.material, []).append(face)
        for group in self.groups:
            self.group_faces.setdefault(group, []).append(face)

    def _check_kind(self, corner: bytes, texture: bool, normal: bool, line: int) -> None:
        """Whether every corner of every face has what the first corner of the first face has:
        a table that some corners index and others do not (an exporter's objects with and
        without UVs in one file) cannot be a value per corner, so it is not read (the faces and
        positions are, as they always were)."""
        if self.first_face is None:
            self.first_face = (texture, normal, line)
            return
        first_texture, first_normal, _ = self.first_face
        for has, had, keyword in ((texture, first_texture, "vt"), (normal, first_normal, "vn")):
            if has != had:
                self.partial.add(keyword)

    def _index(self, text: bytes, corner: bytes, so_far: int, what: str, line: int) -> int:
        """A 0-based row of a corner's 1-based or negative (relative) index ``text``; a
        positive index is checked against the table once the file is read."""
        shown = _short(corner)
        digits = text.lstrip(b"+-").lstrip(b"0")
        if not _INTEGER.fullmatch(text) or len(digits) > _MAX_INDEX_DIGITS:
            raise InputError(
                f"face corner {shown!r} has no valid {what} index", path=self.path, line=line
            )
        value = int(digits or b"0") * (-1 if text.startswith(b"-") else 1)
        if value == 0:
            raise InputError(
                f"face corner {shown!r}: OBJ indices start at 1, 0 is invalid",
                path=self.path,
                line=line,
            )
        if value < 0:
            if -value > so_far:
                raise InputError(
                    f"face corner {shown!r} counts back past the first {what} "
                    f"(only {so_far} defined so far)",
                    path=self.path,
                    line=line,
                )
            return so_far + value
        return value - 1

    def _name(self, name: bytes | str, what: str, line: int) -> str:
        """A set's name, checked as every name is."""
        text = name if isinstance(name, str) else name.decode("utf-8", "replace")
        try:
            return checked_name(text, what)
        except InputError as error:
            raise InputError(error.reason, path=self.path, line=line) from None

    def finish(self, faces: np.ndarray) -> Found:
        """What the statements hold, once every one is read."""
        if len(self.face_lines) != len(faces):  # the position parser read other faces: a bug
            raise RuntimeError(f"{len(self.face_lines)} faces here, {len(faces)} read")
        found = Found({}, {}, self.materials, self.group_faces, self.face_lines)
        for keyword, width in (("vt", 2), ("vn", 3)):
            table = self.tables[keyword]
            found.tables[keyword] = np.array(table, dtype=np.float64).reshape(-1, width)
            indices = self.indices[keyword]
            found.indices[keyword] = np.array(indices, dtype=np.int64) if indices else None
            self._check_range(keyword, found.indices[keyword], len(table))
            if keyword in self.partial:
                found.indices[keyword] = None
        return found

    def _check_range(self, keyword: str, indices: np.ndarray | None, count: int) -> None:
        """Every index within the table of ``count`` rows."""
        if indices is None:
            return
        bad = np.flatnonzero(indices >= count)
        if bad.size:
            what = _TEXTURE[0] if keyword == "vt" else _NORMAL[0]
            raise InputError(
                f"face refers to {what} {int(indices[bad[0]]) + 1}, but the file has only "
                f"{count} '{keyword}' lines",
                path=self.path,
                line=self.index_lines[keyword][int(bad[0])],
            )


def _extras(found: Found) -> ObjExtras:
    """The attributes and face sets of what a reader found."""
    extras = ObjExtras(face_lines=found.face_lines)
    for keyword, name, role in (("vt", UV_NAME, UV), ("vn", NORMAL_NAME, NORMAL)):
        indices = found.indices[keyword]
        if indices is not None:
            extras.attributes.append(Attribute(name, CORNER, found.tables[keyword], indices, role))
    for family, sets in ((MATERIAL_FAMILY, found.materials), (GROUP_FAMILY, found.groups)):
        extras.face_sets.extend(
            FaceSet(name, np.array(members, dtype=np.int64), family)
            for name, members in sets.items()
        )
    return extras


def _check_same_indices(
    extras: ObjExtras, faces: np.ndarray, reference: MeshFrame, path: Path
) -> None:
    """A later frame's corners index ``vt`` and ``vn`` as the first frame's do."""
    first = f" ({reference.path})" if reference.path else ""
    ours = {a.role: a for a in extras.attributes}
    theirs = {a.role: a for a in reference.attributes}
    for role, (what, keyword) in ((UV, _TEXTURE), (NORMAL, _NORMAL)):
        mine, known = ours.get(role), theirs.get(role)
        if mine is None and known is None:
            continue
        if mine is None or known is None:
            has = "has none" if mine is None else "has them"
            raise InputError(
                f"its faces' {what} indices ({keyword}): this frame {has}, the first frame"
                f"{first} {'has them' if mine is None else 'has none'}: every frame of a "
                "sequence must index its vt and vn as the first",
                path=path,
            )
        assert mine.indices is not None and known.indices is not None  # both read here
        count = min(len(mine.indices), len(known.indices))
        different = np.flatnonzero(mine.indices[:count] != known.indices[:count])
        if different.size:
            corner = int(different[0])
            face = int(np.searchsorted(face_corner_starts(faces), corner, side="right")) - 1
            raise InputError(
                f"corner {corner + 1} (of face {face + 1}) uses {what} "
                f"{int(mine.indices[corner]) + 1} but in the first frame{first} it uses "
                f"{int(known.indices[corner]) + 1}: every frame of a sequence must index its "
                "vt and vn as the first",
                path=path,
                line=extras.face_lines[face],
            )
