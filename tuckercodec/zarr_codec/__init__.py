"""The ``tuckercodec`` codec for zarr and numcodecs: arrays of shape (frames, vertices, 3),
chunked over frames, each chunk compressed to a target KG error (extra ``[zarr]``).

Two classes, one codec id, one chunk format:

* :class:`TuckerZarrCodec` for zarr format 3, an array-to-bytes codec (the array's serializer;
  ``"tuckercodec"`` in ``zarr.json``);
* :class:`TuckerNumcodec` for zarr format 2 (the array's compressor) and plain numcodecs use
  (``numcodecs.get_codec({"id": "tuckercodec"})``).

Both are registered through entry points (``numcodecs.codecs`` and ``zarr.codecs``), so that an
array written with them opens without importing tuckercodec first. Each chunk is stored as a
.tkc file of a sequence without faces (``tuckercodec info`` and ``decode`` read it), except a
chunk in which every frame is a single point, which has nothing for a KG error to measure and
is stored exactly (:mod:`~tuckercodec.zarr_codec.chunk`).

Fitted mode (:meth:`TuckerZarrCodec.fit`, :meth:`TuckerNumcodec.fit`): most of a chunk's .tkc is
its per-vertex basis U1, which every chunk would store again. A codec fitted to the array before
it is written holds one basis in its configuration (base64 in ``zarr.json`` or ``.zarray``,
with its SHA-256), chosen so that every chunk of the fitted length meets the target with it on
its own; each chunk is then its .tkc without the U1 section's payload, put back when decoding
(:mod:`~tuckercodec.zarr_codec.fitted`). A chunk the basis cannot serve (frames added later whose
motion it does not span) is stored whole with its own basis, so the target holds for every chunk
whatever was fitted.

Why a KG target met by every chunk is met by the whole array. Write E for the squared error and
D for the square of the KG denominator ||A - E(A)||, so that KG <= t means E <= (t/100)^2 D.
E is a sum over positions, so the array's E is the sum of its chunks'. D is a sum over frames,
because E(A) holds each frame's own centroid: a chunk of whole frames has the same centroids as
the array, so the array's D is the sum of its chunks' too. Summing E_c <= (t/100)^2 D_c over the
chunks gives E <= (t/100)^2 D. When the vertices are split evenly as well, a chunk's centroid is
that of its vertices, the point nearest them in the least-squares sense, so the chunks' D sum to
at most the array's: the bound still holds.

zarr pads a partial edge chunk with the fill value. The zarr format 3 codec cuts the trailing
frames and vertices made only of it before encoding and puts them back when decoding, so the
padding costs nothing and a NaN fill value works. numcodecs is not told the chunk's shape when
decoding, so in zarr format 2 the padding is encoded. Padding frames are single points: they add
nothing to D_c and their error only adds to E_c, so the real frames meet the target with room to
spare. Padding vertices, though, lie at the fill value, and their distance from the real ones
enters D_c: in zarr format 2, split the vertices evenly or not at all. With ``ranks`` or
``target_bpfv`` there is no error target to keep.

A write that covers only part of a chunk makes zarr decode the chunk, update it and encode it
again: the frames already there are then encoded a second time, and their error is measured
against their decoded values, not the original ones. Write whole chunks (``dask.array.to_zarr``
with matching chunks does) to keep the guarantee against the original positions.

A chunk stored below float64 (float32, float16) is checked after its decoded positions are
rounded to its dtype, and encoded again at a tighter target if the rounding took it over.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from .chunk import ChunkMode, decode_chunk, encode_chunk
from .fitted import FittedBasis

if TYPE_CHECKING:
    from .numcodec import TuckerNumcodec
    from .zarr3 import TuckerZarrCodec

__all__ = [
    "ChunkMode",
    "FittedBasis",
    "TuckerNumcodec",
    "TuckerZarrCodec",
    "decode_chunk",
    "encode_chunk",
]


def __getattr__(name: str) -> Any:
    # each class needs its library: importing one must not require the other's
    if name == "TuckerNumcodec":
        from .numcodec import TuckerNumcodec

        return TuckerNumcodec
    if name == "TuckerZarrCodec":
        from .zarr3 import TuckerZarrCodec

        return TuckerZarrCodec
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
