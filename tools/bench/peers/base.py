"""What the coders that the peers suite compares share: one small interface and its measures.

A coder turns a :class:`~tuckercodec.MeshSequence` into bytes and back. Every size counts
everything a user would have to keep to get the frames back: the positions, the connectivity
(faces), and the small framing a real file needs (frame lengths, quantization ranges). Where a
coder has no connectivity coder of its own, the faces are stored once with zstd level 19 on the
plain int32 triangle list, the lossless reference of ../shared/NOTES.md. Errors are measured by
the caller on the decoded positions, never taken from the coder.

Each coder is a module of its own beside this one (:mod:`~tools.bench.peers.tkc`, ``pca``,
``draco``, ``meshopt``, ``sz3``, ``zfp``, ``tthresh``, ``zstd``, and the lossless ``fpz``,
``pco`` and ``blosc``), listed in :data:`tools.bench.peers.CODERS` (the bounds and lossless
suites list theirs); what they share is here: one run measured (:class:`Trial`), what every
coder of one sequence shares (:class:`Context`), the search of an error bound that the
error-bounded float compressors (SZ3, zfp, TTHRESH) make for each KG target, and, for the
bounds and lossless suites, the positions in their own precision, the layouts a float compressor is
given them in, and the worst vertex measured independently of every coder.
"""

from __future__ import annotations

import math
import shutil
import statistics
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import zstandard

from tools.common import resident_peak
from tuckercodec import MeshSequence, internal

ZSTD_LEVEL = 19
#: Bytes of framing per frame for coders that store one buffer per frame: its length, uint32.
FRAME_LENGTH_BYTES = 4


# ------------------------------------------------------------------------------------------
# measuring one run


@dataclass
class Trial:
    """One encode and decode of a sequence by one coder at one setting."""

    coder: str
    setting: str
    total_bytes: int
    #: Bytes of the connectivity stored once; None where every frame carries its own.
    connectivity_bytes: int | None
    encode_seconds: float
    decode_seconds: float
    #: Peak resident memory above the resident memory at the start, bytes (None if unknown).
    peak_bytes: int | None
    decoded: np.ndarray | None = field(repr=False, default=None)  # (F, K, 3), dropped once measured
    target: float | None = None  # the KG target the setting was searched for, if any
    kg: float = math.nan
    metrics: dict[str, float] = field(default_factory=dict)
    #: Work shared by every setting and done once (PCA's SVD): added to each encode's time.
    setup_seconds: float = 0.0
    #: Runs the same encode and decode again: -> (encode seconds, decode seconds, total bytes).
    retime: Callable[[], tuple[float, float, int]] | None = field(repr=False, default=None)


def timed_trial(
    coder: str,
    setting: str,
    encode: Callable[[], tuple[bytes | int, int | None, Any]],
    decode_: Callable[[Any], Any],
    target: float | None = None,
    untimed: Callable[[Any], np.ndarray] | None = None,
) -> Trial:
    """Run ``encode`` (-> total bytes or the bytes themselves, connectivity bytes, state) and
    ``decode_(state)`` (-> positions), timing each and measuring the peak memory of both.

    ``untimed``, if given, turns what ``decode_`` returned into positions in the input's vertex
    order outside the timing: work that only the benchmark needs."""
    with resident_peak() as memory:
        start = time.perf_counter()
        encoded, connectivity_bytes, state = encode()
        encode_seconds = time.perf_counter() - start
        start = time.perf_counter()
        decoded = decode_(state)
        decode_seconds = time.perf_counter() - start
    if untimed is not None:
        decoded = untimed(decoded)
    total = encoded if isinstance(encoded, int) else len(encoded)

    def retime() -> tuple[float, float, int]:
        start = time.perf_counter()
        size, _, again = encode()
        middle = time.perf_counter()
        decode_(again)
        return (
            middle - start,
            time.perf_counter() - middle,
            size if isinstance(size, int) else len(size),
        )

    return Trial(
        coder,
        setting,
        total,
        connectivity_bytes,
        encode_seconds,
        decode_seconds,
        memory["peak"],
        decoded,
        target,
        retime=retime,
    )


def retime_median(trial: Trial, repeat: int) -> None:
    """Time ``trial``'s encode and decode ``repeat`` times in all (its first, measured run
    included) and keep the medians; a run that gives another size is an error (it must time
    the same encode)."""
    if repeat <= 1:
        return
    runs = [(trial.encode_seconds, trial.decode_seconds, trial.total_bytes)]
    retime = trial.retime
    assert retime is not None, f"{trial.coder} {trial.setting} cannot run again"
    runs += [retime() for _ in range(repeat - 1)]
    if any(size != trial.total_bytes for _, _, size in runs):
        raise RuntimeError(
            f"{trial.coder} {trial.setting}: a re-run gave another size: "
            f"{[size for _, _, size in runs]}"
        )
    trial.encode_seconds = statistics.median(r[0] for r in runs)
    trial.decode_seconds = statistics.median(r[1] for r in runs)


def kg_of(centred_norm: float, original: np.ndarray, decoded: np.ndarray) -> float:
    """KG error (Karni-Gotsman, per-frame centroid) given the original's centred norm."""
    return 100.0 * float(np.linalg.norm(decoded - original)) / centred_norm


# ------------------------------------------------------------------------------------------
# shared pieces


def zstd_bytes(raw: bytes) -> bytes:
    return zstandard.ZstdCompressor(level=ZSTD_LEVEL).compress(raw)


def faces_once(sequence: MeshSequence) -> bytes:
    """The faces as a plain int32 list, zstd 19: the connectivity of coders without their own."""
    return zstd_bytes(np.ascontiguousarray(sequence.faces, dtype="<i4").tobytes())


def own_precision(sequence: MeshSequence) -> np.ndarray:
    """The positions in the sequence's own precision: float32 where every value is a float32
    exactly, else float64; what the bound and lossless suites give the float compressors."""
    return sequence.compact_vertices()


#: Arrangements of the (F, K, 3) positions a float compressor may be given, by name: the axes
#: of the stored array in order, the last varying fastest. ``3KF`` puts each vertex coordinate's
#: frames side by side (time fastest), where an animation is smoothest.
LAYOUTS: dict[str, tuple[int, int, int]] = {
    "FK3": (0, 1, 2),
    "3KF": (2, 1, 0),
    "3FK": (2, 0, 1),
}


def arrange(values: np.ndarray, layout: str) -> np.ndarray:
    """The (F, K, 3) ``values`` in ``layout`` (a name of :data:`LAYOUTS`), contiguous."""
    return np.ascontiguousarray(values.transpose(LAYOUTS[layout]))


def restore(arranged: np.ndarray, layout: str) -> np.ndarray:
    """The (F, K, 3) positions of an array in ``layout``: the inverse of :func:`arrange`."""
    return arranged.transpose(np.argsort(LAYOUTS[layout]))


def worst_vertex(original: np.ndarray, decoded: np.ndarray) -> tuple[float, int, int]:
    """The largest Euclidean distance of a decoded vertex from the original, in the
    sequence's units, and its (frame, vertex): measured here with numpy in float64, never
    taken from a coder's report."""
    difference = np.asarray(decoded, dtype=np.float64) - np.asarray(original, dtype=np.float64)
    distances = np.sqrt(np.einsum("fkx,fkx->fk", difference, difference))
    frame, vertex = np.unravel_index(int(np.argmax(distances)), distances.shape)
    return float(distances[frame, vertex]), int(frame), int(vertex)


def bounding_box_diagonal(vertices: np.ndarray) -> float:
    """The diagonal of the box around every vertex of every frame: what the bounds suite's
    ``P%`` bounds are a fraction of."""
    return float(np.linalg.norm(vertices.max(axis=(0, 1)) - vertices.min(axis=(0, 1))))


def lossless_trial(
    coder: str,
    setting: str,
    sequence: MeshSequence,
    values: np.ndarray,
    layout: str,
    compress: Callable[[np.ndarray], bytes],
    decompress: Callable[[bytes, np.ndarray], np.ndarray],
) -> Trial:
    """One lossless coder at one setting: ``compress`` the ``values`` (positions in their own
    precision) arranged in ``layout``, the faces once; ``decompress(payload, like)`` gives back
    an array of the shape and type of ``like`` (the arranged input, read for nothing else). The
    decoded positions stay in their own type, for the caller's comparison of bits. The decode
    unpacks the faces too, as the decode of a whole file would."""
    arranged = arrange(values, layout)
    faces = faces_once(sequence)

    def encode() -> tuple[int, int, bytes]:
        payload = compress(arranged)
        return len(payload) + len(faces), len(faces), payload

    def decode_(payload: bytes) -> np.ndarray:
        np.frombuffer(zstandard.ZstdDecompressor().decompress(faces), dtype="<i4")
        return restore(decompress(payload, arranged).reshape(arranged.shape), layout)

    return timed_trial(coder, f"{setting}, {values.dtype}, {layout}", encode, decode_)


def uncentre(tensor: np.ndarray, centroids: np.ndarray) -> np.ndarray:
    """The (F, K, 3) positions of a K x 3 x F centred tensor and its centroids."""
    return tensor.transpose(2, 0, 1) + centroids[:, None, :]


def match_vertices(original: np.ndarray, points: np.ndarray, coder: str) -> np.ndarray:
    """Draco's decoded points in the original vertex order.

    Draco sorts the vertices for its own traversal and keeps no map back; it also merges
    vertices at the same position (chicken has a few). Its decoded points are exactly the
    lattice points of its quantization, and a vertex's own lattice point is the nearest lattice
    point to it, so the nearest decoded point to each original vertex is its own (or an equal
    one): matching by nearest neighbour gives exactly the error Draco made. A real user would
    have to store the permutation too; it is not counted.
    """
    from scipy.spatial import cKDTree

    distinct = len(np.unique(original, axis=0))
    if not distinct <= points.shape[0] <= original.shape[0]:
        raise RuntimeError(
            f"{coder} returned {points.shape[0]} vertices for {original.shape[0]} "
            f"({distinct} distinct positions): it drops vertices"
        )
    _, index = cKDTree(points).query(original)
    return points[index]


# ------------------------------------------------------------------------------------------
# what a coder is


@dataclass
class Coder:
    """A coder's name, what it needs, and how it produces its trials."""

    name: str
    run: Callable[[MeshSequence, list[float], Context], list[Trial]]
    needs: str = ""  # the import or binary it needs, for the skip message

    def unavailable(self) -> str | None:
        """Why this coder cannot run here, or None."""
        return missing(self.needs)


def missing(needs: str) -> str | None:
    """Why what a coder ``needs`` (an import, or ``binary:NAME``) is not here, or None."""
    if not needs:
        return None
    if needs.startswith("binary:"):
        binary = needs.split(":", 1)[1]
        return None if shutil.which(binary) else f"no `{binary}` binary on the PATH"
    try:
        __import__(needs)
    except ImportError:
        return f"Python package `{needs}` is not installed (pip install '.[bench]')"
    return None


@dataclass
class Context:
    """What every coder of one sequence shares: the centred data and the error measure."""

    sequence: MeshSequence
    centroids: np.ndarray
    tensor: np.ndarray
    centred_norm: float
    bits: list[int]

    @classmethod
    def of(cls, sequence: MeshSequence, bits: list[int]) -> Context:
        tensor, centroids = internal.centre_frames(sequence.vertices)
        return cls(sequence, centroids, tensor, float(np.linalg.norm(tensor)), bits)

    def kg(self, decoded: np.ndarray) -> float:
        return kg_of(self.centred_norm, self.sequence.vertices, decoded)


def search_bound(
    name: str,
    target: float,
    context: Context,
    guess: float,
    compress: Callable[[float], bytes],
    decompress: Callable[[bytes], np.ndarray],
    label: Callable[[float], str],
) -> Trial | None:
    """The smallest file over bounds tried whose decoded KG meets ``target``: start from
    ``guess``, bracket by factors of 4, then halve the log-interval six times."""
    faces = faces_once(context.sequence)
    centroid_bytes = zstd_bytes(context.centroids.astype("<f4").tobytes())

    def attempt(bound: float) -> Trial:
        def encode() -> tuple[int, int, bytes]:
            payload = compress(bound)
            return len(payload) + len(centroid_bytes) + len(faces) + 64, len(faces), payload

        def decode_(payload: bytes) -> np.ndarray:
            centroids = np.frombuffer(
                zstandard.ZstdDecompressor().decompress(centroid_bytes), "<f4"
            )
            return uncentre(decompress(payload), centroids.reshape(-1, 3).astype(np.float64))

        trial = timed_trial(name, label(bound), encode, decode_, target)
        assert trial.decoded is not None  # timed_trial keeps what it decoded
        trial.kg = context.kg(trial.decoded)
        return trial

    met: list[Trial] = []
    low, high = None, None  # largest bound known to meet, smallest known to fail
    bound = guess
    for _ in range(8):  # bracket
        trial = attempt(bound)
        if trial.kg <= target:
            met.append(trial)
            low = bound
            if high is not None:
                break
            bound *= 4
        else:
            high = bound
            if low is not None:
                break
            bound /= 4
    if low is not None and high is not None:
        for _ in range(6):
            bound = math.sqrt(low * high)
            trial = attempt(bound)
            if trial.kg <= target:
                met.append(trial)
                low = bound
            else:
                high = bound
    if not met:
        return None
    best = min(met, key=lambda t: t.total_bytes)
    for trial in met:
        if trial is not best:
            trial.decoded = None
    return best


def search_targets(
    name: str,
    targets: list[float],
    context: Context,
    guess: Callable[[float], float],
    compress: Callable[[float], bytes],
    decompress: Callable[[bytes], np.ndarray],
    label: Callable[[float], str],
) -> list[Trial]:
    """:func:`search_bound` at each target, from the bound ``guess(target)``; a target that no
    bound tried meets has no trial."""
    trials = []
    for target in targets:
        trial = search_bound(name, target, context, guess(target), compress, decompress, label)
        if trial is not None:
            trials.append(trial)
    return trials


def rms_error(context: Context, target: float) -> float:
    """The per-entry RMS error that a KG of ``target`` allows: a starting guess for a bound."""
    return target / 100.0 * context.centred_norm / math.sqrt(context.tensor.size)
