"""The zarr format 3 codec ``tuckercodec``: an array-to-bytes codec (zarr's public
:class:`zarr.abc.codec.ArrayBytesCodec`), the array's serializer.

Fitted (:meth:`TuckerZarrCodec.fit`), its configuration in ``zarr.json`` also holds the basis
that every chunk shares (:mod:`.fitted`): ``{"target_kg": 0.1, "basis": "<base64>",
"basis_sha256": "<hex>"}``.
"""

from __future__ import annotations

import asyncio
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from ..encoder import DEFAULT_TARGET_KG
from ..system.optional import import_optional
from .chunk import (
    SETTINGS_KEYS,
    ChunkMode,
    codec_settings,
    decode_chunk,
    describe_settings,
    encode_chunk,
    fit_settings,
    unpadded,
)
from .fitted import FittedBasis

# a DependencyError naming the extra, rather than an ImportError, when zarr is absent
import_optional("zarr", "zarr", "the tuckercodec zarr codec")

from zarr.abc.codec import ArrayBytesCodec  # noqa: E402
from zarr.registry import register_codec  # noqa: E402

if TYPE_CHECKING:  # zarr's types, for the reader: mypy sees zarr as Any (pyproject.toml)
    from zarr.core.array_spec import ArraySpec
    from zarr.core.buffer import Buffer, NDBuffer

NAME = "tuckercodec"


@dataclass(frozen=True)
class TuckerZarrCodec(ArrayBytesCodec):  # type: ignore[misc]  # zarr is Any to mypy
    """Compress a zarr format 3 array of shape (frames, vertices, 3) with a target KG error per
    chunk; in ``zarr.json`` as ``{"name": "tuckercodec", "configuration": {"target_kg": 0.1}}``.

    Give it as the array's serializer: ``zarr.create_array(..., serializer=TuckerZarrCodec())``
    (or the dict above, with no import: the codec is found through its entry point).

    Args:
        target_kg: the KG error each chunk meets, in percent (default 0.1 when no mode is
            given); the whole array then meets it too (:mod:`tuckercodec.zarr_codec`).
        ranks: fixed ranks [i, k] for every chunk instead (capped at what a short chunk has).
        target_bpfv: a size per chunk in bits per frame per vertex instead.
        basis, basis_sha256: the basis of a fitted codec, as :meth:`fit` makes it (base64
            text and its SHA-256); with ``target_kg`` only.
    """

    is_fixed_size = False

    mode: ChunkMode
    basis: FittedBasis | None = field(default=None)

    def __init__(
        self,
        *,
        target_kg: float | None = None,
        ranks: tuple[int, int] | list[int] | None = None,
        target_bpfv: float | None = None,
        basis: str | None = None,
        basis_sha256: str | None = None,
    ) -> None:
        mode, fitted = codec_settings(target_kg, ranks, target_bpfv, basis, basis_sha256)
        object.__setattr__(self, "mode", mode)
        object.__setattr__(self, "basis", fitted)

    @classmethod
    def fit(
        cls,
        array: Any,
        *,
        target_kg: float = DEFAULT_TARGET_KG,
        chunk_frames: int,
        max_memory: int | None = None,
    ) -> TuckerZarrCodec:
        """A fitted codec for ``array`` (frames, vertices, 3) chunked by ``chunk_frames``
        frames: its configuration holds one per-vertex basis with which every such chunk meets
        ``target_kg`` on its own, and each chunk stores only its own part (:mod:`.fitted`).

        ``array`` is a numpy, zarr or dask array (read a chunk of frames at a time, never whole
        as float64); give the new array chunks of ``chunk_frames`` frames and all vertices.
        ``max_memory`` bounds the fit's memory, in bytes (default: half the machine's).

        Raises:
            InputError: an array of another shape or dtype, or with a non-finite position.
            ValueError: a target or ``chunk_frames`` that is not positive.
        """
        return cls(**fit_settings(array, target_kg, chunk_frames, max_memory))

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> TuckerZarrCodec:
        """The codec of its ``zarr.json`` entry (:meth:`to_dict`)."""
        if not isinstance(data, dict) or data.get("name") != NAME:
            raise ValueError(f"expected a codec named {NAME!r}, got {data!r}")
        unknown = sorted(set(data) - {"name", "configuration"})
        configuration = data.get("configuration", {})
        if unknown or not isinstance(configuration, dict):
            raise ValueError(f"a {NAME} codec entry has only name and configuration: {data!r}")
        keys = sorted(set(configuration) - SETTINGS_KEYS)
        if keys:
            raise ValueError(f"unknown keys in a {NAME} configuration: {keys}")
        return cls(**configuration)

    def __repr__(self) -> str:
        return f"TuckerZarrCodec({describe_settings(self.mode, self.basis)})"

    def to_dict(self) -> dict[str, Any]:
        """``{"name": "tuckercodec", "configuration": {<the mode's one key>}}``, JSON-safe;
        a fitted codec's configuration also has ``basis`` and ``basis_sha256``."""
        configuration = self.mode.config()
        if self.basis is not None:
            configuration.update(self.basis.config())
        return {"name": NAME, "configuration": configuration}

    def validate(self, *, shape: tuple[int, ...], dtype: Any, chunk_grid: Any) -> None:
        """Refuse, when the array is created, what no chunk of it could be encoded as: another
        shape than (frames, vertices, 3), a dtype that is not floating point, or chunks that
        split the xyz axis."""
        if len(shape) != 3 or shape[2] != 3:
            raise ValueError(
                f"the {NAME} codec encodes arrays of shape (frames, vertices, 3), not {shape}"
            )
        native = np.dtype(dtype.to_native_dtype())
        if native.kind != "f":
            raise ValueError(f"the {NAME} codec encodes floating-point positions, not {native}")
        if self.basis is not None and shape[1] != self.basis.vertices:
            raise ValueError(
                f"the {NAME} codec's basis was fitted to {self.basis.vertices} vertices, not the "
                f"array's {shape[1]}"
            )
        chunks = getattr(chunk_grid, "chunk_shape", None)
        if chunks is None:
            return  # a grid without one chunk shape: each chunk is checked as it is encoded
        if chunks[2] != 3:
            raise ValueError(
                f"the {NAME} codec needs chunks that hold whole positions (x, y and z): the chunk "
                f"shape {tuple(chunks)} splits the last axis"
            )
        if self.basis is not None and chunks[1] != shape[1]:
            raise ValueError(
                f"a fitted {NAME} codec needs chunks that hold every vertex (its basis is "
                f"per vertex): the chunk shape {tuple(chunks)} splits the {shape[1]} vertices"
            )

    def compute_encoded_size(self, input_byte_length: int, chunk_spec: ArraySpec) -> int:
        """Not known before encoding: the size depends on the chunk's content."""
        raise NotImplementedError

    def _encode_sync(self, chunk_array: NDBuffer, chunk_spec: ArraySpec) -> Buffer | None:
        # what zarr padded a partial edge chunk with is not encoded: decoding restores it from
        # the fill value (so a NaN fill value works, and the padding costs nothing)
        # (a fitted basis is per vertex: only padding frames are cut)
        positions = unpadded(
            chunk_array.as_numpy_array(), chunk_spec.fill_value, vertices=self.basis is None
        )
        data = encode_chunk(positions, self.mode, self.basis)
        return chunk_spec.prototype.buffer.from_bytes(data)

    def _decode_sync(self, chunk_bytes: Buffer, chunk_spec: ArraySpec) -> NDBuffer:
        positions = decode_chunk(
            chunk_bytes.as_numpy_array(),
            chunk_spec.dtype.to_native_dtype(),
            shape=chunk_spec.shape,
            fill_value=chunk_spec.fill_value,
            basis=self.basis,
        )
        return chunk_spec.prototype.nd_buffer.from_numpy_array(positions)

    async def _encode_single(self, chunk_array: NDBuffer, chunk_spec: ArraySpec) -> Buffer | None:
        # encoding takes long and releases the GIL in BLAS and zstd: off the event loop
        return await asyncio.to_thread(self._encode_sync, chunk_array, chunk_spec)

    async def _decode_single(self, chunk_bytes: Buffer, chunk_spec: ArraySpec) -> NDBuffer:
        return await asyncio.to_thread(self._decode_sync, chunk_bytes, chunk_spec)


register_codec(NAME, TuckerZarrCodec)
