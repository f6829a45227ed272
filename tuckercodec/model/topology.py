"""The face table and what follows from it: its validity rule, its edges, and the mesh parents.

Every part of the package that holds faces uses the one representation of
:class:`~tuckercodec.MeshSequence`: an (M, n) integer array of 0-based vertex indices, where a
polygon with fewer corners than the widest face is padded with -1 at the end of its row. This
module is the one home of its rules:

* :func:`face_table_problem`: indices in -1..K-1, -1 only after a row's real corners, at least
  3 real corners per row (``spec/FORMAT.md`` §6.4 for the FACE section; the in-memory sequence,
  the readers and the metrics apply the same rule);
* :func:`face_edges` and :func:`mesh_edges`: consecutive corners, and the last real corner back
  to the first (a quad has 4 edges and no diagonal);
* :func:`mesh_parents`: the breadth-first spanning forest of the edges that predicts U1's rows
  (``spec/FORMAT.md`` §6.2).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from typing import Any, Literal

import numpy as np

from ..errors import InputError
from ..system import native

#: The parent of a vertex that has none (a root of the forest, or a vertex on no face).
NO_PARENT = -1


@dataclass(frozen=True)
class FaceTableProblem:
    """The first way a face table breaks the rule: ``kind`` is ``"index"`` (an index outside
    -1..K-1) or ``"padding"`` (-1 before a real corner, or fewer than 3 real corners)."""

    kind: Literal["index", "padding"]
    row: int
    message: str


def face_table_problem(faces: np.ndarray, vertex_count: int) -> FaceTableProblem | None:
    """The first problem of an (M, n) integer face table, or ``None`` if it follows the rule.

    Indices are checked first over the whole table, then the padding. Any integer dtype works:
    the range is checked before any cast, so a uint64 2**64 - 1 is out of range, not padding.
    """
    if faces.size == 0:
        return None
    outside = (faces >= vertex_count) | (faces < -1)
    if outside.any():
        row, column = (int(n) for n in np.argwhere(outside)[0])
        return FaceTableProblem(
            "index",
            row,
            f"face {row} has a vertex index {int(faces[row, column])} outside "
            f"0..{vertex_count - 1}: {faces[row].tolist()}",
        )
    padded = faces < 0
    if not padded.any():
        return None
    misplaced = (padded[:, :-1] & ~padded[:, 1:]).any(axis=1) | ((~padded).sum(axis=1) < 3)
    if not misplaced.any():
        return None
    row = int(np.flatnonzero(misplaced)[0])
    return FaceTableProblem(
        "padding",
        row,
        f"face {row} is padded before its end or has fewer than 3 corners: {faces[row].tolist()}",
    )


def checked_face_table(faces: object, vertex_count: int) -> np.ndarray:
    """``faces`` as a C-contiguous (M, n) int64 table that follows the rule; an empty table
    becomes (0, 3). Raises :class:`InputError` naming the first face at fault."""
    table = np.asarray(faces)
    if table.size == 0:
        return np.zeros((0, 3), dtype=np.int64)
    if table.ndim != 2 or table.shape[1] < 3:
        raise InputError(f"faces must have shape (faces, n >= 3), got {table.shape}")
    if not np.issubdtype(table.dtype, np.integer):
        raise InputError(f"faces must be integers, got dtype {table.dtype}")
    problem = face_table_problem(table, vertex_count)
    if problem is not None:
        raise InputError(problem.message)
    return np.ascontiguousarray(table, dtype=np.int64)


def face_edges(faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The edges of every face, ``(a, b)`` index arrays: consecutive corners, and the last
    corner back to the first. Rows padded with -1 close at their last real corner. An edge
    shared by two faces appears twice, and a degenerate face's ``a == b`` edges are kept."""
    faces = np.asarray(faces, dtype=np.int64)
    if faces.size == 0:
        empty = np.zeros(0, dtype=np.int64)
        return empty, empty
    width = faces.shape[1]
    starts, ends = [], []
    for corner in range(width):
        a = faces[:, corner]
        b = faces[:, corner + 1] if corner + 1 < width else faces[:, 0]
        b = np.where(b < 0, faces[:, 0], b)  # padding follows the last corner: close the polygon
        keep = a >= 0
        starts.append(a[keep])
        ends.append(b[keep])
    return np.concatenate(starts), np.concatenate(ends)


def mesh_edges(faces: object, vertex_count: int) -> np.ndarray:
    """The unique undirected edges of ``faces``, (E, 2) int64 with ``a < b``, sorted.

    Edges from a vertex to itself (a face that repeats a corner) are dropped. Raises
    :class:`InputError` for a face table that breaks the rule.
    """
    table = checked_face_table(faces, vertex_count)
    if table.size == 0:
        return np.zeros((0, 2), dtype=np.int64)
    a, b = face_edges(table)
    keep = a != b
    low, high = np.minimum(a, b)[keep], np.maximum(a, b)[keep]
    keys = np.unique(low * np.int64(vertex_count) + high)  # one integer per edge: fast unique
    return np.stack([keys // vertex_count, keys % vertex_count], axis=1)


def mesh_parents(faces: np.ndarray, vertex_count: int) -> np.ndarray:
    """``parent[v]`` in the breadth-first forest of the face edges, or -1 (``spec/FORMAT.md``
    §6.2): for each vertex s in index order not yet reached, s is a root, and a first-in-first-out
    walk from s visits each dequeued vertex's neighbours in ascending index order; a vertex's
    parent is the vertex it was first reached from.

    Of the simple rules tried on the shared sequences this was the most robust: "the largest
    earlier neighbour" was 7 % smaller on chicken but 12 % larger on the cloth, whose vertex
    order leaves a fifth of the vertices without an earlier neighbour.
    """
    core = native.core()
    if core is not None:
        parents: np.ndarray = _native_forest(core, faces, vertex_count).parents()
        return parents
    return _mesh_forest(faces, vertex_count).parents(vertex_count)


def _native_forest(core: Any, faces: np.ndarray, vertex_count: int) -> Any:
    """The compiled core's forest (the same walk as :func:`_mesh_forest`, over every vertex)."""
    table = np.asarray(faces, dtype=np.int64)
    if table.ndim != 2:
        table = table.reshape(0, 0)  # an empty table: no edges
    return core.MeshForest(np.ascontiguousarray(table), vertex_count)


#: Predictor 2's phases: a vertex's rank among the vertices of its depth, in the order of the
#: walk, modulo this; a vertex is also predicted from its neighbours of the same depth and a
#: lower phase (``spec/FORMAT.md`` §6.2). More phases give a vertex more decoded neighbours:
#: 8 rather than 2 made U1 1-3 % smaller on the shared sequences (whole files 0.9-2.7 %) for a
#: few ms more of decoding (samba: 72 -> 76 ms to open at KG 0.1).
MEAN_PHASES = 8
#: The deepest forest predictor 2 may be used on (levels, the roots' included): restoring it
#: costs a step per phase and level (at most 16,384 steps), so a strip of faces would be slow.
MAX_MEAN_LEVELS = 2048


@dataclass(frozen=True)
class MeanSteps:
    """The order and sources of predictor 2 (``spec/FORMAT.md`` §6.2), for one mesh.

    ``rows`` lists every vertex of depth >= 1 by (depth, phase, walk order); step s restores
    ``rows[step_ends[s]:step_ends[s + 1]]`` (depth 1 + s // MEAN_PHASES, phase s % MEAN_PHASES;
    a step may be empty). Row j's *sources* (its parent among them, so at least one) are
    ``sources[source_ends[j]:source_ends[j + 1]]``, each with its *anchor* (the source's parent
    for a source one level up that has one, else the source itself) in ``anchors``.
    """

    rows: np.ndarray  # (R,) int64
    step_ends: np.ndarray  # (steps + 1,) int64
    sources: np.ndarray  # (E,) int64
    anchors: np.ndarray  # (E,) int64
    source_ends: np.ndarray  # (R + 1,) int64
    levels: int  # depths, 0 included
    #: the compiled core's plan of these steps, when it made them
    plan: Any = field(default=None, compare=False, repr=False)

    @property
    def counts(self) -> np.ndarray:
        """Each row's number of sources (at least 1)."""
        return np.diff(self.source_ends)

    def native_plan(self) -> Any:
        """The compiled core's ``MeanPlan`` of these steps (made from the arrays once)."""
        return self.plan if self.plan is not None else self._made_plan

    @cached_property
    def _made_plan(self) -> Any:
        core = native.core()
        assert core is not None, "only the compiled core restores with a plan"
        return core.MeanPlan(
            self.rows,
            self.step_ends,
            self.sources,
            self.anchors,
            self.source_ends,
            int(max(a.max(initial=-1) for a in (self.rows, self.sources, self.anchors))) + 1,
        )

    @cached_property
    def matrix(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(indptr, indices, data) of the float64 CSR matrix whose row j sums 4 q[w] - q[anchor]
        over row j's sources: 4 at each source, -1 at each anchor, repeats summed."""
        return self._weighted(4.0, -1.0)

    def pushed_matrix(self, push: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """:attr:`matrix` for predictor 2's push ``push`` (format 1.6, §6.2): row j sums
        (6 + push) q[w] - push q[anchor] over row j's sources."""
        made = self._pushed.get(push)
        if made is None:
            made = self._pushed[push] = self._weighted(6.0 + push, -float(push))
        return made

    @cached_property
    def _pushed(self) -> dict[int, tuple[np.ndarray, np.ndarray, np.ndarray]]:
        return {}

    def _weighted(self, source: float, anchor: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        import scipy.sparse as sparse

        counts = self.counts
        owner = np.repeat(np.arange(self.rows.size), counts)
        weights = np.concatenate([np.full(counts.sum(), source), np.full(counts.sum(), anchor)])
        matrix = sparse.csr_matrix(
            (
                weights,
                (np.concatenate([owner, owner]), np.concatenate([self.sources, self.anchors])),
            ),
            shape=(
                self.rows.size,
                int(max(self.sources.max(initial=-1), self.anchors.max(initial=-1))) + 1,
            ),
        )
        matrix.sum_duplicates()
        return (
            matrix.indptr.astype(np.int64),
            matrix.indices.astype(np.int64),
            matrix.data.astype(np.float64),
        )


class MeshPrediction:
    """What U1's mesh predictors need (``spec/FORMAT.md`` §6.2), built once per mesh: the
    ``parents`` of predictor 1 at once, and the :class:`MeanSteps` of predictor 2 when first
    asked for (they cost about as much again)."""

    def __init__(self, faces: np.ndarray, vertex_count: int) -> None:
        core = native.core()
        # the compiled core's forest (its whole walk at once), or the numpy one
        self._native: Any = None
        self._forest: _Forest | None = None
        if core is not None:
            self._native = _native_forest(core, faces, vertex_count)
            self.parents: np.ndarray = self._native.parents()
        else:
            self._forest = _mesh_forest(faces, vertex_count)
            self.parents = self._forest.parents(vertex_count)
        self.vertex_count = vertex_count
        self._mean: MeanSteps | None = None

    def _built(self) -> _Forest:
        assert self._forest is not None
        return self._forest

    @property
    def levels(self) -> int:
        """The forest's number of depths, 0 included (1 for a mesh without edges); counted
        only up to MAX_MEAN_LEVELS + 1, so that a strip of faces, on which predictor 2 is not
        allowed, is not walked level by level."""
        if self._mean is not None:
            return self._mean.levels
        if self._native is not None:
            return min(int(self._native.levels()), MAX_MEAN_LEVELS + 1)
        return self._built().level_ends(MAX_MEAN_LEVELS + 1).size - 1

    @property
    def mean_steps(self) -> MeanSteps:
        if self._mean is None:
            if self._native is not None:
                rows, step_ends, sources, anchors, source_ends, levels, plan = (
                    self._native.mean_steps()
                )
                self._mean = MeanSteps(rows, step_ends, sources, anchors, source_ends, levels, plan)
            else:
                self._mean = self._built().mean_steps()
        return self._mean


def mesh_prediction(faces: np.ndarray, vertex_count: int) -> MeshPrediction:
    """The :class:`MeshPrediction` of a face table (one breadth-first walk, as
    :func:`mesh_parents`)."""
    return MeshPrediction(faces, vertex_count)


@dataclass(frozen=True)
class _Forest:
    """The breadth-first walk of :func:`mesh_parents` in the numbering of the vertices on an
    edge (``used[j]`` is vertex j's index in the mesh)."""

    used: np.ndarray  # (n,) int64, ascending
    #: (indptr, indices) of the (n, n) CSR adjacency, one entry per edge, each row ascending
    adjacency: tuple[np.ndarray, np.ndarray]
    walk: np.ndarray  # (n,) the vertices in the order the walk reaches them
    found: np.ndarray  # (n,) int64: each vertex's parent, or -1

    def parents(self, vertex_count: int) -> np.ndarray:
        parents = np.full(vertex_count, NO_PARENT, dtype=np.int64)
        has_parent = self.found >= 0
        parents[self.used[has_parent]] = self.used[self.found[has_parent]]
        return parents

    def level_ends(self, most: int | None = None) -> np.ndarray:
        """Where each depth ends in the walk, ``[0, end of depth 0, end of depth 1, ...]``:
        all of them, or the first ``most``."""
        count = self.used.size
        walk, found = self.walk, self.found
        position = np.empty(count, dtype=np.int64)
        position[walk] = np.arange(count, dtype=np.int64)
        # the walk is first in, first out: a vertex is queued when its parent leaves the queue,
        # so the parents' positions never decrease along the walk, and the vertices of depth
        # d + 1 are the run whose parents lie among those of depth d
        parent_position = np.where(found[walk] >= 0, position[np.maximum(found[walk], 0)], -1)
        ends = [0, int(np.searchsorted(parent_position, 0))]  # the roots come first
        while ends[-1] < count and (most is None or len(ends) <= most):
            ends.append(int(np.searchsorted(parent_position, ends[-1])))
        return np.array(ends, dtype=np.int64)

    def mean_steps(self) -> MeanSteps:
        count = self.used.size
        walk, found = self.walk, self.found
        level_ends = self.level_ends()
        levels = level_ends.size - 1
        depth_in_walk = np.repeat(np.arange(levels, dtype=np.int64), np.diff(level_ends))
        rank = np.arange(count, dtype=np.int64) - level_ends[depth_in_walk]
        step_in_walk = depth_in_walk * MEAN_PHASES + rank % MEAN_PHASES
        step = np.empty(count, dtype=np.int64)
        step[walk] = step_in_walk
        first_step = MEAN_PHASES  # depth 0 (the roots) is not predicted
        steps = max(levels - 1, 0) * MEAN_PHASES
        order = walk[level_ends[1] :][np.argsort(step_in_walk[level_ends[1] :], kind="stable")]
        step_ends = np.zeros(steps + 1, dtype=np.int64)
        np.cumsum(np.bincount(step[order] - first_step, minlength=steps)[:steps], out=step_ends[1:])
        if not order.size:
            empty = np.zeros(0, dtype=np.int64)
            return MeanSteps(empty, step_ends, empty, empty, np.zeros(1, np.int64), levels)
        lengths, neighbour = _rows(*self.adjacency, order)
        owner = np.repeat(order, lengths)
        mine, theirs = step[owner], step[neighbour]
        depth_of = mine // MEAN_PHASES
        upper = theirs // MEAN_PHASES == depth_of - 1
        keep = upper | ((theirs // MEAN_PHASES == depth_of) & (theirs < mine))
        anchor = np.where(upper & (found[neighbour] >= 0), found[neighbour], neighbour)[keep]
        source_ends = np.zeros(order.size + 1, dtype=np.int64)
        row_of = np.repeat(np.arange(order.size), lengths)
        np.cumsum(np.bincount(row_of[keep], minlength=order.size), out=source_ends[1:])
        used = self.used
        return MeanSteps(
            used[order], step_ends, used[neighbour[keep]], used[anchor], source_ends, levels
        )


def _rows(
    indptr: np.ndarray, indices: np.ndarray, rows: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """``(lengths, entries)``: the CSR rows ``rows``, each in its order, back to back."""
    starts = indptr[rows]
    lengths = indptr[rows + 1] - starts
    ends = np.cumsum(lengths)
    positions = np.arange(int(ends[-1]) if ends.size else 0, dtype=np.int64)
    positions += np.repeat(starts - (ends - lengths), lengths)
    return lengths, indices[positions]


#: The most levels :func:`_mesh_forest` walks a level at a time in numpy (a few calls per level,
#: about 20 us here); a deeper forest (a strip of faces) is walked by scipy's compiled
#: breadth-first search, after at most this many levels' work lost. (The shared sequences and
#: the 100,000-vertex meshes of tools.bench have 119 to 536 levels.)
LEVEL_WALK_LIMIT = 1024
#: The most rounds of :func:`_component_roots`' hooking (a handful on meshes).
COMPONENT_ROUNDS = 64


def _mesh_forest(faces: np.ndarray, vertex_count: int) -> _Forest:
    """The breadth-first forest of §6.2 over the vertices on an edge.

    Only vertices on an edge can have a parent; they are numbered 0..n-1 in index order, which
    keeps every order the walk depends on, so the graph's size follows the faces, not K (the
    rest costs at most 13 bytes per vertex, the int64 result included).

    The walk is made a level at a time with numpy, over every component at once: as if a
    virtual root, before every vertex, had each component's smallest vertex as its neighbours
    in ascending order (:func:`_component_roots`). Components are disjoint, so within one the
    queue holds that component's vertices in the order of its own walk, and the parents are the
    spec's. The queue is first in, first out, so level d + 1 is, in order, the neighbours of
    level d's vertices in their order, each row ascending, at their first occurrence, less the
    vertices reached before. A forest deeper than :data:`LEVEL_WALK_LIMIT` is walked by scipy
    (:func:`_scipy_forest`, the same walk), whose import costs about 0.1 s and 11 MB.
    """
    a, b = face_edges(faces)
    proper = a != b  # a degenerate face may repeat a vertex
    a, b = a[proper], b[proper]
    if a.size == 0:
        empty = np.zeros(0, dtype=np.int64)
        return _Forest(empty, (np.zeros(1, dtype=np.int64), empty), empty, empty)  # no edges
    present = np.zeros(vertex_count, dtype=bool)
    present[a] = True
    present[b] = True
    used = np.flatnonzero(present)
    count = used.size
    del present
    if vertex_count <= 4 * a.size:  # dense: a lookup table is fastest
        number = np.zeros(vertex_count, dtype=np.int64)
        number[used] = np.arange(count, dtype=np.int64)
        la, lb = number[a], number[b]
        del number
    else:  # a few faces among many vertices: no table of K entries
        la, lb = np.searchsorted(used, a), np.searchsorted(used, b)
    del a, b
    # one key per directed edge, both ways: sorted, they are the CSR rows, each ascending
    keys = np.concatenate([la * count + lb, lb * count + la])
    keys.sort()  # not np.unique: numpy 2's hashing unique is many times slower here
    keys = keys[np.concatenate([[True], keys[1:] != keys[:-1]])]
    source, indices = np.divmod(keys, count)
    del keys, la, lb
    indptr = np.zeros(count + 1, dtype=np.int64)
    np.cumsum(np.bincount(source, minlength=count), out=indptr[1:])
    upward = source < indices  # each edge once
    roots = _component_roots(source[upward], indices[upward], count)
    del source, upward
    walked = None if roots is None else _level_walk(indptr, indices, roots, count)
    if walked is None:
        walked = _scipy_forest(indptr, indices, count)
    return _Forest(used.astype(np.int64), (indptr, indices), *walked)


def _component_roots(la: np.ndarray, lb: np.ndarray, count: int) -> np.ndarray | None:
    """Each component's smallest vertex, ascending, from the edges ``la``-``lb``: every label
    starts as its vertex; each round hooks the larger label of each edge whose two ends differ
    onto the smaller, then every vertex follows its labels to the end. Labels only fall and
    stay within a component, so each ends at the component's smallest vertex. None after
    :data:`COMPONENT_ROUNDS` rounds (then scipy's search finds the components)."""
    label = np.arange(count, dtype=np.int64)
    for _ in range(COMPONENT_ROUNDS):
        ends_a, ends_b = label[la], label[lb]
        differ = ends_a != ends_b
        if not differ.any():
            return np.flatnonzero(label == np.arange(count))
        la, lb, ends_a, ends_b = la[differ], lb[differ], ends_a[differ], ends_b[differ]
        np.minimum.at(label, np.maximum(ends_a, ends_b), np.minimum(ends_a, ends_b))
        while True:  # pointer jumping: every vertex to the end of its chain of labels
            jumped = label[label]
            if np.array_equal(jumped, label):
                break
            label = jumped
    return None


def _level_walk(
    indptr: np.ndarray, indices: np.ndarray, roots: np.ndarray, count: int
) -> tuple[np.ndarray, np.ndarray] | None:
    """``(walk, parents)`` of the breadth-first walk from ``roots`` (the virtual root's
    neighbours), a level at a time; None past :data:`LEVEL_WALK_LIMIT` levels."""
    found = np.full(count, NO_PARENT, dtype=np.int64)
    # where the queue first meets each vertex of the next level (a place in the level's list
    # of neighbours); the largest int64: not met yet; -1: reached at an earlier level
    first = np.full(count, np.iinfo(np.int64).max, dtype=np.int64)
    first[roots] = -1
    levels, frontier = [roots], roots
    while frontier.size:
        if len(levels) > LEVEL_WALK_LIMIT:
            return None
        lengths, neighbour = _rows(indptr, indices, frontier)
        fresh = first[neighbour] > 0
        neighbour = neighbour[fresh]
        place = np.flatnonzero(fresh)
        np.minimum.at(first, neighbour, place)
        met = first[neighbour] == place  # each vertex at its first place, in the queue's order
        parents = np.repeat(frontier, lengths)[place[met]]
        frontier = neighbour[met]
        found[frontier] = parents
        first[frontier] = -1
        levels.append(frontier)
    levels.pop()  # the last is empty
    return np.concatenate(levels), found


def _scipy_forest(
    indptr: np.ndarray, indices: np.ndarray, count: int
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`_level_walk`'s ``(walk, parents)`` from scipy's compiled breadth-first search,
    which pops a first-in-first-out queue and scans each vertex's row of a sorted CSR matrix in
    order: the neighbours in ascending order. The virtual root, numbered after every vertex,
    lists the components' smallest vertices. (A strip of faces, as deep as half its vertices,
    took minutes when walked one level per Python iteration.)"""
    # imported here: scipy.sparse.csgraph costs about 0.2 s (it imports scipy.linalg)
    import scipy.sparse as sparse
    from scipy.sparse.csgraph import breadth_first_order, connected_components

    adjacency = sparse.csr_matrix(
        (np.ones(indices.size, dtype=np.int8), indices, indptr), shape=(count, count)
    )
    _, labels = connected_components(adjacency, directed=False)
    _, roots = np.unique(labels, return_index=True)  # the smallest vertex of each component
    roots = np.sort(roots)
    # the virtual root `count`: its row lists the component roots, and no row lists it
    forest = sparse.csr_matrix(
        (
            np.ones(indices.size + roots.size, dtype=np.int8),
            np.concatenate([indices, roots]),
            np.concatenate([indptr, [indptr[-1] + roots.size]]),
        ),
        shape=(count + 1, count + 1),
    )
    walk, predecessors = breadth_first_order(forest, count, directed=True, return_predecessors=True)
    found = predecessors[:count].astype(np.int64)
    found[found == count] = NO_PARENT  # the roots hang from the virtual root
    found[found < 0] = NO_PARENT
    return walk[1:].astype(np.int64), found
