"""tuckercodec itself: at each KG target (the encoder's own search is part of its encode), or
with any :class:`~tuckercodec.EncodeOptions` (the bound and lossless modes)."""

from __future__ import annotations

import numpy as np

from tools.bench.peers.base import Context, Trial, timed_trial
from tuckercodec import (
    EncodeOptions,
    Encoder,
    EncodeReport,
    MeshSequence,
    decode,
    encode_with_report,
)


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


def run_with_options(
    sequence: MeshSequence, options: EncodeOptions, setting: str
) -> tuple[Trial, EncodeReport]:
    """One encode with ``options`` and its decode (the whole file, :func:`tuckercodec.decode`:
    faces and float64 positions), and the encoder's report of the first encode, whose claims
    (its worst vertex) the caller checks against its own measure."""
    reports: list[EncodeReport] = []

    def encode() -> tuple[bytes, int, bytes]:
        result = Encoder(options).encode_with_report(sequence)
        reports.append(result.report)
        return result.data, result.report.section_bytes.get("FACE", 0), result.data

    def decode_(data: bytes) -> np.ndarray:
        return decode(data).vertices

    trial = timed_trial("tuckercodec", setting, encode, decode_)
    return trial, reports[0]
