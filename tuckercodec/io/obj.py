"""Reading and writing Wavefront OBJ meshes, fast and exactly.

(At about 700 lines this module is longer than the others on purpose: OBJ's two parsers share
one set of rules and must agree on every input, so they stay side by side with those rules.)

This module reads the ``v`` positions, in file order, and the ``f`` faces. Everything else
(``vt``, ``vn``, ``vp``, ``o``, ``g``, ``s``, ``usemtl``, ``mtllib``, ``l``, comments, unknown
statements) is ignored here: :mod:`.obj_attributes` reads ``vt``, ``vn``, ``usemtl`` and ``g``
into attributes and face sets (the format's frame reader), and :mod:`.obj_attribute_writer`
writes them. trimesh is never used for OBJ because it reorders and merges vertices, which would
break the vertex correspondence between frames.

What the two lines that matter may hold:

* ``v x y z``, optionally followed by a weight ``w`` (4 numbers, which OBJ allows) or an RGB or
  RGBA vertex colour (6 or 7 numbers, which some exporters append). x y z are kept; the rest is
  read past: it must be numbers, but need not be finite since it is never used. Any other count,
  a token that is not a decimal number, and a NaN or infinite x, y or z are errors.
* ``f`` and three or more corners ``a``, ``a/t``, ``a//n`` or ``a/t/n``, of which only the vertex
  index ``a`` is used: 1-based, or negative to count back from the last vertex defined above the
  face's line (``-1`` is that vertex), as OBJ says. A positive index may name a vertex defined
  further down; all are checked against the file's vertex count. Zero, an index out of range
  and a face of fewer than three corners are errors. Faces of mixed sizes are padded with -1
  to the widest, within a limit on the padded table's size.

A line ending in a backslash continues on the next one (the statement keeps its first line's
number).

Two parsers share one set of rules:

* :func:`_parse_fast` handles the common, tidy file with a few whole-file operations (numpy finds
  the line starts, ``bytes.split`` cuts all numbers at once). It never reports errors: as soon as
  anything is unusual it gives up and returns ``None``.
* :func:`_parse_careful` walks the file line by line. It is the reference: it reads everything
  the fast parser reads, to the same result, and more (indented lines, trailing comments, line
  continuations...), and it is the one that reports errors, with the 1-based line number.

The fast parser gives up on every input the careful one might read differently, so the two always
agree; the tests check this, also on random input.

Where the compiled core is installed (:mod:`tuckercodec.system.native`), it runs instead of the
fast parser: the careful parser's rules in one pass over the bytes (``tuckercodec_core::text``),
faces equal to the first frame's shared rather than parsed again, and the checks of the reading
chunk by chunk. Whatever it refuses goes to the careful parser, which raises the error, so the
errors are the careful parser's own; ``tests/test_native_text.py`` compares the two.

Before either parser runs, the file is read a chunk at a time and refused at the first NUL byte,
the first byte that is not UTF-8, or the first line longer than :data:`MAX_LINE_BYTES`, so that a
binary or hostile file (say a single 2 GB line) is refused after a few megabytes, never read
whole. Line ends may be ``\\n``, ``\\r\\n`` or a lone ``\\r``; every error counts lines the
same way.
"""

from __future__ import annotations

import codecs
import os
import re
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType
from typing import BinaryIO

import numpy as np

from ..errors import InputError
from ..model.topology import face_table_problem
from ..system import native
from ..system.atomic import write_atomic, write_staged
from ..system.reading import open_regular_file
from .common.float_text import vertex_text
from .registry import MeshFrame, ReadOptions

#: The longest line the OBJ reader accepts, in bytes, its line end not counted: 4 MiB, a face of
#: about half a million corners, far beyond any real mesh. A longer line is refused as soon as
#: this much of it has been read, so a corrupt or hostile file costs neither the time nor the
#: memory of reading it whole.
MAX_LINE_BYTES = 4 * 2**20
# The face table pads every face to the widest one, so one huge polygon among many triangles
# would make it far larger than the file (a 0.7 MB file asked for 45 GiB). It may hold at most
# 16 entries per corner in the file or 2**24 entries (128 MiB), whichever is more: a 500-gon cap
# among 30 000 triangles is fine, a 300 000-gon among 20 000 triangles is refused.
_PADDED_PER_CORNER = 16
_PADDED_AT_LEAST = 2**24
# Bytes read at a time: at most the line limit, so that a line that fits in one chunk is never
# too long and only lines that cross a chunk boundary need counting.
_CHUNK_BYTES = 2**20

# Characters a tidy ``v`` block may hold: the keyword, numbers, whitespace. Anything else
# (``nan``, ``inf``, ``_``, ``#``...) sends the file to the careful parser, so ``float`` in the fast
# path only ever sees plain decimal numbers, exactly like the careful parser's _NUMBER pattern.
_VERTEX_CHARS = b"v0123456789+-.eE \t\n\r\x0b\x0c"
_FACE_CHARS = b"f0123456789+- \t\n\r\x0b\x0c"

# "\d+(?:\.\d*)?", not "\d+\.?\d*": the same numbers, but the latter splits a run of digits
# between its two \d in every way before it gives up, quadratic time on "111...1x".
_NUMBER = re.compile(rb"[+-]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?")
_NON_FINITE = {b"nan", b"inf", b"infinity"}
_INTEGER = re.compile(rb"[+-]?\d+")
# A face index of more digits than this is out of range for any file (and of int64).
_MAX_INDEX_DIGITS = 18
# The "/vt/vn" after the vertex index of a corner ("1/2/3" -> "1"). Only after a digit: a corner
# without a vertex index ("/2") must keep its slash so that the fast parser gives up on it.
_TEXTURE_NORMAL_PART = re.compile(rb"(?<=[0-9])/\S*")

# A v line may carry a weight w (4 numbers) or an RGB(A) colour (6 or 7 numbers): xyz is kept.
_VERTEX_NUMBER_COUNTS = (3, 4, 6, 7)

_NEWLINE, _SPACE = ord("\n"), ord(" ")
_ODD_LINE_START = np.frombuffer(b" \t\x0b\x0c", dtype=np.uint8)  # indented lines
_ODD_AFTER_KEYWORD = np.frombuffer(b"\t\x0b\x0c#\\\n", dtype=np.uint8)  # "v\t", "v#", bare "v"


@dataclass(eq=False)
class _Located:
    """The careful parser's result: the mesh plus the line number of every vertex and face."""

    vertices: np.ndarray
    faces: np.ndarray
    vertex_lines: list[int]
    face_lines: list[int]


# --------------------------------------------------------------------------------------------
# reading


def read_obj(path: str | os.PathLike[str]) -> tuple[np.ndarray, np.ndarray]:
    """Read the vertices and faces of an OBJ file.

    Returns ``(vertices, faces)``: vertices (K, 3) float64 in the order of the ``v`` lines, faces
    (M, n) int64 with 0-based indices, rows of polygons shorter than the widest one padded with
    -1 ((0, 3) when the file has no faces).

    Raises:
        InputError: the file cannot be read or is not a valid OBJ mesh; the error names the file
            and, where one is at fault, the 1-based line.
    """
    mesh = read_obj_frame(path)
    return mesh.vertices, mesh.faces


def read_obj_frame(
    path: str | os.PathLike[str],
    reference: MeshFrame | None = None,
    options: ReadOptions | None = None,
) -> MeshFrame:
    """Read one OBJ frame of a sequence, checking it against the first frame ``reference``
    (``options``: nothing in an OBJ file is compressed, so ``max_memory`` has nothing to bound).

    With a reference, the frame must have as many vertices and the same faces as the reference;
    when its face lines are byte for byte those of the reference, they are not parsed again and
    ``faces`` is the reference's array.

    Raises:
        InputError: as :func:`read_obj`, and when the vertex count or the faces differ from the
            reference (naming the first line that differs).
    """
    return read_obj_frame_text(path, reference)[0]


def read_obj_frame_text(
    path: str | os.PathLike[str], reference: MeshFrame | None = None
) -> tuple[MeshFrame, bytes]:
    """:func:`read_obj_frame`, and the file's text (line ends made ``\\n``), which
    :mod:`.obj_attributes` reads the other statements of."""
    path = Path(path)
    data = _read_text(path)
    core = native.core()
    if core is not None:
        mesh = _parse_native(core, data, path, reference)
    else:
        mesh = _parse_fast(data, reference)
    if mesh is None:
        located = _parse_careful(data, path)
        mesh = MeshFrame(located.vertices, located.faces)
    mesh.path = str(path)
    if reference is not None:
        _check_matches(mesh, reference, data, path)
    return mesh, data


def _read_text(path: Path) -> bytes:
    """The bytes of a text file, with line ends made ``\\n``.

    Binary data (a NUL byte or bytes that are not UTF-8), a line longer than
    :data:`MAX_LINE_BYTES` and an empty file are errors naming the line.
    """
    try:
        with open_regular_file(path, "an OBJ file") as stream:
            data = _read_checked(stream, path)
    except IsADirectoryError:
        raise InputError("is a folder, not an OBJ file", path=path) from None
    except OSError as error:
        raise InputError(f"cannot read: {error.strerror or error}", path=path) from None
    data = data.removeprefix(codecs.BOM_UTF8)
    if not data.strip():
        raise InputError("the file is empty", path=path)
    if b"\r" in data:
        # "\r\n" (Windows) and a lone "\r" (old Mac) end a line, as bytes.splitlines() says
        data = data.replace(b"\r\n", b"\n").replace(b"\r", b"\n")
    return data


def _read_checked(stream: BinaryIO, path: Path) -> bytes:
    """Read a whole stream a chunk at a time, refusing it at the first NUL byte, byte that is
    not UTF-8 or line longer than :data:`MAX_LINE_BYTES`, before reading any further."""
    limit = MAX_LINE_BYTES  # read at call time, so that the tests can lower it
    core = native.core()
    if core is not None:
        return _read_checked_native(core, stream, path, limit)
    decoder = codecs.getincrementaldecoder("utf-8")()
    chunks: list[bytes] = []
    line = 1  # the number of the line the chunk starts in
    line_length = 0  # bytes of that line in the chunks before
    after_cr = False  # the chunk before ended in "\r": a "\n" first in this one ends no line

    def refuse(reason: str, offset: int) -> InputError:
        """An error at byte ``offset`` of the current chunk."""
        return InputError(reason, path=path, line=line + _line_ends(chunk[:offset], after_cr))

    while chunk := stream.read(min(_CHUNK_BYTES, limit)):
        nul = chunk.find(b"\0")
        if nul >= 0:
            raise refuse(_FAULTS["nul"], nul)
        # decode only to validate; an ASCII chunk is valid unless a character is left open
        if not chunk.isascii() or decoder.getstate()[0]:
            try:
                decoder.decode(chunk)
            except UnicodeDecodeError as error:
                # error.start counts the bytes the decoder kept from the chunk before
                at = max(0, error.start - (len(error.object) - len(chunk)))
                raise refuse(_FAULTS["utf8"], at) from None
        last_end = max(chunk.rfind(b"\n"), chunk.rfind(b"\r"))
        if last_end < 0:
            line_length += len(chunk)
        else:
            if line_length + _first_line_end(chunk) > limit:
                raise refuse(_too_long(limit), 0)
            line_length = len(chunk) - last_end - 1
        if line_length > limit:
            raise refuse(_too_long(limit), len(chunk))
        line += _line_ends(chunk, after_cr)
        after_cr = chunk.endswith(b"\r")
        chunks.append(chunk)
    try:
        decoder.decode(b"", final=True)
    except UnicodeDecodeError:
        raise InputError(_FAULTS["truncated"], path=path, line=line) from None
    return b"".join(chunks)


#: What a refused text file is told, by the kind of fault the compiled core reports.
_FAULTS = {
    "nul": "contains NUL bytes: this is binary data, not an OBJ text file",
    "utf8": "is not UTF-8 text (binary data?), so not an OBJ file",
    "truncated": "is not UTF-8 text: it ends inside a character",
}


def _read_checked_native(core: ModuleType, stream: BinaryIO, path: Path, limit: int) -> bytes:
    """:func:`_read_checked` with its checks run by the compiled core, chunk by chunk alike."""
    check = core.ObjTextCheck(limit)
    chunks: list[bytes] = []
    while chunk := stream.read(min(_CHUNK_BYTES, limit)):
        fault = check.feed(chunk)
        if fault is None:
            chunks.append(chunk)
            continue
        kind, line = fault
        raise InputError(_FAULTS.get(kind) or _too_long(limit), path=path, line=line)
    fault = check.finish()
    if fault is not None:
        raise InputError(_FAULTS["truncated"], path=path, line=fault[1])
    return b"".join(chunks)


def _too_long(limit: int) -> str:
    """The message for a line over the limit."""
    return (
        f"line longer than {limit} bytes (tuckercodec.io.obj.MAX_LINE_BYTES): not an OBJ text "
        "file, or a damaged one"
    )


def _line_ends(data: bytes, after_cr: bool) -> int:
    """The number of line ends in ``data``: ``\\n``, ``\\r\\n`` or a lone ``\\r`` (what
    ``bytes.splitlines`` splits at). ``after_cr``: the bytes before ended in ``\\r``."""
    ends = data.count(b"\n") + data.count(b"\r") - data.count(b"\r\n")
    if after_cr and data.startswith(b"\n"):
        ends -= 1  # the second half of a "\r\n" split between two chunks
    return ends


def _first_line_end(data: bytes) -> int:
    """The offset of the first ``\\n`` or ``\\r`` in ``data``, which has one."""
    ends = [at for at in (data.find(b"\n"), data.find(b"\r")) if at >= 0]
    return min(ends)


# --------------------------------------------------------------------------------------------
# the compiled core's parser


def _parse_native(
    core: ModuleType, data: bytes, path: Path, reference: MeshFrame | None
) -> MeshFrame | None:
    """The careful parser's result, from the compiled core (the rules of
    :func:`_parse_careful`, in Rust); ``None`` where the core refuses the text, so that the
    careful parser itself raises the error: the reference's class, message and line. The face
    statements of a frame equal to the reference's (its ``face_text``, the core's key) are
    not parsed again."""
    known = reference.face_text if reference is not None else None
    count = len(reference.vertices) if reference is not None else 0
    try:
        vertices, faces, face_key = core.obj_parse(data, known, count)
    except core.ObjError:
        return None
    if reference is not None and (faces is None or np.array_equal(faces, reference.faces)):
        faces = reference.faces  # one table for the whole sequence, as the fast parser shares
    return MeshFrame(vertices, faces, face_key)


# --------------------------------------------------------------------------------------------
# the fast parser


def _parse_fast(data: bytes, reference: MeshFrame | None) -> MeshFrame | None:
    """Parse a tidy file in a few whole-file operations, or ``None``: go the careful way."""
    lines = _line_table(data)
    if lines is None:
        return None
    starts, ends, is_vertex, is_face = lines

    vertex_text = _join_lines(data, starts, ends, is_vertex)
    vertices = _fast_vertices(vertex_text, int(is_vertex.sum()))
    if vertices is None:
        return None

    face_text = _join_lines(data, starts, ends, is_face)
    # Negative indices count back from the line they are on, so equal text is not enough then.
    reusable = b"-" not in face_text
    if (
        reference is not None
        and reusable
        and reference.face_text == face_text
        and len(reference.vertices) == len(vertices)
    ):
        return MeshFrame(vertices, reference.faces, face_text)
    vertices_before = np.cumsum(is_vertex)[is_face]
    faces = _fast_faces(face_text, vertices_before, len(vertices))
    if faces is None:
        return None
    return MeshFrame(vertices, faces, face_text if reusable else None)


def _line_table(data: bytes) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None:
    """Start and end offsets of every line and which are ``v``/``f`` lines; None if any is odd.

    Odd lines are those the careful parser could read differently than "a line starting with
    ``v `` or ``f ``": indented lines, ``v`` followed by a tab, ``#`` or nothing, and lines
    continued on the next one (a backslash at the end or before a comment; this also catches some
    harmless backslashes, which only costs the careful parser's time).
    """
    if b"\\" in data and (b"\\\n" in data or b"\\#" in data or data.endswith(b"\\")):
        return None
    text = np.frombuffer(data + b"\n\n", dtype=np.uint8)  # two spare bytes to look past the end
    newlines = np.flatnonzero(text[: len(data)] == _NEWLINE)
    starts = np.concatenate(([0], newlines + 1))
    ends = np.concatenate((newlines, [len(data)]))
    first, second = text[starts], text[starts + 1]
    keyword = (first == ord("v")) | (first == ord("f"))
    odd = np.isin(first, _ODD_LINE_START) | (keyword & np.isin(second, _ODD_AFTER_KEYWORD))
    if odd.any():
        return None
    is_vertex = (first == ord("v")) & (second == _SPACE)
    is_face = (first == ord("f")) & (second == _SPACE)
    return starts, ends, is_vertex, is_face


def _join_lines(data: bytes, starts: np.ndarray, ends: np.ndarray, chosen: np.ndarray) -> bytes:
    """The chosen lines joined by newlines (one slice when they follow each other, as usual)."""
    rows = np.flatnonzero(chosen)
    if rows.size == 0:
        return b""
    first, last = int(rows[0]), int(rows[-1])
    if last - first + 1 == rows.size:
        return data[starts[first] : ends[last]]
    return b"\n".join(
        data[s:e] for s, e in zip(starts[rows].tolist(), ends[rows].tolist(), strict=True)
    )


def _fast_vertices(text: bytes, count: int) -> np.ndarray | None:
    """(count, 3) positions from ``v`` lines that all have 3 (or all 4, 6 or 7) plain numbers."""
    if count == 0 or text.translate(None, _VERTEX_CHARS):
        return None
    tokens = text.split()
    per_line = len(tokens) // count  # keyword + numbers, if every line has as many numbers
    # With every per_line-th token the keyword, each line has exactly per_line - 1 numbers (a
    # stray "v" among the numbers would make float() fail below).
    if (
        per_line - 1 not in _VERTEX_NUMBER_COUNTS
        or len(tokens) != per_line * count
        or tokens[::per_line].count(b"v") != count
    ):
        return None
    del tokens[::per_line]
    try:
        values = np.array(list(map(float, tokens)), dtype=np.float64)
    except ValueError:
        return None
    xyz = values.reshape(count, per_line - 1)[:, :3]
    if not np.isfinite(xyz).all():  # e.g. 1e999; the careful parser names the line
        return None
    return np.ascontiguousarray(xyz)


def _fast_faces(text: bytes, vertices_before: np.ndarray, vertex_count: int) -> np.ndarray | None:
    """0-based, -1-padded faces from plain ``f`` lines with valid indices, else None.

    ``vertices_before[i]`` is the number of ``v`` lines above face line i, which resolves
    negative (relative) indices.
    """
    count = len(vertices_before)
    if count == 0:
        return np.zeros((0, 3), dtype=np.int64)
    if b"#" in text:  # a trailing comment, which the slash removal below could swallow
        return None
    if b"/" in text:
        text = _TEXTURE_NORMAL_PART.sub(b"", text)
    if text.translate(None, _FACE_CHARS):
        return None
    tokens = text.split()
    # Each line starts with the keyword; a stray "f" among the corners would fail int() below.
    keyword_at = [position for position, token in enumerate(tokens) if token == b"f"]
    if len(keyword_at) != count:
        return None
    sizes = np.diff(np.append(keyword_at, len(tokens))) - 1
    if sizes.min() < 3:
        return None
    try:
        values = np.array([int(token) for token in tokens if token != b"f"], dtype=np.int64)
    except (ValueError, OverflowError):
        return None
    # OBJ indices are 1-based; negative ones count back from the face's line (-1 = last vertex).
    before = np.repeat(vertices_before, sizes)
    indices = np.where(values < 0, before + values, values - 1)
    if (values == 0).any() or indices.min() < 0 or indices.max() >= vertex_count:
        return None
    if not _padding_fits(count, int(sizes.max()), len(values)):
        return None  # the careful parser names the widest face
    return _rows_from_sizes(indices, sizes)


def _padding_fits(face_count: int, width: int, corners: int) -> bool:
    """Whether ``face_count`` faces padded to ``width`` stay within the limit for ``corners``."""
    return face_count * width <= max(_PADDED_AT_LEAST, _PADDED_PER_CORNER * corners)


def _rows_from_sizes(indices: np.ndarray, sizes: np.ndarray) -> np.ndarray:
    """Cut a flat index list into rows of the given sizes, padding short rows with -1."""
    width = int(sizes.max())
    if (sizes == width).all():
        return indices.reshape(len(sizes), width)
    faces = np.full((len(sizes), width), -1, dtype=np.int64)
    rows = np.repeat(np.arange(len(sizes)), sizes)
    columns = np.arange(len(indices)) - np.repeat(np.cumsum(sizes) - sizes, sizes)
    faces[rows, columns] = indices
    return faces


# --------------------------------------------------------------------------------------------
# the careful parser


def _statements(data: bytes) -> Iterator[tuple[int, list[bytes]]]:
    """Yield ``(line number, tokens)`` of every statement, without comments and blank lines.

    A line ending in a backslash (once its comment is removed) continues on the next line; the
    statement keeps the number of its first line.
    """
    pending: list[bytes] = []
    pending_line = 0
    for number, line in enumerate(data.splitlines(), start=1):
        line = line.split(b"#", 1)[0]
        if line.endswith(b"\\"):
            if not pending:
                pending_line = number
            pending.append(line[:-1])
            continue
        if pending:
            line = b" ".join([*pending, line])
            number = pending_line
            pending = []
        tokens = line.split()
        if tokens:
            yield number, tokens
    if pending:
        tokens = b" ".join(pending).split()
        if tokens:
            yield pending_line, tokens


def _parse_careful(data: bytes, path: Path) -> _Located:
    """Parse line by line, raising an :class:`InputError` that names the line at fault."""
    vertices: list[tuple[float, float, float]] = []
    vertex_lines: list[int] = []
    faces: list[list[int]] = []
    face_lines: list[int] = []
    for number, tokens in _statements(data):
        keyword = tokens[0]
        if keyword == b"v":
            vertices.append(_vertex(tokens[1:], path, number))
            vertex_lines.append(number)
        elif keyword == b"f":
            faces.append(_face(tokens[1:], len(vertices), path, number))
            face_lines.append(number)
        # everything else (vt, vn, vp, o, g, s, usemtl, mtllib, l, p, ...) does not matter here

    if not vertices:
        raise InputError("no vertices: the file has no 'v' lines", path=path)
    for face, number in zip(faces, face_lines, strict=True):
        for index in face:
            if index >= len(vertices):
                raise InputError(
                    f"face refers to vertex {index + 1}, but the file has only "
                    f"{len(vertices)} vertices",
                    path=path,
                    line=number,
                )
    sizes = [len(face) for face in faces]
    if sizes and not _padding_fits(len(faces), max(sizes), sum(sizes)):
        widest = int(np.argmax(sizes))
        raise InputError(
            f"a face of {sizes[widest]} corners: padding all {len(faces)} faces to its width "
            f"would take {len(faces) * sizes[widest] * 8 / 2**30:.1f} GiB; split the polygon",
            path=path,
            line=face_lines[widest],
        )
    return _Located(
        np.array(vertices, dtype=np.float64).reshape(-1, 3),
        _pad_faces(faces),
        vertex_lines,
        face_lines,
    )


def _vertex(numbers: list[bytes], path: Path, line: int) -> tuple[float, float, float]:
    """The xyz of a ``v`` line's numbers (x y z [w] or x y z r g b [a])."""
    if len(numbers) not in _VERTEX_NUMBER_COUNTS:
        raise InputError(
            f"a 'v' line needs x y z (optionally w, or an r g b [a] colour), "
            f"got {len(numbers)} value(s)",
            path=path,
            line=line,
        )
    values = [_number(token, path, line) for token in numbers]
    if not all(np.isfinite(values[:3])):
        shown = " ".join(_short(token) for token in numbers[:3])
        raise InputError(f"non-finite vertex coordinate: {shown}", path=path, line=line)
    return values[0], values[1], values[2]


def _number(token: bytes, path: Path, line: int) -> float:
    """A decimal number; nan and inf are returned so that the caller can say "non-finite"."""
    if _NUMBER.fullmatch(token):
        return float(token)
    unsigned = token[1:] if token[:1] in (b"+", b"-") else token  # one sign, as float() takes
    if unsigned.lower() in _NON_FINITE:
        return float(token)
    raise InputError(f"not a number: {_short(token)!r}", path=path, line=line)


def _face(corners: list[bytes], vertices_so_far: int, path: Path, line: int) -> list[int]:
    """0-based vertex indices of an ``f`` line's corners (``a``, ``a/b``, ``a//c``, ``a/b/c``).

    Negative indices count back from the last vertex defined before this line (-1 is that
    vertex). Positive indices are checked against the vertex count once the file is read.
    """
    if len(corners) < 3:
        raise InputError(
            f"a face needs at least 3 corners, got {len(corners)}", path=path, line=line
        )
    indices = []
    for corner in corners:
        text = corner.split(b"/", 1)[0]
        shown = _short(corner)
        if not _INTEGER.fullmatch(text):
            raise InputError(f"face corner {shown!r} is not a vertex index", path=path, line=line)
        digits = text.lstrip(b"+-").lstrip(b"0")
        if len(digits) > _MAX_INDEX_DIGITS:
            # no file has that many vertices; and int() refuses over 4300 digits with a ValueError
            raise InputError(
                f"face corner {shown!r} refers to a vertex number of {len(digits)} digits, "
                "more than any file holds",
                path=path,
                line=line,
            )
        value = int(digits or b"0") * (-1 if text.startswith(b"-") else 1)
        if value == 0:
            raise InputError(
                f"face corner {shown!r}: OBJ indices start at 1, 0 is invalid",
                path=path,
                line=line,
            )
        if value < 0:
            if -value > vertices_so_far:
                raise InputError(
                    f"face corner {shown!r} counts back past the first vertex "
                    f"(only {vertices_so_far} defined so far)",
                    path=path,
                    line=line,
                )
            indices.append(vertices_so_far + value)
        else:
            indices.append(value - 1)
    return indices


def _short(token: bytes) -> str:
    """A token as a message quotes it: its first 40 characters and "..." if it is longer (a
    line may be megabytes long, and a message is read by a person)."""
    text = token.decode("utf-8", "replace")
    return text if len(text) <= 40 else text[:40] + "..."


def _pad_faces(faces: list[list[int]]) -> np.ndarray:
    """A list of faces of any sizes as one (M, n) array, short rows padded with -1."""
    if not faces:
        return np.zeros((0, 3), dtype=np.int64)
    width = max(len(face) for face in faces)
    if all(len(face) == width for face in faces):
        return np.array(faces, dtype=np.int64)
    padded = np.full((len(faces), width), -1, dtype=np.int64)
    for row, face in enumerate(faces):
        padded[row, : len(face)] = face
    return padded


# --------------------------------------------------------------------------------------------
# checking a frame against the first one


def _check_matches(mesh: MeshFrame, reference: MeshFrame, data: bytes, path: Path) -> None:
    """Raise if ``mesh`` has another vertex count or other faces than ``reference``."""
    same_count = len(mesh.vertices) == len(reference.vertices)
    if same_count and (
        mesh.faces is reference.faces or np.array_equal(mesh.faces, reference.faces)
    ):
        return
    # Something differs: the careful parser knows on which line.
    located = _parse_careful(data, path)
    first = f" ({reference.path})" if reference.path else ""  # the other file to look at
    if not same_count:
        count, expected = len(mesh.vertices), len(reference.vertices)
        line = located.vertex_lines[min(expected, count - 1)]
        raise InputError(
            f"has {count} vertices but the first frame has {expected}{first}: every frame of a "
            "sequence must have the same vertices",
            path=path,
            line=line,
        )
    row = _first_different_row(mesh.faces, reference.faces)
    ours = _face_text(mesh.faces, row)
    theirs = _face_text(reference.faces, row)
    if located.face_lines:
        line = located.face_lines[min(row, len(located.face_lines) - 1)]
    else:  # no faces at all: point at the end of the file, where they are missing
        line = len(data.splitlines())
    raise InputError(
        f"face {row + 1} is {ours} but in the first frame it is {theirs}{first}: every frame of a "
        "sequence must have the same faces",
        path=path,
        line=line,
    )


def _first_different_row(faces: np.ndarray, reference: np.ndarray) -> int:
    """Index of the first face that differs (or is missing in one of the two)."""
    width = max(faces.shape[1], reference.shape[1])
    rows = min(len(faces), len(reference))
    a = _widen(faces[:rows], width)
    b = _widen(reference[:rows], width)
    different = np.flatnonzero((a != b).any(axis=1))
    return int(different[0]) if different.size else rows


def _widen(faces: np.ndarray, width: int) -> np.ndarray:
    """Pad faces with -1 columns up to ``width``."""
    extra = np.full((len(faces), width - faces.shape[1]), -1, dtype=np.int64)
    return np.hstack([faces, extra])


def _face_text(faces: np.ndarray, row: int) -> str:
    """A face as its 1-based OBJ corners, e.g. ``f 1 2 3``, or ``missing``."""
    if row >= len(faces):
        return "missing"
    return "f " + " ".join(str(index + 1) for index in faces[row].tolist() if index >= 0)


# --------------------------------------------------------------------------------------------
# writing


def write_obj(
    path: str | os.PathLike[str],
    vertices: np.ndarray,
    faces: np.ndarray,
    *,
    precision: int | None = None,
    overwrite: bool = False,
    staged: bool = False,
) -> None:
    """Write vertices and faces as an OBJ file, atomically.

    Args:
        path: the file to write.
        vertices: (K, 3) positions, written as ``v x y z`` lines in this order.
        faces: (M, n) 0-based indices, -1 for padding (omitted), written as 1-based ``f`` lines.
        precision: significant digits of the coordinates; ``None`` (default) writes the
            shortest text that reads back to the very same float64 (Python's ``repr``).
        overwrite: replace an existing file; otherwise an existing file is an error.
        staged: ``path`` is a new file in the staging folder of a folder of frames, which is
            synced and moved in whole (:func:`tuckercodec.system.atomic.atomic_folder` with
            ``sync``): it is written plainly (:func:`tuckercodec.system.atomic.write_staged`).

    Raises:
        FileExistsError: ``path`` exists and ``overwrite`` is False (checked before writing; the
            file is written to a temporary name and renamed, see :mod:`tuckercodec.system.atomic`).
        ValueError: the arrays have the wrong shape or hold non-finite/out-of-range values.
    """
    vertices = np.asarray(vertices, dtype=np.float64)
    faces = np.asarray(faces)
    _check_writable(vertices, faces, precision)
    if precision is None:  # repr's text, made by array operations; the faces' kept bytes
        chunks = [vertex_text(vertices), _faces_bytes(faces)]
    else:
        lines = _vertex_lines(vertices, precision)
        joined = "\n".join([*lines, _faces_text(faces)]) if lines else _faces_text(faces)
        chunks = [joined.encode("ascii")]
    if staged:
        write_staged(path, chunks)
    else:
        write_atomic(path, lambda handle: handle.writelines(chunks), overwrite=overwrite)


def _check_writable(vertices: np.ndarray, faces: np.ndarray, precision: int | None) -> None:
    """Reject what would make a broken or unreadable OBJ file."""
    if vertices.ndim != 2 or vertices.shape[1] != 3:
        raise ValueError(f"vertices must have shape (K, 3), got {vertices.shape}")
    if not np.isfinite(vertices).all():
        raise ValueError("vertices must be finite (OBJ readers reject nan and inf)")
    if faces.size and (faces.ndim != 2 or faces.shape[1] < 3):
        raise ValueError(f"faces must have shape (M, n >= 3), got {faces.shape}")
    if faces.size and not np.issubdtype(faces.dtype, np.integer):
        raise ValueError(f"faces must be integers, got dtype {faces.dtype}")
    problem = face_table_problem(faces, len(vertices))
    if problem is not None:  # an OBJ reader would refuse the file, this one included
        raise ValueError(problem.message)
    if precision is not None and (isinstance(precision, bool) or not 1 <= precision <= 17):
        raise ValueError(f"precision must be 1..17 significant digits or None, got {precision!r}")


def _vertex_lines(vertices: np.ndarray, precision: int | None) -> list[str]:
    """``v x y z`` lines; ``repr`` of a Python float is its shortest exact round-trip text.
    Every number is formatted by one C-level ``map`` over the flat values, then the lines
    are put together three at a time: about 1.5 times as fast as formatting row by row."""
    values = vertices.reshape(-1).tolist()
    numbers = list(map(repr if precision is None else f"%.{precision}g".__mod__, values))
    each = iter(numbers)
    return [f"v {x} {y} {z}" for x, y, z in zip(each, each, each, strict=True)]


#: The last faces written (a copy) and their text, as str and as ASCII bytes: a folder of
#: frames writes the same faces in every frame, so their text is made once (found by the
#: table's values, not its identity: the caller may have changed it in place). Frames written
#: from several threads at once may each make it: the same text.
_last_faces: tuple[np.ndarray, str, bytes] | None = None


def _faces_text(faces: np.ndarray) -> str:
    """The ``f`` lines of ``faces``, each ended by a newline (the last text kept for the next
    frame of a folder, when it writes the same faces)."""
    return _faces_cached(faces)[0]


def _faces_bytes(faces: np.ndarray) -> bytes:
    """:func:`_faces_text` as ASCII bytes."""
    return _faces_cached(faces)[1]


def _faces_cached(faces: np.ndarray) -> tuple[str, bytes]:
    global _last_faces
    cached = _last_faces
    # the same values in the same shape and type: the same text (a comparison costs a tenth
    # of a hash of the table, which took 0.4 ms a frame for horse gallop's 16843 faces)
    if (
        cached is not None
        and cached[0].shape == faces.shape
        and cached[0].dtype == faces.dtype
        and np.array_equal(cached[0], faces)
    ):
        return cached[1], cached[2]
    core = native.core()
    if core is not None and faces.ndim == 2 and faces.size:
        encoded = core.obj_face_text(np.ascontiguousarray(faces, dtype=np.int64))
        text = encoded.decode("ascii")
    else:
        text = "".join(line + "\n" for line in _face_lines(faces))
        encoded = text.encode("ascii")
    _last_faces = (faces.copy(), text, encoded)
    return text, encoded


def _face_lines(faces: np.ndarray) -> list[str]:
    """1-based ``f`` lines, leaving out the -1 padding."""
    if faces.size == 0:
        return []
    rows = (faces.astype(np.int64) + 1).tolist()
    if (faces >= 0).all():
        line = "f " + " ".join(["%d"] * faces.shape[1])
        return [line % tuple(row) for row in rows]
    return ["f " + " ".join(str(index) for index in row if index > 0) for row in rows]
