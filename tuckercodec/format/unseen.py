"""§6.8 with ``coder`` 1 (format 1.6): a NEW tip's vertex as its signed rank among the unseen.

With ``coder`` 0 a NEW vertex w is stored as ``w - last - 1``, its gap to the last new vertex:
every vertex placed in between is paid for again. With ``coder`` 1 it is stored as its rank
``r = u(w) - u(last)`` among the vertices not seen yet, where u(x) counts the unseen vertices
below x (u = 0 while ``last`` is -1): ``r >= 0`` is w's place among the unseen above ``last``
(0 for the first of them), ``r < 0`` among those below (-1 for the nearest). Where the walk
runs along the file's order, most gaps are across vertices already placed, and their ranks are
small.

w keeps its u(w) unseen vertices below it once it is placed, so u of each new vertex is the
running sum of the ranks: the decoder needs only the unseen vertex with t unseen below it, and
the encoder only how many placed vertices lie below w. A Fenwick tree over the placed vertices
answers both in O(log K). The conversion depends on the ranks alone, not on the walk, so it runs
before the walk, which then reads gaps as with ``coder`` 0.

The compiled core has the same two loops (``tuckercodec/native/core/src/traversal/ranks.rs``);
the Python here is their reference and fallback, tested to give the same values and errors.
"""

from __future__ import annotations

import numpy as np

from ..system import native

#: The largest vertex count the compiled core takes (its counts are int64).
MAX_NATIVE_K = 1 << 62


class RankError(ValueError):
    """A rank that names no unseen vertex; its message is the detail of R39-traversal."""


class PlacedVertices:
    """The vertices placed so far among ``0..k-1``: a Fenwick tree of their counts.

    Its nodes are a dict filled as vertices are placed, not a table of k entries: k is the
    header's claim, not yet checked against anything when FACE is decoded, and must not size
    an allocation (about log2 k nodes per vertex placed).
    """

    def __init__(self, k: int) -> None:
        self.top = 1 << max(k - 1, 0).bit_length()  # a power of two >= k, for the descent
        self.tree: dict[int, int] = {}

    def place(self, v: int) -> None:
        """Mark vertex ``v`` (unplaced, in 0..k-1) as placed."""
        tree, i = self.tree, v + 1
        while i <= self.top:
            tree[i] = tree.get(i, 0) + 1
            i += i & -i

    def below(self, x: int) -> int:
        """How many placed vertices are below ``x``."""
        tree, total = self.tree, 0
        while x > 0:
            total += tree.get(x, 0)
            x &= x - 1
        return total

    def unplaced(self, t: int) -> int:
        """The unplaced vertex with exactly ``t`` unplaced vertices below it (``0 <= t`` and
        fewer than the unplaced vertices): the binary descent of a Fenwick tree."""
        tree, position, step = self.tree, 0, self.top
        while step:
            node = position + step
            free = step - tree.get(node, 0)  # unplaced vertices in position..node-1
            if free <= t:
                position, t = node, t - free
            step >>= 1
        return position


def ranks_of(vertices: np.ndarray, k: int) -> np.ndarray:
    """The rank of each NEW vertex (distinct, in 0..k-1, in the walk's order) among the unseen
    vertices, int64. By the compiled core where it is installed, else :func:`_ranks_python`."""
    placed = np.ascontiguousarray(vertices, dtype=np.int64)
    core = native.core()
    if core is not None and 0 <= k <= MAX_NATIVE_K:
        ranks: np.ndarray | None = core.unseen_ranks(placed, k)
        if ranks is not None:  # None: a vertex outside 0..k-1, which no walk places
            return ranks
    return _ranks_python(placed, k)


def _ranks_python(vertices: np.ndarray, k: int) -> np.ndarray:
    """:func:`ranks_of` one vertex at a time: the reference."""
    tree = PlacedVertices(k)
    ranks, before = [], 0
    for w in vertices.tolist():
        t = w - tree.below(w)  # u(w): the unseen vertices below w
        ranks.append(t - before)
        tree.place(w)
        before = t
    return np.array(ranks, dtype=np.int64)


def vertices_of(ranks: np.ndarray, k: int) -> np.ndarray:
    """The NEW vertices, in turn, that the ``ranks`` name among ``0..k-1`` (int64), or
    :class:`RankError` at the first rank that names no unseen vertex. By the compiled core
    where it is installed, else :func:`_vertices_python`: the same vertices or error."""
    values = np.ascontiguousarray(ranks, dtype=np.int64)
    core = native.core()
    if core is not None and 0 <= k <= MAX_NATIVE_K:
        try:
            vertices: np.ndarray = core.unseen_vertices(values, k)
        except core.Broken as error:
            raise RankError(error.args[1]) from None
        return vertices
    return _vertices_python(values, k)


def _vertices_python(ranks: np.ndarray, k: int) -> np.ndarray:
    """:func:`vertices_of` one rank at a time: the reference."""
    tree = PlacedVertices(k)
    vertices, t = [], 0
    for placed, r in enumerate(ranks.tolist()):
        t += r  # u(w) of the vertex named: the running sum of the ranks
        if not 0 <= t < k - placed:
            raise RankError(f"new vertex rank {r} names no unseen vertex")
        w = tree.unplaced(t)
        tree.place(w)
        vertices.append(w)
    return np.array(vertices, dtype=np.int64)


def gaps(vertices: np.ndarray) -> np.ndarray:
    """The NEW vertices as ``coder`` 0 stores them: ``w - last - 1``, last -1 at the start."""
    return np.diff(vertices, prepend=np.int64(-1)) - 1


def vertices_from_gaps(residuals: np.ndarray) -> np.ndarray:
    """The inverse of :func:`gaps` (for residuals of a walk, whose vertices are distinct)."""
    return np.cumsum(np.asarray(residuals, dtype=np.int64) + 1) - 1
