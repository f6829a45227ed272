"""The numcodecs codec ``tuckercodec``: zarr format 2 arrays, and plain numcodecs use.

Fitted (:meth:`TuckerNumcodec.fit`), its configuration (the ``compressor`` of ``.zarray``) also
holds the basis that every chunk shares (:mod:`.fitted`): ``basis`` and ``basis_sha256``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..encoder import DEFAULT_TARGET_KG
from ..errors import InputError
from ..system.optional import import_optional
from .chunk import (
    SETTINGS_KEYS,
    ChunkMode,
    checked_dtype,
    chunk_positions,
    codec_settings,
    decode_chunk,
    describe_settings,
    encode_chunk,
    fit_settings,
)
from .fitted import FittedBasis

# a DependencyError naming the extra, rather than an ImportError, when numcodecs is absent
import_optional("numcodecs", "zarr", "the tuckercodec numcodecs codec")

from numcodecs.abc import Codec  # noqa: E402
from numcodecs.compat import ensure_ndarray_like, ndarray_copy  # noqa: E402
from numcodecs.registry import register_codec  # noqa: E402


class TuckerNumcodec(Codec):  # type: ignore[misc]  # numcodecs is untyped (Any)
    """Compress arrays of shape (frames, vertices, 3) with a target KG error per chunk.

    The numcodecs codec (id ``"tuckercodec"``), for zarr format 2 (as the array's compressor)
    and for plain :meth:`encode`/:meth:`decode`. A zarr format 3 array uses
    :class:`~tuckercodec.zarr_codec.TuckerZarrCodec` instead, as its serializer.

    Args:
        target_kg: the KG error each chunk meets, in percent (default 0.1 when no mode is
            given); the whole array then meets it too (:mod:`tuckercodec.zarr_codec`).
        ranks: fixed ranks [i, k] for every chunk instead (capped at what a short chunk has).
        target_bpfv: a size per chunk in bits per frame per vertex instead.
        dtype: the dtype that :meth:`decode` returns and :meth:`encode` accepts (default
            ``"<f8"``). numcodecs hands a codec's decoded bytes to zarr without the array's
            dtype, so it must be in the configuration: give the array's dtype (``"<f4"`` for a
            float32 array).
        basis, basis_sha256: the basis of a fitted codec, as :meth:`fit` makes it (base64
            text and its SHA-256); with ``target_kg`` only.
    """

    codec_id = "tuckercodec"

    def __init__(
        self,
        target_kg: float | None = None,
        ranks: tuple[int, int] | list[int] | None = None,
        target_bpfv: float | None = None,
        dtype: Any = "<f8",
        basis: str | None = None,
        basis_sha256: str | None = None,
    ) -> None:
        self._mode: ChunkMode
        self._basis: FittedBasis | None
        self._mode, self._basis = codec_settings(target_kg, ranks, target_bpfv, basis, basis_sha256)
        self._dtype: np.dtype[Any] = checked_dtype(dtype)

    @classmethod
    def fit(
        cls,
        array: Any,
        *,
        target_kg: float = DEFAULT_TARGET_KG,
        chunk_frames: int,
        dtype: Any = None,
        max_memory: int | None = None,
    ) -> TuckerNumcodec:
        """A fitted codec for ``array`` (frames, vertices, 3) chunked by ``chunk_frames``
        frames: its configuration holds one per-vertex basis with which every such chunk meets
        ``target_kg`` on its own, and each chunk stores only its own part (:mod:`.fitted`).

        ``array`` is a numpy, zarr or dask array (read a chunk of frames at a time, never whole
        as float64); ``dtype`` defaults to its dtype. Give the new array chunks of
        ``chunk_frames`` frames and all vertices. ``max_memory`` bounds the fit's memory, in
        bytes (default: half the machine's).

        Raises:
            InputError: an array of another shape or dtype, or with a non-finite position.
            ValueError: a target or ``chunk_frames`` that is not positive.
        """
        settings = fit_settings(array, target_kg, chunk_frames, max_memory)
        return cls(**settings, dtype=np.dtype(array.dtype if dtype is None else dtype).str)

    @property
    def mode(self) -> ChunkMode:
        """The encoder's mode every chunk gets."""
        return self._mode

    @property
    def dtype(self) -> np.dtype[Any]:
        """The dtype of decoded chunks."""
        return self._dtype

    @property
    def basis(self) -> FittedBasis | None:
        """A fitted codec's basis, ``None`` otherwise."""
        return self._basis

    def get_config(self) -> dict[str, Any]:
        """JSON-safe: ``id``, the one mode's key, ``dtype`` (and a fitted codec's ``basis``
        and ``basis_sha256``)."""
        config = {"id": self.codec_id, **self._mode.config(), "dtype": self._dtype.str}
        if self._basis is not None:
            config.update(self._basis.config())
        return config

    @classmethod
    def from_config(cls, config: dict[str, Any]) -> TuckerNumcodec:
        """The codec of a :meth:`get_config` dict (``id`` already removed, as numcodecs does)."""
        known = {*SETTINGS_KEYS, "dtype"}
        unknown = sorted(set(config) - known - {"id"})
        if unknown:
            raise ValueError(f"unknown keys in a tuckercodec configuration: {unknown}")
        return cls(**{key: value for key, value in config.items() if key in known})

    def __repr__(self) -> str:
        settings = describe_settings(self._mode, self._basis)
        return f"TuckerNumcodec({settings}, dtype={self._dtype.str!r})"

    def encode(self, buf: Any) -> bytes:
        """One chunk, an array of shape (frames, vertices, 3) of this codec's dtype, as a .tkc
        file (a lossless point chunk when every frame is a single point).

        Raises:
            InputError: another shape or dtype, a non-finite position, or a Fortran-ordered
                chunk (zarr's ``order="F"``, which numcodecs would read back transposed).
        """
        array = chunk_positions(buf)
        if array.dtype != self._dtype:
            raise InputError(
                f"this codec decodes to {self._dtype} (dtype={self._dtype.str!r}) but the chunk "
                f"is {array.dtype} ({array.dtype.str!r}): create the codec with "
                f"TuckerNumcodec(dtype={array.dtype.str!r}), the array's dtype, so that "
                "decoding gives it back"
            )
        if array.flags.f_contiguous and not array.flags.c_contiguous:
            raise InputError(
                "the chunk is in Fortran order (a zarr array with order='F'), which numcodecs "
                "cannot tell the decoder: use order='C' (or np.ascontiguousarray)"
            )
        return encode_chunk(array, self._mode, self._basis)

    def decode(self, buf: Any, out: Any = None) -> Any:
        """The chunk's positions: an array of shape (frames, vertices, 3) of :attr:`dtype`, or
        written into ``out`` (of exactly the chunk's size; a float ``out`` gets its own dtype)
        and ``out`` returned."""
        if out is None:
            return decode_chunk(buf, self._dtype, basis=self._basis)
        target = ensure_ndarray_like(out)
        dtype = target.dtype if target.dtype.kind == "f" else self._dtype
        # no more than out holds: a chunk declaring more is refused before it is decompressed
        most = target.nbytes // (3 * np.dtype(dtype).itemsize)
        try:
            positions = decode_chunk(buf, dtype, basis=self._basis, positions=most)
        except ValueError as error:
            if "declares more than the destination" not in str(error):
                raise
            raise ValueError(f"out has {target.nbytes} bytes, but {error}") from None
        if target.nbytes != positions.nbytes:
            raise ValueError(
                f"out has {target.nbytes} bytes, but the chunk decodes to {positions.nbytes} "
                f"({positions.shape} of {positions.dtype})"
            )
        return ndarray_copy(positions, out)


register_codec(TuckerNumcodec)
