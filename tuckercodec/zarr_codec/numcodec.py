"""The numcodecs codec ``tuckercodec``: zarr format 2 arrays, and plain numcodecs use."""

from __future__ import annotations

from typing import Any

import numpy as np

from ..errors import InputError
from ..optional import import_optional
from .chunk import ChunkMode, checked_dtype, chunk_mode, chunk_positions, decode_chunk, encode_chunk

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
    """

    codec_id = "tuckercodec"

    def __init__(
        self,
        target_kg: float | None = None,
        ranks: tuple[int, int] | list[int] | None = None,
        target_bpfv: float | None = None,
        dtype: Any = "<f8",
    ) -> None:
        self._mode: ChunkMode = chunk_mode(target_kg, ranks, target_bpfv)
        self._dtype: np.dtype[Any] = checked_dtype(dtype)

    @property
    def mode(self) -> ChunkMode:
        """The encoder's mode every chunk gets."""
        return self._mode

    @property
    def dtype(self) -> np.dtype[Any]:
        """The dtype of decoded chunks."""
        return self._dtype

    def get_config(self) -> dict[str, Any]:
        """JSON-safe: ``id``, the one mode's key, ``dtype``."""
        return {"id": self.codec_id, **self._mode.config(), "dtype": self._dtype.str}

    @classmethod
    def from_config(cls, config: dict[str, Any]) -> TuckerNumcodec:
        """The codec of a :meth:`get_config` dict (``id`` already removed, as numcodecs does)."""
        known = {"target_kg", "ranks", "target_bpfv", "dtype"}
        unknown = sorted(set(config) - known - {"id"})
        if unknown:
            raise ValueError(f"unknown keys in a tuckercodec configuration: {unknown}")
        return cls(**{key: value for key, value in config.items() if key in known})

    def __repr__(self) -> str:
        settings = ", ".join(f"{key}={value!r}" for key, value in self._mode.config().items())
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
        return encode_chunk(array, self._mode)

    def decode(self, buf: Any, out: Any = None) -> Any:
        """The chunk's positions: an array of shape (frames, vertices, 3) of :attr:`dtype`, or
        written into ``out`` (of exactly the chunk's size; a float ``out`` gets its own dtype)
        and ``out`` returned."""
        if out is None:
            return decode_chunk(buf, self._dtype)
        target = ensure_ndarray_like(out)
        dtype = target.dtype if target.dtype.kind == "f" else self._dtype
        positions = decode_chunk(buf, dtype)
        if target.nbytes != positions.nbytes:
            raise ValueError(
                f"out has {target.nbytes} bytes, but the chunk decodes to {positions.nbytes} "
                f"({positions.shape} of {positions.dtype})"
            )
        return ndarray_copy(positions, out)


register_codec(TuckerNumcodec)
