"""The coders that :mod:`tools.bench` compares, each behind one small interface.

A coder turns a :class:`~tuckercodec.MeshSequence` into bytes and back. Every size counts
everything a user would have to keep to get the frames back: the positions, the connectivity
(faces), and the small framing a real file needs (frame lengths, quantization ranges). Where a
coder has no connectivity coder of its own, the faces are stored once with zstd level 19 on the
plain int32 triangle list, the lossless reference of ../shared/NOTES.md. Errors are measured by
the caller on the decoded positions, never taken from the coder.

The coders:

* ``tuckercodec``: this codec, at each KG target.
* ``pca``: the seed paper's section 2.4 baseline (PCA of the F x 3K matrix of centred frames)
  given this codec's quantization (one parameter D; per-entry noise D/12, steps scaled by the
  singular values) and packing (zigzag, byte planes, zstd 19, mesh prediction of the basis
  vectors, time prediction of the coefficients), in this codec's container, with the same
  search of the truncation/quantization split on real bytes.
* ``draco-mesh`` / ``draco-points``: Draco on each frame (DracoPy), quantization bits 8-16,
  compression level 10 (the smallest). ``draco-mesh`` encodes each frame as a mesh, so every
  frame carries the connectivity, plus one permutation back to the input's vertex order
  (log2(K!) bits; see :func:`_run_draco`); ``draco-points`` encodes each frame as a point cloud
  with ``preserve_order`` and the faces once.
* ``meshopt``: meshoptimizer's vertex codec on each frame, positions quantized to 8-16 bits over
  the sequence's bounding box (uint16 x 4 per vertex, glTF's KHR_mesh_quantization layout), the
  frames then packed with zstd 19 as gltfpack users do; faces by meshoptimizer's index codec
  after its vertex-cache optimisation (which reorders triangles, never vertices), then zstd 19.
* ``sz3`` (pysz, L2-norm error bound, on the 3 x K x F layout) and ``zfp`` (zfpy, absolute
  tolerance, K x 3 x F) on the centred float64 tensor, with the per-frame centroids as float32
  and the faces once. The bound is searched so that the decoded KG error meets each target.
* ``zstd-f32``: the positions as float32 with zstd 19 (the lossless reference).
* ``tthresh``: TTHRESH (a general Tucker compressor) on the centred tensor when a ``tthresh``
  binary is on the PATH; never vendored or built here. Its ``-e`` is the relative Frobenius
  error of the tensor, which on the centred tensor is exactly KG / 100.
"""

from __future__ import annotations

import atexit
import io
import math
import shutil
import struct
import subprocess
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import zstandard

from tools.common import resident_peak
from tuckercodec import MeshSequence, decode, encode_with_report, internal

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


def uncentre(tensor: np.ndarray, centroids: np.ndarray) -> np.ndarray:
    """The (F, K, 3) positions of a K x 3 x F centred tensor and its centroids."""
    return tensor.transpose(2, 0, 1) + centroids[:, None, :]


def _match_vertices(original: np.ndarray, points: np.ndarray, coder: str) -> np.ndarray:
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
# the coders


@dataclass
class Coder:
    """A coder's name, what it needs, and how it produces its trials."""

    name: str
    run: Callable[[MeshSequence, list[float], Context], list[Trial]]
    needs: str = ""  # the import or binary it needs, for the skip message

    def unavailable(self) -> str | None:
        """Why this coder cannot run here, or None."""
        if not self.needs:
            return None
        if self.needs.startswith("binary:"):
            binary = self.needs.split(":", 1)[1]
            return None if shutil.which(binary) else f"no `{binary}` binary on the PATH"
        try:
            __import__(self.needs)
        except ImportError:
            return f"Python package `{self.needs}` is not installed (pip install '.[bench]')"
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


def run_tuckercodec(sequence: MeshSequence, targets: list[float], context: Context) -> list[Trial]:
    # One function per setting, so that each trial's closures (kept for re-timing) hold their
    # own target, not the loop's last one.
    def trial_at(target: float) -> Trial:
        def encode() -> tuple[bytes, int, bytes]:
            result = encode_with_report(sequence, target_kg=target)
            return result.data, result.report.section_bytes.get("FACE", 0), result.data

        def decode_(data: bytes) -> np.ndarray:
            return decode(data).vertices

        return timed_trial("tuckercodec", f"KG<={target:g}", encode, decode_, target)

    return [trial_at(target) for target in targets]


# --- PCA baseline ---------------------------------------------------------------------------

#: Shares of the squared error budget left to quantization, as in tuckercodec's encoder.
PCA_SHARES = (0.1, 0.2, 0.3, 0.45, 0.6, 0.75)


class _PcaModel:
    """The PCA of the F x 3K matrix of centred frames, and its quantized, packed form."""

    def __init__(self, sequence: MeshSequence, context: Context) -> None:
        self.sequence = sequence
        self.context = context
        frames, vertices = sequence.frame_count, sequence.vertex_count
        matrix = context.tensor.transpose(2, 0, 1).reshape(frames, 3 * vertices)
        left, self.sigma, right_t = np.linalg.svd(matrix, full_matrices=False)
        self.coefficients = left * self.sigma[None, :]  # F x r: frame f = sum_j A[f, j] * basis_j
        self.basis = right_t  # r x 3K, orthonormal rows
        energy = self.sigma**2
        # tails[r]: the squared error of rank r
        self.tails = np.concatenate([np.cumsum(energy[::-1])[::-1], [0.0]])
        # the same connectivity codec and mesh prediction as tuckercodec's (format 1.2)
        self.mesh = internal.mesh_prediction(sequence.faces, vertices)
        self.parents = self.mesh.parents
        self.faces = internal.faces.encode_face_section(sequence.faces, vertices)

    def quantize(self, rank: int, step: float) -> tuple[internal.qmat.QuantizedMatrix, ...]:
        root = math.sqrt(step)
        vertices = self.sequence.vertex_count
        sigma = np.maximum(self.sigma[:rank], np.finfo(float).tiny)
        # each basis vector as three columns (x, y, z) of a K-row matrix, predicted over the mesh
        basis = (
            self.basis[:rank]
            .reshape(rank, vertices, 3)
            .transpose(1, 0, 2)
            .reshape(vertices, 3 * rank)
        )
        basis_q = internal.qmat.quantize(basis, np.repeat(root / sigma, 3))
        coefficients_q = internal.qmat.quantize(self.coefficients[:, :rank], np.full(rank, root))
        centroids_q = internal.qmat.quantize(
            self.context.centroids, np.full(3, root / math.sqrt(vertices))
        )
        return basis_q, coefficients_q, centroids_q

    def positions(self, rank: int, basis_q, coefficients_q, centroids_q) -> np.ndarray:
        vertices = self.sequence.vertex_count
        basis = (
            basis_q.values()
            .reshape(vertices, rank, 3)
            .transpose(1, 0, 2)
            .reshape(rank, 3 * vertices)
        )
        frames = coefficients_q.values() @ basis
        return frames.reshape(-1, vertices, 3) + centroids_q.values()[:, None, :]

    def pack(self, rank: int, parts, level: int) -> bytes:
        basis_q, coefficients_q, centroids_q = parts
        face = self.faces
        known = internal.sections.entry  # the entry of a section this codec defines
        qmat_entry = {"critical": True, "codec": internal.sections.QMAT}  # PCA's own sections
        centroid_params, centroid_payload = internal.qmat.encode_matrix(
            centroids_q, None, level=level
        )
        sections = [
            (known("FACE", face.params, face.codec), face.payload),
            (known("CENT", centroid_params), centroid_payload),
        ]
        for section_id, matrix, parents in (
            ("COEF", coefficients_q, None),
            ("BASE", basis_q, self.mesh),
        ):
            params, payload = internal.qmat.encode_matrix(matrix, parents, level=level)
            sections.append(({"id": section_id, **qmat_entry, **params}, payload))
        header = {
            "vertices": self.sequence.vertex_count,
            "frames": self.sequence.frame_count,
            "pca_rank": rank,
            "encoder": "tools/peers.py PCA baseline",
        }
        return internal.pack_container(header, sections)

    def unpack(self, data: bytes) -> np.ndarray:
        """Decode a file written by :meth:`pack` from its bytes alone (CRCs checked)."""
        container = internal.parse_container(data)
        rank = container.header["pca_rank"]

        def matrix(section_id: str, parents: Any) -> internal.qmat.QuantizedMatrix:
            entry = container.section(section_id)
            return internal.qmat.decode_matrix(
                container.payload(data, entry),
                entry.params,
                parents,
                section_id,
                coding_tools=container.coding_tools,  # predictors 2 and 3 (format 1.2)
            )

        return self.positions(
            rank, matrix("BASE", self.mesh), matrix("COEF", None), matrix("CENT", None)
        )

    def encode(self, target: float) -> bytes:
        """The smallest file found whose decoded KG error is at most ``target``."""
        limit2 = (target / 100.0 * self.context.centred_norm) ** 2 * (1 - 1e-9)
        vertices, frames = self.sequence.vertex_count, self.sequence.frame_count
        best: tuple[int, int, float] | None = None  # (bytes at the search level, rank, step)
        for share in PCA_SHARES:
            rank = int(np.argmax(self.tails <= (1 - share) * limit2))
            room = limit2 - self.tails[rank]
            if rank == 0 or room <= 0:
                continue
            step = 12.0 * room / (3 * vertices * rank + frames * rank + 3 * frames)
            rank, step, parts = self._meet(rank, step, limit2)
            size = len(self.pack(rank, parts, internal.streams.SEARCH_LEVEL))
            if best is None or size < best[0]:
                best = (size, rank, step)
        if best is None:
            raise ValueError(f"PCA cannot meet KG {target} (the target is within rounding of zero)")
        _, rank, step = best
        return self.pack(rank, self.quantize(rank, step), internal.streams.DEFAULT_LEVEL)

    def _meet(self, rank: int, step: float, limit2: float):
        """Shrink D until the decoded squared error is within ``limit2``."""
        original = self.sequence.vertices
        for _ in range(40):
            parts = self.quantize(rank, step)
            error2 = float(np.square(self.positions(rank, *parts) - original).sum())
            if error2 <= limit2:
                return rank, step, parts
            room = limit2 - self.tails[rank]
            added = max(error2 - self.tails[rank], 1e-300)
            step *= min(0.95, max(0.25, 0.97 * room / added))
        raise ValueError("PCA could not meet the error target")  # pragma: no cover


def run_pca(sequence: MeshSequence, targets: list[float], context: Context) -> list[Trial]:
    # The SVD is the same for every target: made once, its time added to every encode's, and
    # its peak memory taken into every trial's.
    with resident_peak() as memory:
        start = time.perf_counter()
        model = _PcaModel(sequence, context)
        svd_seconds = time.perf_counter() - start

    def trial_at(target: float) -> Trial:
        def encode() -> tuple[bytes, int, bytes]:
            data = model.encode(target)
            return data, len(model.faces[1]), data

        trial = timed_trial(
            "pca", f"KG<={target:g}", encode, lambda data: model.unpack(data), target
        )
        trial.setup_seconds = svd_seconds
        if trial.peak_bytes is not None and memory["peak"] is not None:
            trial.peak_bytes = max(trial.peak_bytes, memory["peak"])
        return trial

    return [trial_at(target) for target in targets]


# --- Draco ------------------------------------------------------------------------------------


def _run_draco(sequence: MeshSequence, context: Context, *, with_faces: bool) -> list[Trial]:
    import DracoPy

    name = "draco-mesh" if with_faces else "draco-points"
    vertices = sequence.vertices.astype(np.float32)
    triangles = sequence.triangles().astype(np.uint32)
    if with_faces and not triangles.size:
        return []  # a point cloud has no mesh to encode; draco-points covers it
    # An animation cache binds vertices by index, so the input order must come back. A point
    # cloud keeps it with preserve_order; a mesh so encoded loses Draco's connectivity coding
    # (4-7 times larger on chicken), so the mesh keeps Draco's own order, which its traversal of
    # the fixed connectivity makes the same in every frame (up to vertices at equal positions,
    # which are interchangeable), and pays once for the permutation back: log2(K!) bits, the
    # least any coding of a permutation can take.
    permutation_bytes = (
        math.ceil(math.lgamma(sequence.vertex_count + 1) / math.log(2) / 8) if with_faces else 0
    )

    def trial_at(bits: int) -> Trial:
        def encode() -> tuple[int, int | None, list[bytes]]:
            buffers = [
                DracoPy.encode(
                    frame,
                    triangles if with_faces else None,
                    quantization_bits=bits,
                    compression_level=10,
                    preserve_order=not with_faces,
                )
                for frame in vertices
            ]
            total = (
                sum(len(b) for b in buffers) + FRAME_LENGTH_BYTES * len(buffers) + permutation_bytes
            )
            faces = None
            if not with_faces:
                faces = len(faces_once(sequence))
                total += faces
            return total, faces, buffers

        def decode_(buffers: list[bytes]) -> list[np.ndarray]:
            return [
                np.asarray(DracoPy.decode(buffer).points, dtype=np.float64) for buffer in buffers
            ]

        def in_input_order(frames: list[np.ndarray]) -> np.ndarray:
            if not with_faces:  # kept in order: nothing to match, and no reordering is allowed
                return np.stack(frames)
            return np.stack(
                [_match_vertices(vertices[f], points, name) for f, points in enumerate(frames)]
            )

        return timed_trial(name, f"{bits} bits", encode, decode_, untimed=in_input_order)

    return [trial_at(bits) for bits in context.bits]


def run_draco_mesh(sequence: MeshSequence, targets: list[float], context: Context) -> list[Trial]:
    return _run_draco(sequence, context, with_faces=True)


def run_draco_points(sequence: MeshSequence, targets: list[float], context: Context) -> list[Trial]:
    return _run_draco(sequence, context, with_faces=False)


# --- meshoptimizer ---------------------------------------------------------------------------


def run_meshopt(sequence: MeshSequence, targets: list[float], context: Context) -> list[Trial]:
    import meshoptimizer

    frames, vertices = sequence.frame_count, sequence.vertex_count
    low = sequence.vertices.min(axis=(0, 1))
    extent = float((sequence.vertices.max(axis=(0, 1)) - low).max()) or 1.0
    indices = sequence.triangles().astype(np.uint32).reshape(-1)
    optimised = np.empty_like(indices)
    if indices.size:
        meshoptimizer.optimize_vertex_cache(optimised, indices, vertex_count=vertices)
    index_bytes = (
        zstd_bytes(
            meshoptimizer.encode_index_buffer(
                np.asarray(optimised, dtype=np.uint32), vertex_count=vertices
            )
        )
        if indices.size
        else b""
    )

    def trial_at(bits: int) -> Trial:
        step = extent / ((1 << bits) - 1)

        def encode() -> tuple[int, int, bytes]:
            q = np.zeros((vertices, 4), dtype=np.uint16)
            stream = io.BytesIO()
            stream.write(struct.pack("<4dB", *low, extent, bits))  # the dequantization, once
            for frame in sequence.vertices:
                q[:, :3] = np.rint((frame - low) / step)
                encoded = meshoptimizer.encode_vertex_buffer(q)
                stream.write(struct.pack("<I", len(encoded)))
                stream.write(encoded)
            packed = zstd_bytes(stream.getvalue())
            return len(packed) + len(index_bytes), len(index_bytes), packed

        def decode_(packed: bytes) -> np.ndarray:
            raw = zstandard.ZstdDecompressor().decompress(packed)
            *origin, span, stored_bits = struct.unpack_from("<4dB", raw)
            unit = span / ((1 << stored_bits) - 1)
            offset = struct.calcsize("<4dB")
            out = np.empty((frames, vertices, 3))
            for f in range(frames):
                (length,) = struct.unpack_from("<I", raw, offset)
                offset += 4
                # Ask for the default float32 (vertices, 2) and view it as uint16: the package's
                # dtype=np.uint16 allocates vertices, not vertices * 4, entries and overruns it.
                data = meshoptimizer.decode_vertex_buffer(
                    vertices, 8, raw[offset : offset + length]
                )
                offset += length
                q = np.ascontiguousarray(data).view(np.uint16).reshape(vertices, 4)
                out[f] = q[:, :3] * unit + np.asarray(origin)
            return out

        return timed_trial("meshopt", f"{bits} bits", encode, decode_)

    return [trial_at(bits) for bits in context.bits]


# --- error-bounded float compressors ---------------------------------------------------------


def _search_bound(
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


def _search_targets(
    name: str,
    targets: list[float],
    context: Context,
    guess: Callable[[float], float],
    compress: Callable[[float], bytes],
    decompress: Callable[[bytes], np.ndarray],
    label: Callable[[float], str],
) -> list[Trial]:
    """:func:`_search_bound` at each target, from the bound ``guess(target)``; a target that no
    bound tried meets has no trial."""
    trials = []
    for target in targets:
        trial = _search_bound(name, target, context, guess(target), compress, decompress, label)
        if trial is not None:
            trials.append(trial)
    return trials


def _rms_error(context: Context, target: float) -> float:
    """The per-entry RMS error that a KG of ``target`` allows: a starting guess for a bound."""
    return target / 100.0 * context.centred_norm / math.sqrt(context.tensor.size)


def run_sz3(sequence: MeshSequence, targets: list[float], context: Context) -> list[Trial]:
    from pysz import sz, szConfig, szErrorBoundMode

    # Axis first (3 x K x F): about 10 % smaller than K x 3 x F on chicken at the same error.
    axis_first = np.ascontiguousarray(context.tensor.transpose(1, 0, 2))
    shape = axis_first.shape

    def compress(bound: float) -> bytes:
        config = szConfig(shape)
        config.errorBoundMode = szErrorBoundMode.L2NORM
        config.l2normErrorBound = bound
        payload, _ = sz.compress(axis_first, config)
        return payload.tobytes()

    def decompress(payload: bytes) -> np.ndarray:
        data, _ = sz.decompress(np.frombuffer(payload, dtype=np.uint8), np.float64, shape)
        return np.asarray(data).reshape(shape).transpose(1, 0, 2)

    def guess(target: float) -> float:  # the L2 norm of the error a KG target allows
        return target / 100.0 * context.centred_norm

    return _search_targets(
        "sz3", targets, context, guess, compress, decompress, lambda b: f"L2 <= {b:.3g}"
    )


def run_zfp(sequence: MeshSequence, targets: list[float], context: Context) -> list[Trial]:
    import zfpy

    def compress(bound: float) -> bytes:
        return zfpy.compress_numpy(context.tensor, tolerance=bound)

    def decompress(payload: bytes) -> np.ndarray:
        return zfpy.decompress_numpy(payload)

    def guess(target: float) -> float:
        return 4.0 * _rms_error(context, target)

    return _search_targets(
        "zfp", targets, context, guess, compress, decompress, lambda b: f"tol {b:.3g}"
    )


def run_tthresh(sequence: MeshSequence, targets: list[float], context: Context) -> list[Trial]:
    """TTHRESH through its command line, on the centred tensor written as raw float64."""
    binary = shutil.which("tthresh")
    if binary is None:
        return []
    k, three, frames = context.tensor.shape
    # Not a with-block: the trials' re-timing runs TTHRESH again after this function returns.
    folder = tempfile.mkdtemp(prefix="tkc-tthresh-")
    atexit.register(shutil.rmtree, folder, True)
    raw = Path(folder) / "tensor.raw"
    compressed = Path(folder) / "tensor.tthresh"
    restored = Path(folder) / "restored.raw"
    context.tensor.tofile(raw)  # C order, time fastest: TTHRESH's first size varies fastest

    def compress(bound: float) -> bytes:
        sizes = [str(frames), str(three), str(k)]
        arguments = ["-i", str(raw), "-t", "double", "-s", *sizes, "-e", repr(bound)]
        subprocess.run(
            [binary, *arguments, "-c", str(compressed)],
            check=True,
            capture_output=True,
            timeout=3600,
        )
        return compressed.read_bytes()

    def decompress(payload: bytes) -> np.ndarray:
        compressed.write_bytes(payload)
        subprocess.run(
            [binary, "-c", str(compressed), "-o", str(restored)],
            check=True,
            capture_output=True,
            timeout=3600,
        )
        return np.fromfile(restored, dtype=np.float64).reshape(context.tensor.shape)

    def guess(target: float) -> float:  # -e is the relative error of the centred tensor
        return target / 100.0

    return _search_targets(
        "tthresh", targets, context, guess, compress, decompress, lambda b: f"-e {b:.3g}"
    )


def run_zstd(sequence: MeshSequence, targets: list[float], context: Context) -> list[Trial]:
    faces = faces_once(sequence)

    def encode() -> tuple[int, int, bytes]:
        payload = zstd_bytes(sequence.vertices.astype("<f4").tobytes())
        return len(payload) + len(faces), len(faces), payload

    def decode_(payload: bytes) -> np.ndarray:
        raw = zstandard.ZstdDecompressor().decompress(payload)
        return np.frombuffer(raw, dtype="<f4").reshape(sequence.vertices.shape).astype(np.float64)

    return [timed_trial("zstd-f32", "lossless float32", encode, decode_)]


CODERS: list[Coder] = [
    Coder("tuckercodec", run_tuckercodec),
    Coder("pca", run_pca),
    Coder("draco-mesh", run_draco_mesh, "DracoPy"),
    Coder("draco-points", run_draco_points, "DracoPy"),
    Coder("meshopt", run_meshopt, "meshoptimizer"),
    Coder("sz3", run_sz3, "pysz"),
    Coder("zfp", run_zfp, "zfpy"),
    Coder("zstd-f32", run_zstd),
    Coder("tthresh", run_tthresh, "binary:tthresh"),
]
