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
  follows the surface);
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

The decoder is one pass in Python over the faces, on integers in lists and dicts; the encoder
runs the same walk with the mesh to answer each question. Both share :class:`_Boundary`.
"""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Iterator, Mapping
from typing import Any

import numpy as np

from ..errors import FormatError
from . import streams
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
#: ``corner_order``: the rotation is the position in the stored face of the walk's first corner
#: (0), or of the face's smallest vertex index (1).
ROTATE_FROM_GATE, ROTATE_FROM_SMALLEST = 0, 1


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
    faces: np.ndarray, vertex_count: int, level: int = streams.DEFAULT_LEVEL
) -> tuple[dict[str, Any], bytes, np.ndarray]:
    """``(params, payload, faces in walk order)`` of a FACE section with codec faces-traverse.

    The encoder tries both corner orders and keeps the smaller. The faces it returns are the
    ones a decoder gives back: the same rows, corners and orientation, in the walk's order.
    """
    table = np.asarray(faces, dtype=np.int64)
    count, width = table.shape if table.ndim == 2 and table.size else (0, 3)
    rows = [[v for v in row if v >= 0] for row in table.tolist()]
    walk = _Walk(rows, vertex_count)
    best: tuple[dict[str, Any], bytes] | None = None
    for corner_order in (ROTATE_FROM_GATE, ROTATE_FROM_SMALLEST):
        coded = [walk.ops_for(corner_order), walk.degrees, walk.new_residuals, walk.references]
        params, payload = pack_streams(coded, count, width, corner_order, level)
        if best is None or len(payload) < len(best[1]):
            best = params, payload
    assert best is not None
    walked = table[walk.order] if count else np.zeros((0, width), dtype=np.int64)
    return best[0], best[1], walked


def pack_streams(
    coded: list[list[int]], count: int, width: int, corner_order: int, level: int
) -> tuple[dict[str, Any], bytes]:
    """``(params, payload)`` of the four streams ``coded`` (ops, degrees, vertices, references)."""
    parts, table = [], []
    for values in coded:
        payload, planes = streams.pack_integers(np.asarray(values, dtype=np.int64), level)
        parts.append(payload)
        table.append([len(values), planes, len(payload)])
    params = {"shape": [count, width], "corner_order": corner_order, "streams": table}
    return params, b"".join(parts)


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
) -> tuple[list[list[int]], int]:
    """The four streams of a faces-traverse payload (§6.8), and ``corner_order``.

    In §5 step 15's order: ``corner_order``, the streams' table (:func:`_stream_table`: each
    entry's form, the bounds on the counts, the lengths against the payload), every ``planes``
    (R30), the bytes the streams decompress to (R21), then each stream. Nothing is allocated by a
    declared count before its stream is decompressed.
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
    table = _stream_table(params.get("streams"), count, width, vertex_count, where)
    total = sum(length for _, _, length in table)
    if total != len(payload):
        raise _problem(
            f"{where}.streams", f"the streams take {total} bytes of a {len(payload)}-byte payload"
        )
    fields = [f"{where}.streams.{name}" for name in STREAM_NAMES]
    planes = [
        streams.checked_planes({"planes": entry[1]}, field)
        for entry, field in zip(table, fields, strict=True)
    ]
    raw = sum(entry[0] * p for entry, p in zip(table, planes, strict=True))
    check_limit(
        raw,
        limits,
        "max_section_bytes",
        what=f"the faces-traverse streams' {raw} bytes",
        field=f"{where}.streams",
    )
    values, offset = [], 0
    for (size, _, length), p, field in zip(table, planes, fields, strict=True):
        values.append(
            streams.unpack_integers(payload[offset : offset + length], size, p, field).tolist()
        )
        offset += length
    return values, int(corner_order)


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
) -> np.ndarray:
    """The (M, n) faces of a FACE section with codec faces-traverse (§6.8), in walk order.

    In §5 step 15's order: the streams' table is checked and the streams read
    (:func:`read_streams`), then the walk rebuilds the faces from them (:func:`_walk`). The walk's
    state grows with the values it reads; the (M, n) table is made once M faces are decoded.
    """
    count, width = section_shape(params, where, min_cols=3)
    values, corner_order = read_streams(payload, params, count, width, vertex_count, where, limits)
    try:
        rows = _walk(values, count, width, vertex_count, corner_order, where)
    except StopIteration:  # a stream read past its end
        raise _broken(where, "a stream ends early") from None
    if width == 3:
        return np.array(rows, dtype=np.int64).reshape(count, 3)
    out = np.full((count, width), -1, dtype=np.int64)
    for row, stored in zip(out, rows, strict=True):
        row[: len(stored)] = stored
    return out


def _walk(
    values: list[list[int]], count: int, width: int, k: int, corner_order: int, where: str
) -> list[list[int]]:
    """The ``count`` stored faces the walk decodes from the streams ``values``, in walk order,
    spending each (StopIteration where one ends early). A face starts at a gate or a seed, takes
    its tips, turns to its stored rotation and joins the boundary: one loop, inline, since a call
    per value would double its time (samba's 19,938 triangles take about 40 ms)."""
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
