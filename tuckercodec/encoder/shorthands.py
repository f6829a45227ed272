"""The one-call encodes: each builds an :class:`~.encoder.Encoder` from its options (or
:class:`~.options.EncodeOptions`' fields as keywords, checked in
:func:`~.options.resolve_options` alone) and runs it once."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from ..decomposition.analysis import Analysis
from ..model.sequence import MeshSequence
from ..model.sources import FrameSource
from ..system.parallel import Executor
from .encoder import Encoder
from .options import EncodeOptions, resolve_options
from .results import EncodeResult
from .segmented import SharedBasis


def encode_with_report(
    sequence: MeshSequence,
    options: EncodeOptions | None = None,
    *,
    analysis: Analysis | None = None,
    executor: Executor | None = None,
    **fields: Any,
) -> EncodeResult:
    """Encode a sequence; the file's bytes and a report of ranks, errors and sizes.

    Shorthand for ``Encoder(resolve_options(options, **fields), executor=executor)
    .encode_with_report(sequence)``.

    Args:
        sequence: the mesh sequence (any number of frames; not every frame a single point).
        options: what to encode for, whole (default: a KG error of 0.1).
        analysis: the sequence's :func:`~tuckercodec.analyze` result, if already computed.
        executor: with segments, where the passes' tasks run (:mod:`tuckercodec.system.parallel`);
            the bytes written do not depend on it.
        **fields: any field of :class:`EncodeOptions` by name (``target_kg``, ``ranks``,
            ``max_error``, ``lossless``, ``level``...), put over ``options`` as
            :func:`dataclasses.replace` does (:func:`resolve_options`).

    Raises:
        TypeError: a keyword that is not a field of :class:`EncodeOptions`.
        InputError: the sequence cannot be encoded (every frame a single point, or coordinates
            float64 cannot square).
        UnreachableTargetError: no file of the format meets the target: a ``target_bpfv``
            below the coarsest file's size, or an error target too small for the format's
            32-bit integers (centroids far from the origin, or a target within rounding of 0).
        ValueError: an option that is out of range (ranks, a non-positive target), or two
            modes at once.
    """
    encoder = Encoder(resolve_options(options, **fields), executor=executor)
    return encoder.encode_with_report(sequence, analysis=analysis)


def encode_source(
    frames: FrameSource,
    options: EncodeOptions | None = None,
    *,
    executor: Executor | None = None,
    progress: Callable[[str], None] | None = None,
    **fields: Any,
) -> EncodeResult:
    """Encode an opened sequence (:func:`tuckercodec.io.open_frames`): whole (loaded, format
    1.0) when that fits ``max_memory`` (default half the machine's memory) and no
    ``segment_frames`` is given, else in segments read a range at a time (format 1.1).
    Shorthand for :meth:`Encoder.encode_source`; ``options``, ``executor`` and ``**fields``
    (any field of :class:`EncodeOptions` by name, over ``options``) as for
    :func:`encode_with_report`; ``progress`` is called with a line as each pass starts."""
    encoder = Encoder(resolve_options(options, **fields), executor=executor, progress=progress)
    return encoder.encode_source(frames)


def encode_frames(
    source: FrameSource,
    options: EncodeOptions | None = None,
    *,
    executor: Executor | None = None,
    progress: Callable[[str], None] | None = None,
    shared_basis: SharedBasis | None = None,
    **fields: Any,
) -> EncodeResult:
    """Encode a sequence read a range of frames at a time into a segmented file (format 1.1),
    however small: shorthand for :meth:`Encoder.encode_segments`. ``options``, ``executor``,
    ``progress`` and ``**fields`` (any field of :class:`EncodeOptions` by name, over
    ``options``) as for :func:`encode_source`; the KG error is of the whole sequence.
    ``shared_basis``: a shared U1 to use as it is
    (:func:`tuckercodec.encoder.segmented.shared_basis_of`)."""
    encoder = Encoder(resolve_options(options, **fields), executor=executor, progress=progress)
    return encoder.encode_segments(source, shared_basis=shared_basis)


def encode(sequence: MeshSequence, options: EncodeOptions | None = None, **fields: Any) -> bytes:
    """Encode a sequence into the bytes of a file (``spec/FORMAT.md``).

    The options are given whole (``options``, an :class:`EncodeOptions`), as keywords named as
    its fields (``target_kg=0.05``, ``ranks=(i, k)``, ``target_bpfv``, ``max_error``,
    ``lossless=True``, ``level``...), or both, the keywords put over ``options`` as
    :func:`dataclasses.replace` does; a keyword that is not a field is a ``TypeError``. One
    mode at a time; the default is a KG error of 0.1 that the decoded sequence never exceeds.
    :func:`encode_with_report` also says what was chosen and measured.
    """
    return Encoder(resolve_options(options, **fields)).encode(sequence)
