"""The compiled core against pure Python, file by file: both must give the same verdict.

The pure-Python decoder is the reference; the compiled core (``tuckercodec._native``) runs the
same steps faster. On every input, each decodes the whole file (``Decoder(data)``: its
faces, names and every frame, and ``check()`` where the file carries corrections), and the two
outcomes must be the same:

* both accept the file, and the faces, the names and every decoded value are the same bits;
* or both refuse it with a :class:`~tuckercodec.FormatError` of the same class, the same rule
  of spec/FORMAT.md §11 and the same message.

Anything else that escapes either (another exception, a Rust panic) is a failure too. The
inputs: the conformance vectors and the decoders' committed fuzz inputs, then structural
mutations of them (:func:`.container.structural_mutation`: one header value, one section-table
entry or one payload changed, every checksum made right, so that the checks behind the
checksums are reached), half of them with a few bytes changed and the CRCs re-signed as well.

    python -m tools.fuzz --differential 100000           # the vectors, then 100,000 mutations
    python -m tools.fuzz --differential 2000 --seed 7

Both implementations run in this one process (:func:`tuckercodec.system.native.pure_python`
switches the core off for the reference's turn).
"""

from __future__ import annotations

import hashlib
import random
import time
import warnings
from collections import Counter
from typing import Any

from .container import resign, structural_mutation
from .paths import CORPUS, REGRESSIONS, VECTORS, saved_inputs

#: The folders of committed .tkc inputs, beside the vectors.
TKC_TARGETS = ("decoder", "segmented")


def seed_inputs() -> list[bytes]:
    """The conformance vectors and the decoders' committed fuzz inputs, each once."""
    paths = sorted(VECTORS.glob("*.tkc"))
    paths += saved_inputs(*(root / name for root in (CORPUS, REGRESSIONS) for name in TKC_TARGETS))
    return list(dict.fromkeys(path.read_bytes() for path in paths))


def outcome(data: bytes) -> tuple[Any, ...]:
    """One implementation's verdict on a whole decode: ``("ok", digest)`` with a digest of the
    faces, names and every frame's bits, or ``("refused", class, rule, message)``, or
    ``("crashed", class, message)`` for anything else."""
    from tuckercodec import Decoder, FormatError

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            decoder = Decoder(data)
            digest = hashlib.sha256()
            digest.update(decoder.faces.tobytes())
            digest.update(repr(decoder.frame_names).encode())
            digest.update(decoder.positions().tobytes())
            if decoder.corrections is not None:
                decoder.check()
    except FormatError as error:
        return ("refused", type(error).__name__, error.rule, str(error))
    except Exception as error:  # any other escape is the finding
        return ("crashed", type(error).__name__, str(error)[:300])
    return ("ok", digest.hexdigest())


def both(data: bytes) -> tuple[tuple[Any, ...], tuple[Any, ...]]:
    """``(compiled core's outcome, pure Python's outcome)`` on one input."""
    from tuckercodec.internal import native

    compiled = outcome(data)
    with native.pure_python():
        reference = outcome(data)
    return compiled, reference


def mutations(seeds: list[bytes], count: int, seed: int) -> list[bytes]:
    """``count`` structural mutations of the seeds (some also with bytes changed, re-signed)."""
    rng = random.Random(seed)
    out: list[bytes] = []
    while len(out) < count:
        data = structural_mutation(rng.choice(seeds), rng)
        if data is None:
            continue
        if rng.random() < 0.5:  # a few bytes anywhere after the preamble, checksums re-signed
            changed = bytearray(data)
            for _ in range(rng.randint(1, 4)):
                changed[rng.randrange(32, len(changed))] = rng.randrange(256)
            data = resign(bytes(changed))
        out.append(data)
    return out


def compare(count: int, seed: int, failures_kept: int = 20) -> dict[str, Any]:
    """Run the seeds and ``count`` mutations through both implementations; a summary with the
    verdicts counted and the first disagreements (``failures``: empty when all agree)."""
    from tuckercodec.internal import native

    if native.core() is None:
        return {"failures": [f"no compiled core to compare: {native.describe()}"]}
    started = time.perf_counter()
    seeds = seed_inputs()
    inputs = seeds + mutations(seeds, count, seed)
    verdicts: Counter[str] = Counter()
    rules: Counter[str] = Counter()
    failures: list[str] = []
    for number, data in enumerate(inputs):
        compiled, reference = both(data)
        verdicts[reference[0]] += 1
        if reference[0] == "refused":
            rules[reference[2]] += 1
        if compiled != reference or compiled[0] == "crashed":
            verdicts["disagree"] += 1
            if len(failures) < failures_kept:
                failures.append(
                    f"input {number} ({len(data)} bytes, sha256 "
                    f"{hashlib.sha256(data).hexdigest()[:16]}): core {compiled!r}, "
                    f"Python {reference!r}"
                )
    return {
        "inputs": len(inputs),
        "seeds": len(seeds),
        "mutations": count,
        "seed": seed,
        "verdicts": dict(verdicts),
        "rules": dict(sorted(rules.items())),
        "seconds": round(time.perf_counter() - started, 1),
        "failures": failures,
    }
