"""§6.8 Codec ``faces-traverse`` (format 1.2): connectivity by traversal, vertex order kept.

The walk's encoder and decoder mirror each other step by step, and they are kept side by side
so that a change to one is read against the other.

The faces are coded by walking across their edges, as Edgebreaker and the cut-border machine do,
instead of as a table of indices. The walk keeps a *boundary*: the directed edges of the faces
decoded so far whose opposite edge no decoded face has yet. It pops *gates* (boundary edges
a -> b) from a stack; across each it either finds no new face or attaches one, (b, a, w1, ...):
the orientation of its neighbour, sharing the gate. Each tip w is coded as

* ``NEW``: a vertex not seen yet; its index is the last new vertex's index + 1 + a residual
  (the *order map*: the file's vertex order is kept exactly, and costs little where the order
  follows the surface); with ``coder`` 1 (format 1.6), its signed rank among the vertices not
  seen yet instead (:mod:`.unseen`);
* ``PREV``: the vertex before the face's previous corner on the boundary (closing a fan);
* ``NEXT``: the vertex after the face's first corner on the boundary (closing the other side);
* ``FAR``: any vertex already seen, as a residual from the previous corner (rare: handles,
  pinches, joins of components).

Nothing assumes a manifold: an edge of three faces, a face of the other orientation (``FLIP``),
a repeated vertex, a polygon (its degree is coded) and a vertex on no face (it takes one of the
indices left, in ascending order) all code, only at more bits. A face no gate reaches starts a
*seed*, corners coded as tips. What is kept: every face, its corners' cyclic order and its
orientation (the rotation of the stored corners is coded, ``corner_order`` says against which
corner). What is not: the order of the faces, which is the walk's (§6.8 makes it normative).

The four streams are stored as zstd over byte planes (§6.1), or with ``coder`` 1 (format 1.6,
in a file with flag bit 3) each as one column of the adaptive coder (§6.14), the NEW vertices
as ranks; the walk reads and writes gaps either way (the ranks are turned to and from gaps
outside it).

The decoder is one pass in Python over the faces, on integers in lists and dicts, with numpy
doing what is not sequential before and after it (:func:`_walk_triangles`; :func:`_walk` holds
every case and is its reference); the encoder runs the same walk with the mesh to answer each
question. The encoder and :func:`_walk` share :class:`_Boundary`. Where the compiled core is
installed (:mod:`..system.native`), both walks run there instead (``tuckercodec/native/core/src/
traversal``), giving the same streams, faces and errors; the Python here is their reference.
"""

from __future__ import annotations

import operator
from collections import defaultdict
from collections.abc import Iterator, Mapping, Sequence
from typing import Any, NamedTuple

import msgpack
import numpy as np

from ..errors import FormatError
from ..system import native
from . import adaptive, streams, uniform, unseen
from .limits import DEFAULT_LIMITS, Limits, check_limit
from .sections import section_shape

FACES_TRAVERSE = "faces-traverse"
#: Gate kinds: no face across the gate, a face of the same orientation, the other one. A gate
#: with a face is one op, ``1 + 8 * rotation + 4 * flipped + first tip``: one symbol per
#: triangle, so that zstd's Huffman coder pays its rounding once per face, not three times.
GATE_NONE, GATE_FACE, GATE_FLIP = 0, 1, 2
#: Tip operations (the first tip of an attached face inside its gate op; the others alone).
TIP_NEW, TIP_PREV, TIP_NEXT, TIP_FAR = 0, 1, 2, 3
#: The four integer streams of the payload, in order.
STREAM_NAMES = ("ops", "degrees", "vertices", "references")
NEW_VERTICES = STREAM_NAMES.index("vertices")
#: ``corner_order``: the rotation is the position in the stored face of the walk's first corner
#: (0), or of the face's smallest vertex index (1).
ROTATE_FROM_GATE, ROTATE_FROM_SMALLEST = 0, 1
#: With ``coder`` 1 every integer of the four streams is a 32-bit one, as with §6.1's planes.
ADAPTIVE_PLANES = 4
#: The ``ranks`` values (format 1.9, §6.8): with ``coder`` 1 the vertices stream holds each NEW
#: vertex's rank from the last one in the adaptive coder, or its place among the unseen vertices
#: in a uniform stream (:mod:`.uniform`), for a vertex order the walk does not follow.
RANKS_ADAPTIVE, RANKS_UNIFORM = 0, 1
#: The preamble's flag bit 6 (critical): ``ranks`` 1 (format 1.9).
UNIFORM_RANKS = 0x0040
UNIFORM_RANKS_MINOR = 9


class _Boundary:
    """The directed edges of the decoded faces whose opposite edge is not decoded yet.

    ``count[x * K + y]`` is how many times x -> y is open (more than once only where faces
    overlap). ``into[v]`` and ``out_of[v]`` are stacks of the edges u -> v and v -> w (as keys
    ``u * K + v``, ``v * K + w``) in the order they became open: an entry stays when its edge
    closes, and is popped for good once it is found on top with its edge closed
    (:func:`_newest`). So adding, removing and reading the newest are O(1) amortized whatever a
    file does: lists searched for the entry to remove cost a crafted file quadratic time, and so
    did ordered dicts, whose last entry is found by passing over every entry removed behind it
    (a 5 KB section took 56 s). An edge open again is pushed again, above its stale entry.
    :meth:`attach` adds a face and pushes its new gates.
    """

    def __init__(self, vertex_count: int) -> None:
        self.k = vertex_count
        self.count: dict[int, int] = {}
        # by vertex, made as vertices are touched: a header's vertex count is not yet checked
        # against anything when FACE is decoded, and must not size an allocation
        self.into: defaultdict[int, list[int]] = defaultdict(list)
        self.out_of: defaultdict[int, list[int]] = defaultdict(list)
        self.gates: list[int] = []

    def newest_into(self, v: int) -> int | None:
        """The u of the newest open u -> v, if any (PREV)."""
        key = _newest(self.into.get(v), self.count)
        return None if key is None else key // self.k

    def newest_out_of(self, v: int) -> int | None:
        """The w of the newest open v -> w, if any (NEXT)."""
        key = _newest(self.out_of.get(v), self.count)
        return None if key is None else key % self.k

    def attach(self, cycle: list[int], first_gate: int) -> None:
        """Add the face ``cycle`` (in walk order): each edge x -> y closes an open y -> x, or
        opens; the edges from ``first_gate`` on become gates, the last one popped first."""
        k, count, into, out_of, gates = self.k, self.count, self.into, self.out_of, self.gates
        for j, (x, y) in enumerate(zip(cycle, cycle[1:] + cycle[:1], strict=True)):
            opposite, key = y * k + x, x * k + y
            open_count = count.get(opposite)
            if open_count:
                if open_count == 1:  # y -> x is closed: its entries in into(x), out(y) go stale
                    del count[opposite]
                else:
                    count[opposite] = open_count - 1
            elif key in count:
                count[key] += 1
            else:  # x -> y becomes open: the newest entry of both ends
                count[key] = 1
                into[y].append(key)
                out_of[x].append(key)
            if j >= first_gate:
                gates.append(key)


def _newest(stack: list[int] | None, open_edges: Mapping[int, int]) -> int | None:
    """The key of the newest open edge of ``stack``, its closed ones on top popped for good."""
    while stack:
        if stack[-1] in open_edges:
            return stack[-1]
        stack.pop()
    return None


# ---------------------------------------------------------------------------------- encoding


def encode_traversal(
    faces: np.ndarray,
    vertex_count: int,
    level: int = streams.DEFAULT_LEVEL,
    *,
    adaptive_coding: bool = False,
    uniform_ranks: bool = False,
) -> tuple[dict[str, Any], bytes, np.ndarray]:
    """``(params, payload, faces in walk order)`` of a FACE section with codec faces-traverse.

    The encoder tries both corner orders, with ``adaptive_coding`` (a file that may be of
    format 1.6) both coders, and with ``uniform_ranks`` too (format 1.9) both ways to store the
    new vertices in coder 1, and keeps the smallest. The faces it returns are the ones a decoder
    gives back: the same rows, corners and orientation, in the walk's order.
    """
    params, payload, walked, _ = encode_traversal_ordered(
        faces, vertex_count, level, adaptive_coding=adaptive_coding, uniform_ranks=uniform_ranks
    )
    return params, payload, walked


def encode_traversal_ordered(
    faces: np.ndarray,
    vertex_count: int,
    level: int = streams.DEFAULT_LEVEL,
    *,
    adaptive_coding: bool = False,
    uniform_ranks: bool = False,
) -> tuple[dict[str, Any], bytes, np.ndarray, np.ndarray]:
    """:func:`encode_traversal`, and the walk's order: the input's row of each walked face.

    Each candidate is weighed by its payload and its parameters together (``coder`` 1 adds a
    key to the header, and ``ranks`` 1 another), so that the file never grows for it."""
    table = np.asarray(faces, dtype=np.int64)
    count, width = table.shape if table.ndim == 2 and table.size else (0, 3)
    walk = _walked(table, count, vertex_count)
    # the codings to try, (coder, ranks), each with the three streams the corner order does not
    # change, packed once: only the ops differ between the corner orders
    zstd = (adaptive.CODER_ZSTD, RANKS_ADAPTIVE)
    plain = [walk.degrees, walk.new_residuals, walk.references]
    rest = {zstd: [_pack_stream(values, level, adaptive.CODER_ZSTD) for values in plain]}
    ranks = _ranks(walk.new_residuals, vertex_count) if adaptive_coding else None
    if ranks is not None and _fits_adaptive([*walk.ops, walk.degrees, ranks, walk.references]):
        coder = adaptive.CODER_ADAPTIVE
        others = [
            _pack_stream(walk.degrees, level, coder),
            _pack_stream(walk.references, level, coder),
        ]
        rest[coder, RANKS_ADAPTIVE] = [others[0], _pack_stream(ranks, level, coder), others[1]]
        if uniform_ranks and vertex_count <= uniform.MAX_TOTAL:
            places = np.cumsum(ranks)  # u(w): the unseen vertices below each new vertex w
            coded = ranks.size, 0, uniform.encode_uniform(places, vertex_count)
            rest[coder, RANKS_UNIFORM] = [others[0], coded, others[1]]
    best: tuple[int, dict[str, Any], bytes] | None = None
    for corner_order in (ROTATE_FROM_GATE, ROTATE_FROM_SMALLEST):
        ops = {
            coder: _pack_stream(walk.ops[corner_order], level, coder)
            for coder in {coder for coder, _ in rest}
        }
        for (coder, ranked), streams_ in rest.items():
            packed = [ops[coder], *streams_]
            params, payload = _assembled(packed, count, width, corner_order, coder, ranked)
            size = len(payload) + len(msgpack.packb(params))
            if best is None or size < best[0]:
                best = size, params, payload
    assert best is not None
    order = np.asarray(walk.order, dtype=np.int64)
    walked = table[order] if count else np.zeros((0, width), dtype=np.int64)
    return best[1], best[2], walked, order


def _ranks(new_residuals: Sequence[int], vertex_count: int) -> np.ndarray | None:
    """The NEW vertices' ranks among the unseen (``coder`` 1), or None where the walk's vertex
    count is beyond what the rank coding takes (2**62)."""
    if not 0 <= vertex_count <= 1 << 62:
        return None
    vertices = unseen.vertices_from_gaps(np.asarray(new_residuals, dtype=np.int64))
    return unseen.ranks_of(vertices, vertex_count)


def _fits_adaptive(coded: Sequence[Sequence[int] | np.ndarray]) -> bool:
    """Whether every value is a 32-bit integer, as a decoder of ``coder`` 1 requires."""
    limit = 1 << (8 * ADAPTIVE_PLANES - 1)
    for values in coded:
        array = np.asarray(values, dtype=np.int64)
        if array.size and (int(array.min()) < -limit or int(array.max()) >= limit):
            return False
    return True


class _Streams(NamedTuple):
    """A walk's streams: the ops for each corner order (0, 1), the degrees, the NEW and FAR
    residuals, and the input's row of each walked face in walk order (lists or int64 arrays)."""

    ops: tuple[Sequence[int], Sequence[int]]
    degrees: Sequence[int]
    new_residuals: Sequence[int]
    references: Sequence[int]
    order: Sequence[int]


def _walked(table: np.ndarray, count: int, vertex_count: int) -> _Streams:
    """The streams of the walk over ``table``: by the compiled core where it is installed and
    the table is one it takes (it answers None otherwise), else by :class:`_Walk`."""
    core = native.core()
    if core is not None and count and 0 <= vertex_count <= 1 << 32:
        walked = core.encode_traversal(np.ascontiguousarray(table), vertex_count)
        if walked is not None:
            ops_from_gate, ops_from_smallest, *rest = walked
            return _Streams((ops_from_gate, ops_from_smallest), *rest)
    walk = _Walk([[v for v in row if v >= 0] for row in table.tolist()], vertex_count)
    ops = (walk.ops_for(ROTATE_FROM_GATE), walk.ops_for(ROTATE_FROM_SMALLEST))
    return _Streams(ops, walk.degrees, walk.new_residuals, walk.references, walk.order)


def pack_streams(
    coded: Sequence[Sequence[int]],
    count: int,
    width: int,
    corner_order: int,
    level: int,
    coder: int = adaptive.CODER_ZSTD,
) -> tuple[dict[str, Any], bytes]:
    """``(params, payload)`` of the four streams ``coded`` (ops, degrees, vertices, references):
    zstd over byte planes (§6.1), or with ``coder`` 1 each one adaptive column (§6.14, planes 0;
    the vertices stream then holds the NEW vertices' ranks)."""
    packed = [_pack_stream(values, level, coder) for values in coded]
    return _assembled(packed, count, width, corner_order, coder)


def _pack_stream(
    values: Sequence[int] | np.ndarray, level: int, coder: int
) -> tuple[int, int, bytes]:
    """``(count, planes, payload)`` of one stream: zstd over byte planes, or with ``coder`` 1
    one adaptive column (planes 0)."""
    array = np.asarray(values, dtype=np.int64)
    if coder == adaptive.CODER_ADAPTIVE:
        order = adaptive.sequence_order(array.size)
        return array.size, 0, adaptive.encode_columns(array[None, :], order)
    payload, planes = streams.pack_integers(array, level)
    return array.size, planes, payload


def _assembled(
    packed: Sequence[tuple[int, int, bytes]],
    count: int,
    width: int,
    corner_order: int,
    coder: int,
    ranks: int = RANKS_ADAPTIVE,
) -> tuple[dict[str, Any], bytes]:
    """``(params, payload)`` of the four packed streams (ops, degrees, vertices, references)."""
    params: dict[str, Any] = {"shape": [count, width], "corner_order": corner_order}
    if coder == adaptive.CODER_ADAPTIVE:  # absent means 0: a file of coder 0 is as before 1.6
        params["coder"] = coder
    if ranks == RANKS_UNIFORM:  # absent means 0, as before 1.9
        params["ranks"] = ranks
    params["streams"] = [[size, planes, len(payload)] for size, planes, payload in packed]
    return params, b"".join(payload for _, _, payload in packed)


class _Walk:
    """The walk with the mesh known: the decoder's loop with each read replaced by the mesh's
    answer. It records the streams; the gate ops are finished by :meth:`ops_for`, once the
    corner order is chosen."""

    def __init__(self, rows: list[list[int]], k: int) -> None:
        self.rows, self.k = rows, k
        # per directed edge x -> y, the faces with the consecutive corners x, y, each once, the
        # input's first last: the walk pops the visited ones off the end as it meets them, so
        # that all its searches together take time linear in the corners (a search from the
        # front each time was quadratic on an edge of many faces: 50,000 faces took 115 s)
        self.faces_with: dict[int, list[int]] = {}
        for f in range(len(rows) - 1, -1, -1):
            row = rows[f]
            for x, y in zip(row, row[1:] + row[:1], strict=True):
                faces = self.faces_with.get(x * k + y)
                if faces is None:
                    self.faces_with[x * k + y] = [f]
                elif faces[-1] != f:  # the edge again in the same face
                    faces.append(f)
        self.polygons = any(len(row) != 3 for row in rows)
        self.done = [False] * len(rows)
        self.seen = bytearray(k)
        self.boundary = _Boundary(k)
        self.ops: list[int] = []
        #: (position in ops, kind, start corner, position of the smallest corner, degree)
        self.gate_ops: list[tuple[int, int, int, int, int]] = []
        self.degrees: list[int] = []
        self.new_residuals: list[int] = []
        self.references: list[int] = []
        self.order: list[int] = []
        self.last_new = -1
        self._run()

    def ops_for(self, corner_order: int) -> list[int]:
        """The ops stream with each gate op's rotation counted for ``corner_order``."""
        ops = list(self.ops)
        for position, kind, start, smallest, n in self.gate_ops:
            rotation = start if corner_order == ROTATE_FROM_GATE else (start + smallest) % n
            ops[position] += 1 + 8 * rotation + 4 * (kind == GATE_FLIP)
        return ops

    def _tip(self, w: int, previous: int, first: int, is_first: bool) -> None:
        boundary = self.boundary
        if not self.seen[w]:
            self.seen[w] = 1
            self.ops.append(TIP_NEW)
            self.new_residuals.append(w - self.last_new - 1)
            self.last_new = w
        elif not is_first and boundary.newest_into(previous) == w:
            self.ops.append(TIP_PREV)
        elif not is_first and boundary.newest_out_of(first) == w:
            self.ops.append(TIP_NEXT)
        else:
            self.ops.append(TIP_FAR)
            self.references.append(w - previous)

    def _across(self, a: int, b: int) -> tuple[int, int, int] | None:
        """The first unvisited face, in the input's order, with the consecutive corners b, a
        (the orientation of the gate's face), else a, b: ``(face, corner where the walk starts,
        GATE_FACE or GATE_FLIP)``, or None. O(1) amortized: a visited face is popped once."""
        done = self.done
        for first, second, kind in ((b, a, GATE_FACE), (a, b, GATE_FLIP)):
            faces = self.faces_with.get(first * self.k + second)
            while faces and done[faces[-1]]:
                faces.pop()
            if faces:
                row = self.rows[faces[-1]]
                n = len(row)
                for j in range(n):  # the first such corner, as the face's corners are stored
                    if row[j] == first and row[(j + 1) % n] == second:
                        return faces[-1], j, kind
        return None

    def _visit(self, f: int) -> list[int]:
        self.done[f] = True
        self.order.append(f)
        row = self.rows[f]
        if self.polygons:
            self.degrees.append(len(row) - 3)
        return row

    def _run(self) -> None:
        rows, k, boundary = self.rows, self.k, self.boundary
        next_seed = 0
        while len(self.order) < len(rows):
            if not boundary.gates:  # a seed: the first face not visited, corners as stored
                while self.done[next_seed]:
                    next_seed += 1
                row = self._visit(next_seed)
                previous = 0
                for j, w in enumerate(row):
                    self._tip(w, previous, row[0], j == 0)
                    previous = w
                boundary.attach(list(row), 0)
                continue
            gate = boundary.gates.pop()
            if gate not in boundary.count:
                continue
            found = self._across(*divmod(gate, k))
            if found is None:
                self.ops.append(GATE_NONE)
                continue
            f, start, kind = found
            row = self._visit(f)
            n = len(row)
            cycle = [row[(start + j) % n] for j in range(n)]
            # the gate op is finished by ops_for: it takes the first tip's op in
            self.gate_ops.append((len(self.ops), kind, start, cycle.index(min(cycle)), n))
            previous = cycle[1]
            for w in cycle[2:]:
                self._tip(w, previous, cycle[0], False)
                previous = w
            boundary.attach(cycle, 1)


# ---------------------------------------------------------------------------------- decoding


def read_streams(
    payload: bytes | memoryview,
    params: Mapping[str, Any],
    count: int,
    width: int,
    vertex_count: int,
    where: str,
    limits: Limits = DEFAULT_LIMITS,
    *,
    adaptive_coding: bool = False,
    uniform_ranks: bool = False,
) -> tuple[list[list[int]], int]:
    """The four streams of a faces-traverse payload (§6.8) as lists, and ``corner_order``
    (:func:`read_stream_arrays`, whose checks it makes)."""
    arrays, corner_order = read_stream_arrays(
        payload,
        params,
        count,
        width,
        vertex_count,
        where,
        limits,
        adaptive_coding=adaptive_coding,
        uniform_ranks=uniform_ranks,
    )
    return [values.tolist() for values in arrays], corner_order


def read_stream_arrays(
    payload: bytes | memoryview,
    params: Mapping[str, Any],
    count: int,
    width: int,
    vertex_count: int,
    where: str,
    limits: Limits = DEFAULT_LIMITS,
    *,
    adaptive_coding: bool = False,
    uniform_ranks: bool = False,
) -> tuple[list[np.ndarray], int]:
    """The four streams of a faces-traverse payload (§6.8), int64 arrays, and ``corner_order``;
    the vertices stream as the walk reads it, gaps ``w - last - 1``, whichever the coder.

    In §5 step 15's order: ``corner_order``, ``coder`` (R46: 1 only where ``adaptive_coding``,
    a file with flag bit 3), where ``uniform_ranks`` (flag bit 6) ``ranks`` (R46: 1 only with
    ``coder`` 1 and at most 2**31 vertices; elsewhere an unknown parameter), the streams'
    table (:func:`_stream_table`: each entry's form, the bounds on the counts, the lengths
    against the payload), every ``planes`` (R30: 1..4, or 0 with ``coder`` 1), the bytes the
    streams decompress to (R21), then each stream (R29, or R46 for an adaptive or uniform one),
    then with ``coder`` 1 the ranks of the NEW vertices (R39). Nothing is allocated by a
    declared count before its stream is decoded.
    """
    corner_order = params.get("corner_order")
    # an int, not a float that equals 0 or 1 (§1: an int is never a float): found by the
    # JavaScript decoder, which refused a float 1.0 that this check let through
    if type(corner_order) is not int or corner_order not in (
        ROTATE_FROM_GATE,
        ROTATE_FROM_SMALLEST,
    ):
        raise _problem(
            f"{where}.corner_order", f"corner_order must be 0 or 1, got {corner_order!r}"
        )
    coder = adaptive.checked_coder(
        params.get("coder", adaptive.CODER_ZSTD),
        where,
        adaptive_coding,
        needs="flag bit 3",
    )
    ranks = _checked_ranks(params, coder, vertex_count, where) if uniform_ranks else RANKS_ADAPTIVE
    table = _stream_table(params.get("streams"), count, width, vertex_count, where)
    total = sum(length for _, _, length in table)
    if total != len(payload):
        raise _problem(
            f"{where}.streams", f"the streams take {total} bytes of a {len(payload)}-byte payload"
        )
    fields = [f"{where}.streams.{name}" for name in STREAM_NAMES]
    planes = [
        streams.checked_planes(
            {"planes": entry[1]}, field, adaptive=coder == adaptive.CODER_ADAPTIVE
        )
        for entry, field in zip(table, fields, strict=True)
    ]
    # the bytes the integers take: 32-bit ones for an adaptive stream, as §6.1's 4 planes
    raw = sum(entry[0] * (p or ADAPTIVE_PLANES) for entry, p in zip(table, planes, strict=True))
    check_limit(
        raw,
        limits,
        "max_section_bytes",
        what=f"the faces-traverse streams' {raw} bytes",
        field=f"{where}.streams",
    )
    values, offset = [], 0
    for number, ((size, _, length), p, field) in enumerate(zip(table, planes, fields, strict=True)):
        part = payload[offset : offset + length]
        values.append(_stream(part, size, p, coder, ranks, number, vertex_count, field))
        offset += length
    if coder == adaptive.CODER_ADAPTIVE:
        try:
            placed = unseen.vertices_of(values[2], vertex_count)
        except unseen.RankError as error:
            raise _broken(where, str(error)) from None
        values[2] = unseen.gaps(placed)
    return values, int(corner_order)


def _stream(
    part: bytes | memoryview,
    size: int,
    planes: int,
    coder: int,
    ranks: int,
    number: int,
    vertex_count: int,
    where: str,
) -> np.ndarray:
    """Stream ``number`` (§6.8's order) of ``size`` integers from its bytes ``part``: zstd
    planes (R29), an adaptive column (R46), or with ``ranks`` 1 the vertices' uniform stream
    (R46), whose places among the unseen are turned into ranks, their differences."""
    if number == NEW_VERTICES and ranks == RANKS_UNIFORM:
        places = uniform.decode_uniform(part, size, vertex_count, where)
        return np.diff(places, prepend=np.int64(0))
    if coder == adaptive.CODER_ADAPTIVE:
        return _adaptive_stream(part, size, where)
    return streams.unpack_integers(part, size, planes, where)


def _checked_ranks(params: Mapping[str, Any], coder: int, vertex_count: int, where: str) -> int:
    """``ranks`` of a file with flag bit 6 (format 1.9), R46 unless it is absent (0), 0, or 1
    with ``coder`` 1 and at most :data:`.uniform.MAX_TOTAL` vertices."""
    ranks = params.get("ranks", RANKS_ADAPTIVE)
    if type(ranks) is not int or ranks not in (RANKS_ADAPTIVE, RANKS_UNIFORM):
        adaptive.refuse(f"ranks must be 0 or 1, got {ranks!r}", f"{where}.ranks")
    if ranks == RANKS_UNIFORM and coder != adaptive.CODER_ADAPTIVE:
        adaptive.refuse("ranks 1 needs coder 1", f"{where}.ranks")
    if ranks == RANKS_UNIFORM and vertex_count > uniform.MAX_TOTAL:
        adaptive.refuse(
            f"ranks 1 takes at most {uniform.MAX_TOTAL} vertices, not {vertex_count}",
            f"{where}.ranks",
        )
    return int(ranks)


def _adaptive_stream(payload: bytes | memoryview, size: int, where: str) -> np.ndarray:
    """One stream of ``coder`` 1: ``size`` integers, one column of §6.14 in ascending order,
    each a 32-bit integer (R46). The payload's bound (R46) is checked before the coding order,
    whose arrays are ``size`` long, is made."""
    adaptive.check_expansion(size, len(payload), where)
    order = adaptive.sequence_order(size)
    return adaptive.decode_within_planes(payload, 1, size, ADAPTIVE_PLANES, order, where)[0]


def _stream_table(
    table: object, count: int, width: int, vertex_count: int, where: str
) -> list[tuple[int, int, int]]:
    """``streams``: four ``[count, planes, length]`` arrays of ints >= 0, whose counts keep
    §6.8's bounds (R39). A walk of ``count`` faces reads every value of every stream, and never
    more than the bounds allow, so a file that breaks one fails here, before its streams are
    decompressed, rather than in the walk."""
    if not isinstance(table, list) or len(table) != len(STREAM_NAMES):
        raise _problem(
            f"{where}.streams",
            f"streams must be an array of {len(STREAM_NAMES)} [count, planes, bytes] arrays",
        )
    for name, entry in zip(STREAM_NAMES, table, strict=True):
        if (
            not isinstance(entry, list)
            or len(entry) != 3
            or not all(isinstance(n, int) and not isinstance(n, bool) and n >= 0 for n in entry)
        ):
            raise _problem(
                f"{where}.streams.{name}",
                "each stream is described by [count, planes, bytes], ints >= 0",
            )
    ops, degrees, news, references = (entry[0] for entry in table)
    corners = count * (3 if degrees == 0 else width)  # at most: 3 corners without degrees
    problem = None
    if degrees not in (0, count):
        problem = "degrees", f"{degrees} degrees for {count} faces: one each, or none"
    elif not count <= ops <= 2 * corners:
        problem = "ops", f"{ops} ops, outside the {count}..{2 * corners} that {count} faces read"
    elif news > vertex_count:
        problem = "vertices", f"{news} new vertices, more than the {vertex_count} there are"
    elif news + references > corners:
        detail = f"{news} new vertices and {references} references, more than {corners} corners"
        problem = "references", detail
    if problem is not None:
        name, detail = problem
        raise _problem(f"{where}.streams.{name}", f"the streams declare {detail} (§6.8)")
    return [(entry[0], entry[1], entry[2]) for entry in table]


def decode_traversal(
    payload: bytes | memoryview,
    params: Mapping[str, Any],
    vertex_count: int,
    where: str,
    limits: Limits = DEFAULT_LIMITS,
    *,
    adaptive_coding: bool = False,
    uniform_ranks: bool = False,
) -> np.ndarray:
    """The (M, n) faces of a FACE section with codec faces-traverse (§6.8), in walk order.

    In §5 step 15's order: the streams' table is checked and the streams read
    (:func:`read_stream_arrays`), then the walk rebuilds the faces from them
    (:func:`walk_streams`). The walk's state grows with the values it reads; the (M, n) table is
    made once M faces are decoded. ``adaptive_coding``: the file sets flag bit 3, so that
    ``coder`` may be 1; ``uniform_ranks``: flag bit 6, so that ``ranks`` may be 1.
    """
    count, width = section_shape(params, where, min_cols=3)
    arrays, corner_order = read_stream_arrays(
        payload,
        params,
        count,
        width,
        vertex_count,
        where,
        limits,
        adaptive_coding=adaptive_coding,
        uniform_ranks=uniform_ranks,
    )
    return walk_streams(arrays, count, width, vertex_count, corner_order, where)


def walk_streams(
    arrays: list[np.ndarray], count: int, width: int, k: int, corner_order: int, where: str
) -> np.ndarray:
    """The (count, width) faces the walk decodes from the four int64 streams ``arrays``, or
    R39-traversal. The compiled core's walk runs where it is installed and the values fit its
    int64 (K) and u32 (edges) counts; else a table of triangles (no degrees) is walked by
    :func:`_walk_triangles`, any other by :func:`_walk`, which holds every case of §6.8 and is
    the reference both are tested against (same faces, same first error)."""
    core = native.core()
    if core is not None and 0 <= k < 1 << 62 and sum(a.size for a in arrays) <= 1 << 30:
        try:
            faces: np.ndarray = core.decode_traversal(arrays, count, width, k, corner_order)
        except core.Broken as error:
            raise _broken(where, error.args[1]) from None
        return faces
    try:
        if not arrays[1].size:
            return _walk_triangles(arrays, count, width, k, corner_order, where)
        values = [stream.tolist() for stream in arrays]
        rows = _walk(values, count, width, k, corner_order, where)
    except StopIteration:  # a stream read past its end
        raise _broken(where, "a stream ends early") from None
    return _padded(rows, count, width)


def _padded(rows: list[list[int]], count: int, width: int) -> np.ndarray:
    """The (count, width) table of ``rows``, padded with -1."""
    lengths = np.fromiter((len(row) for row in rows), dtype=np.int64, count=count)
    flat = np.fromiter((v for row in rows for v in row), dtype=np.int64, count=int(lengths.sum()))
    out = np.full((count, width), -1, dtype=np.int64)
    out[np.arange(width)[None, :] < lengths[:, None]] = flat  # row-major: each row's corners
    return out


def _new_vertices(residuals: np.ndarray, k: int) -> tuple[list[int | None], int]:
    """The vertex of each NEW tip in turn, ``last + 1 + r`` (§6.8), all at once by a running
    sum: ``(vertices, bad)``. Up to the first vertex outside 0..k-1 or placed before, the sum is
    the walk's ``last`` (it moves on only by good vertices); there the walk must fail, so the
    list stops, ends in ``None`` and ``bad`` is that vertex (-1 if every one is good)."""
    placed = np.cumsum(residuals + 1) - 1  # |r| < 2**32 and at most 2**31 of them: no wrap
    repeated = np.ones(placed.size, dtype=bool)
    repeated[np.unique(placed, return_index=True)[1]] = False  # a copy of an earlier value
    problems = np.flatnonzero(repeated | (placed < 0) | (placed >= k))
    if not problems.size:
        return placed.tolist(), -1
    stop = int(problems[0])
    vertices: list[int | None] = list(placed[:stop].tolist())
    vertices.append(None)
    return vertices, int(placed[stop])


class _TriangleWalk:
    """The state of :func:`_walk_triangles` and its rarer steps: the streams being read, the
    boundary (_Boundary's count, into and out_of), the gates, and each face's corners and code.
    The walk's loop binds what it uses most to locals."""

    def __init__(self, arrays: list[np.ndarray], k: int, where: str) -> None:
        self.k, self.where = k, where
        self.placed, self.bad = _new_vertices(arrays[2], k)
        self.op_source, self.new_source = iter(arrays[0].tolist()), iter(self.placed)
        self.reference_source = iter(arrays[3].tolist())
        self.next_op, self.next_new = self.op_source.__next__, self.new_source.__next__
        self.next_reference = self.reference_source.__next__
        self.open_edges: dict[int, int] = {}
        self.into: defaultdict[int, list[int]] = defaultdict(list)
        self.out_of: defaultdict[int, list[int]] = defaultdict(list)
        self.gates: list[int] = []
        self.corners: list[int] = []  # each face's corners in walk order (c0, c1, c2)
        self.codes: list[int] = []  # each face's gate op - 1, -1 for a seed
        self.known: dict[int, int] = {}  # vertex -> its turn among NEW tips, made at first FAR

    def new_vertex(self) -> int:
        w = self.next_new()
        if w is None:
            raise _broken(self.where, f"new vertex {self.bad} is outside 0..{self.k - 1} or placed")
        return w

    def far(self, previous: int) -> int:
        w = previous + self.next_reference()
        placed, known = self.placed, self.known
        if not known:  # placed's vertices are distinct up to its end or None
            good = placed[: len(placed) - (self.bad >= 0)]
            known.update(zip(good, range(len(good)), strict=True))  # type: ignore[arg-type]
        turn = known.get(w)  # seen: placed by a NEW tip read so far
        if turn is None or turn >= len(placed) - operator.length_hint(self.new_source):
            raise _broken(self.where, f"referenced vertex {w} is not one seen before")
        return w

    def newest(self, tip: int, vertex: int) -> int:
        """PREV (the newest open u -> vertex) or NEXT (vertex -> w)."""
        stack = self.into.get(vertex) if tip == TIP_PREV else self.out_of.get(vertex)
        while stack and stack[-1] not in self.open_edges:
            stack.pop()
        if not stack:
            raise _broken(self.where, f"tip operation {tip} names no vertex here")
        return stack[-1] // self.k if tip == TIP_PREV else stack[-1] % self.k

    def join(self, x: int, y: int) -> int:
        """One edge x -> y of a face added to the boundary (_Boundary.attach); its key."""
        open_edges, k = self.open_edges, self.k
        opposite, key = y * k + x, x * k + y
        open_count = open_edges.get(opposite)
        if not open_count:
            if key in open_edges:
                open_edges[key] += 1
            else:
                open_edges[key] = 1
                self.into[y].append(key)
                self.out_of[x].append(key)
        elif open_count == 1:
            del open_edges[opposite]
        else:
            open_edges[opposite] = open_count - 1
        return key

    def seed(self) -> None:
        """A face no gate reaches: three tips, each with the next op; every edge a gate."""
        cycle: list[int] = []
        previous = 0
        while len(cycle) < 3:
            tip = self.next_op()
            if tip == TIP_NEW:
                w = self.new_vertex()
            elif tip == TIP_FAR:
                w = self.far(previous)
            elif cycle and tip in (TIP_PREV, TIP_NEXT):
                w = self.newest(tip, previous if tip == TIP_PREV else cycle[0])
            else:
                raise _broken(self.where, f"tip operation {tip} names no vertex here")
            cycle.append(w)
            previous = w
        for x, y in zip(cycle, cycle[1:] + cycle[:1], strict=True):
            self.gates.append(self.join(x, y))
        self.corners.extend(cycle)
        self.codes.append(-1)

    def check_ends(self) -> None:
        """Every stream read to its end (there is no degrees stream for triangles)."""
        sources = (self.op_source, iter(()), self.new_source, self.reference_source)
        for name, source in zip(STREAM_NAMES, sources, strict=True):
            if operator.length_hint(source):
                raise _broken(self.where, f"stream {name} has values left, or ends early")


def _walk_triangles(
    arrays: list[np.ndarray], count: int, width: int, k: int, corner_order: int, where: str
) -> np.ndarray:
    """:func:`_walk` for a table of triangles (no degrees stream), its loop cut to what is
    sequential; numpy places the NEW vertices before it and turns the faces after it. A NEW tip
    across an unflipped gate, the common face, is decoded inline; the rest call
    :class:`_TriangleWalk`. Same values read in the same order, same checks and errors."""
    walk = _TriangleWalk(arrays, k, where)
    next_op, next_new, bad = walk.next_op, walk.next_new, walk.bad
    far, join, seed, newest = walk.far, walk.join, walk.seed, walk.newest
    open_edges, into, out_of, gates = walk.open_edges, walk.into, walk.out_of, walk.gates
    open_count_of, pop_gate, push_gate = open_edges.get, gates.pop, gates.append
    corners, add_code = walk.corners, walk.codes.append
    top, faces = 8 * width, 0
    while faces < count:
        if not gates:
            seed()
            faces += 1
            continue
        gate = pop_gate()
        gate_count = open_count_of(gate)
        # a gate closed since it was pushed reads no op; GATE_NONE: no face across it
        if not gate_count or not (op := next_op()):
            continue
        if not 0 < op <= top:
            raise _broken(where, f"gate operation {op} is outside 0..{top}")
        op -= 1  # rotation * 8 + 4 * flipped + first tip
        a, b = divmod(gate, k)
        first, previous = (a, b) if op & 4 else (b, a)
        tip = op & 3
        if tip == 0:  # TIP_NEW, the most common
            w = next_new()
            if w is None:
                raise _broken(where, f"new vertex {bad} is outside 0..{k - 1} or placed")
            if first != previous:  # w is on no edge yet: neither of its two can be open
                if op >= 24:
                    raise _broken(where, f"rotation {op >> 3} of a face of 3 corners")
                if op & 4:  # _Boundary.attach written out: first -> previous, no gate
                    join(first, previous)
                elif gate_count == 1:  # ... closes the gate
                    del open_edges[gate]
                else:
                    open_edges[gate] = gate_count - 1
                # previous -> w and w -> first open, both gates (were first the same vertex
                # as previous, the second would close the first: that goes the general way)
                key, after = previous * k + w, w * k + first
                open_edges[key] = open_edges[after] = 1
                into[w] = [key]
                out_of[w] = [after]
                out_of[previous].append(key)
                into[first].append(after)
                push_gate(key)
                push_gate(after)
                corners += (first, previous, w)
                add_code(op)
                faces += 1
                continue
        elif tip == 3:  # TIP_FAR
            w = far(previous)
        else:  # TIP_PREV (the newest open u -> previous) or TIP_NEXT (first -> w)
            w = newest(tip, previous if tip == TIP_PREV else first)
        if op >= 24:
            raise _broken(where, f"rotation {op >> 3} of a face of 3 corners")
        # the edge first -> previous closes the gate (flipped: joins it, no gate); the edges
        # previous -> w and w -> first are gates
        if op & 4:
            join(first, previous)
        elif gate_count == 1:
            del open_edges[gate]
        else:
            open_edges[gate] = gate_count - 1
        push_gate(join(previous, w))
        push_gate(join(w, first))
        corners += (first, previous, w)
        add_code(op)
        faces += 1
    walk.check_ends()
    return _stored(corners, walk.codes, count, width, corner_order)


def _stored(
    corners: list[int], codes: list[int], count: int, width: int, corner_order: int
) -> np.ndarray:
    """The stored triangles, padded to ``width``: each walked face turned by its rotation
    (§6.8 step 2) as :func:`_walk` turns it, a seed (code -1) as it is."""
    # fromiter: faster than np.array on a list of ints, which first looks for nested lists
    cycles = np.fromiter(corners, dtype=np.int64, count=3 * count).reshape(count, 3)
    code = np.fromiter(codes, dtype=np.int64, count=count)
    walked = code >= 0
    offset = np.where(walked, code >> 3, 0)
    if corner_order == ROTATE_FROM_SMALLEST:
        offset -= np.where(walked, cycles.argmin(axis=1), 0)  # argmin: the first smallest
    # stored[(offset + j) % 3] = cycle[j], so stored[i] = cycle[(i - offset) % 3]
    take = np.arange(0, 3 * count, 3)[:, None] + (np.arange(3)[None, :] - offset[:, None]) % 3
    turned = cycles.reshape(-1)[take]
    if width == 3:
        return turned
    out = np.full((count, width), -1, dtype=np.int64)
    out[:, :3] = turned
    return out


def _walk(
    values: list[list[int]], count: int, width: int, k: int, corner_order: int, where: str
) -> list[list[int]]:
    """The ``count`` stored faces the walk decodes from the streams ``values``, in walk order,
    spending each (StopIteration where one ends early). A face starts at a gate or a seed, takes
    its tips, turns to its stored rotation and joins the boundary: one loop, inline, since a call
    per value would double its time. Polygons are decoded by it; triangles by the faster
    :func:`_walk_triangles`, tested to give the same faces and errors."""
    polygons = bool(values[1])
    sources = [iter(source) for source in values]
    ops, degrees, new_residuals, references = sources
    seen: set[int] = set()  # not a table of k entries: k is the header's claim (see _Boundary)
    boundary = _Boundary(k)
    gates, into, out_of, open_edges = boundary.gates, boundary.into, boundary.out_of, boundary.count
    last_new = -1
    rows: list[list[int]] = []  # the stored faces, in walk order
    while len(rows) < count:
        if gates:
            gate = gates.pop()
            # a gate closed since it was pushed reads no op; GATE_NONE: no face across it
            if gate not in open_edges or (op := next(ops)) == GATE_NONE:
                continue
            if not 1 <= op <= 8 * width:
                raise _broken(where, f"gate operation {op} is outside 0..{8 * width}")
            rotation, rest = divmod(op - 1, 8)
            a, b = divmod(gate, k)
            cycle = [a, b] if rest >= 4 else [b, a]
            tip_op, first_gate = rest & 3, 1
        else:  # a seed: every corner is a tip
            cycle, tip_op, rotation, first_gate = [], next(ops), 0, 0
        n = 3 + next(degrees) if polygons else 3
        if not 3 <= n <= width:
            raise _broken(where, f"a face of {n} corners in a table of width {width}")
        previous = cycle[-1] if cycle else 0
        while len(cycle) < n:
            if tip_op == TIP_NEW:
                w = last_new + 1 + next(new_residuals)
                if not 0 <= w < k or w in seen:
                    raise _broken(where, f"new vertex {w} is outside 0..{k - 1} or placed")
                seen.add(w)
                last_new = w
            elif tip_op == TIP_FAR:
                w = previous + next(references)
                if not 0 <= w < k or w not in seen:
                    raise _broken(where, f"referenced vertex {w} is not one seen before")
            elif cycle and tip_op in (TIP_PREV, TIP_NEXT):
                # the newest open edge into the previous corner, or out of the first: closed
                # ones on top are popped for good (_newest, written out)
                stack = into.get(previous) if tip_op == TIP_PREV else out_of.get(cycle[0])
                while stack and stack[-1] not in open_edges:
                    stack.pop()
                if not stack:
                    raise _broken(where, f"tip operation {tip_op} names no vertex here")
                w = stack[-1] // k if tip_op == TIP_PREV else stack[-1] % k
            else:
                raise _broken(where, f"tip operation {tip_op} names no vertex here")
            cycle.append(w)
            previous = w
            if len(cycle) < n:
                tip_op = next(ops)
        if rotation >= n:
            raise _broken(where, f"rotation {rotation} of a face of {n} corners")
        offset = rotation
        if corner_order == ROTATE_FROM_SMALLEST and first_gate:
            offset -= cycle.index(min(cycle))
        offset %= n  # stored[(offset + j) % n] = cycle[j]: cycle turned right by offset
        rows.append(cycle[n - offset :] + cycle[: n - offset] if offset else cycle)
        # _Boundary.attach written out: a call per face costs 10 % of the decoder's time (the
        # round-trip tests hold the two to the same rule); new edges, the most, tested first
        for j, (x, y) in enumerate(zip(cycle, cycle[1:] + cycle[:1], strict=True)):
            opposite, key = y * k + x, x * k + y
            open_count = open_edges.get(opposite)
            if not open_count:
                if key in open_edges:
                    open_edges[key] += 1
                else:  # x -> y becomes open: the newest entry of both ends
                    open_edges[key] = 1
                    into[y].append(key)
                    out_of[x].append(key)
            elif open_count == 1:  # y -> x is closed: its entries in into(x), out(y) go stale
                del open_edges[opposite]
            else:
                open_edges[opposite] = open_count - 1
            if j >= first_gate:
                gates.append(key)
    _check_spent(sources, where)
    return rows


def _check_spent(sources: list[Iterator[int]], where: str) -> None:
    """R39-traversal unless the walk read every value of the four streams."""
    for name, stream in zip(STREAM_NAMES, sources, strict=True):
        if next(stream, None) is not None:
            raise _broken(where, f"stream {name} has values left, or ends early")


def _broken(where: str, detail: str) -> FormatError:
    """R39-traversal for a walk that cannot go on: ``the traversal breaks: {detail}``."""
    return _problem(where, f"the traversal breaks: {detail}")


def _problem(field: str, message: str) -> FormatError:
    """The one home of R39-traversal: ``field`` names the section or its parameter."""
    return FormatError(message, rule="R39-traversal", field=field)
