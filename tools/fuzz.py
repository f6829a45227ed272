"""Coverage-guided fuzzing of the decoder with atheris (issue 5).

    python -m tools.fuzz --seconds 600            # a long run, one process
    python -m tools.fuzz --runs 20000             # a fixed number of inputs
    python -m tools.fuzz --replay tests/fuzz/regressions/*   # re-check saved inputs
    python -m tools.fuzz --seconds 600 --merge    # then fold new coverage into the corpus
    python -m tools.fuzz --merge-from WORK_DIR    # fold an earlier run's scratch corpus in

Every input goes through :func:`check_input`: ``tuckercodec.decode(data)``,
``tuckercodec.info(data)`` and ``Decoder(data).frame(0)``. Each must either succeed or raise
:class:`tuckercodec.FormatError` (or a subclass): the documented error for a bad file. Anything
else is a crash: any other exception, a warning (the test suite turns warnings into errors), an
input slower than ``--timeout`` seconds, a process beyond ``--memory-mb`` (an input that
allocates more than ``--report-mb`` is saved too, as ``bigmem-``), or a broken invariant
between the three entry points (``info`` must accept every file ``decode`` accepts and report
the same sizes, and frame 0 decoded alone must match frame 0 of the whole sequence, §8).

Seeds are ``spec/vectors/*.tkc`` and ``tests/fuzz/corpus/``; the run itself grows a scratch
corpus (``--work``, a temporary folder by default), so the committed corpus only changes with
``--merge``, which adds, smallest first, the inputs that execute a line transition of
tuckercodec that nothing in the corpus does yet, within ``--corpus-kb``. Crashing inputs are
written to ``tests/fuzz/crashes/``, one per distinct failure (exception type and place). Once
fixed, move each to ``tests/fuzz/regressions/`` with a name saying what it broke;
``tests/test_decoder_fuzz.py`` replays the corpus, the regressions and anything left in
``crashes/``.

Most random bytes fail a CRC-32 at once, so besides libFuzzer's byte mutations a structural
mutator rebuilds the file with correct checksums after changing one header value, one
section-table entry or one decoded payload: the semantic checks behind the checksums are
reached as often as the checksums themselves.

The fuzzing runs in a child process (``--worker``) so that the driver can stop it on time,
restart it after a hang or an out-of-memory (libFuzzer exits on those), and sum the inputs
tried over the restarts from libFuzzer's final statistics.

This module imports tuckercodec (and :mod:`tools.common`, which does) only inside functions:
the worker must import the package for the first time under atheris' instrumentation, or the
fuzzer runs blind to its coverage.
"""

from __future__ import annotations

import argparse
import contextlib
import hashlib
import json
import os
import random
import re
import shutil
import struct
import subprocess
import sys
import tempfile
import time
import traceback
import warnings
import zlib
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]  # tools.common.REPO, without importing tuckercodec
VECTORS = ROOT / "spec" / "vectors"
FUZZ_DIR = ROOT / "tests" / "fuzz"
CORPUS = FUZZ_DIR / "corpus"
CRASHES = FUZZ_DIR / "crashes"
REGRESSIONS = FUZZ_DIR / "regressions"
#: Files in the fuzz folders that are notes, not inputs.
NOT_INPUTS = {".md", ".txt", ".json"}


# ------------------------------------------------------------------------------------------
# the oracle: what every input must do


class InvariantError(AssertionError):
    """The three entry points disagree about one input."""


def check_input(data: bytes) -> str:
    """Run one input through the decoder's entry points; return ``"ok"`` or the name of the
    :class:`~tuckercodec.FormatError` subclass it ended in.

    Raises whatever else escapes (the crash), or :class:`InvariantError`.
    """
    import numpy as np

    import tuckercodec
    from tuckercodec import Decoder, FormatError

    outcome = "ok"
    sequence = None
    try:
        sequence = tuckercodec.decode(data)
    except FormatError as error:
        outcome = type(error).__name__
    try:
        header = tuckercodec.info(data)
    except FormatError as error:
        if sequence is not None:
            raise InvariantError(f"decode accepts the file but info raises {error!r}") from None
        header = None
    sizes = None if header is None else (header.frames, header.vertices)
    if sequence is not None and sizes is not None and sizes != sequence.vertices.shape[:2]:
        raise InvariantError(
            f"info says {sizes[0]} x {sizes[1]}, decode gives {sequence.vertices.shape}"
        )
    try:
        first = Decoder(data).frame(0)
    except FormatError as error:
        if sequence is not None:
            raise InvariantError(f"decode accepts the file but frame(0) raises {error!r}") from None
        first = None
    if sequence is not None and first is not None:
        reference = sequence.vertices[0]
        tolerance = 1e-9 * float(np.abs(reference).max()) + 1e-12  # spec/FORMAT.md §8
        if not np.allclose(first, reference, rtol=0, atol=tolerance):
            raise InvariantError("frame 0 decoded alone differs from frame 0 of the whole sequence")
    return outcome


def signature_of(error: BaseException) -> str:
    """A short name for a failure: its type and where in tuckercodec (or beyond) it was raised,
    so that one bug found a thousand times is saved once."""
    frames = traceback.extract_tb(error.__traceback__)
    ours = [f for f in frames if "tuckercodec" in f.filename] or frames
    place = f"{Path(ours[-1].filename).stem}-{ours[-1].lineno}" if ours else "unknown"
    return f"{type(error).__name__}-{place}"


# ------------------------------------------------------------------------------------------
# the structural mutator


def _lenient_parse(data: bytes) -> tuple[list[int], dict[str, Any], bytes] | None:
    """``(preamble fields, header, data area)`` of anything that looks like a container, or
    ``None``. Nothing is checked: the point is to edit and re-sign."""
    import msgpack

    from tuckercodec.internal import PREAMBLE, SIGNATURE

    if len(data) < 32 or data[:8] != SIGNATURE:
        return None
    fields = list(PREAMBLE.unpack_from(data, 8))
    header_length = fields[3]
    if 32 + header_length + 4 > len(data):
        return None
    try:
        header = msgpack.unpackb(data[32 : 32 + header_length], raw=False, strict_map_key=False)
    except Exception:  # any damage means "not parseable", never a crash here
        return None
    if not isinstance(header, dict):
        return None
    return fields, header, data[36 + header_length :]


def _sections(header: dict[str, Any], area: bytes) -> list[tuple[dict[str, Any], bytes]] | None:
    """The section entries with their payloads, when the table is well formed enough."""
    table = header.get("sections")
    if not isinstance(table, list):
        return None
    out = []
    for entry in table:
        if not isinstance(entry, dict):
            return None
        offset, length = entry.get("offset"), entry.get("length")
        if not (
            isinstance(offset, int) and isinstance(length, int) and offset >= 0 and length >= 0
        ):
            return None
        out.append((dict(entry), area[offset : offset + length]))
    return out


def _pack(
    fields: list[int],
    header: dict[str, Any],
    sections: list[tuple[dict[str, Any], bytes]] | None,
    area: bytes,
    rng: random.Random,
) -> bytes:
    """A file with correct CRCs (and mostly correct offsets and lengths) from edited parts."""
    import msgpack

    from tuckercodec.internal import pack_raw

    header = dict(header)
    if sections is not None:
        table, offset, parts = [], 0, []
        for entry, payload in sections:
            entry = dict(entry)
            if rng.random() < 0.95:  # now and then keep a stale field, to reach the table checks
                entry.update(offset=offset, length=len(payload), crc32=zlib.crc32(payload))
            table.append(entry)
            offset += len(payload)
            parts.append(payload)
        header["sections"] = table
        area = b"".join(parts)
    major, minor, flags, _, _ = fields
    return pack_raw(major, minor, flags, msgpack.packb(header, use_bin_type=True), area)


_EDGE_INTS = [
    0,
    1,
    -1,
    2,
    3,
    4,
    5,
    64,
    65,
    255,
    256,
    2**16,
    2**24,
    2**24 + 1,
    2**26,
    2**26 + 1,
    2**27,
    2**28,
    2**31 - 1,
    2**31,
    2**32 - 1,
    2**32,
    2**53 + 1,
    2**63 - 1,
    -(2**63),
    2**64 - 1,
    10**9,
]
_EDGE_FLOATS = [
    0.0,
    -0.0,
    1.0,
    -1.0,
    1e308,
    -1e308,
    5e-324,
    float("nan"),
    float("inf"),
    float("-inf"),
    3.4e38,
]


def _hostile_value(rng: random.Random, current: Any, depth: int = 0) -> Any:
    """A value a careless decoder might trip over, often close to ``current``."""
    import msgpack

    kind = rng.randrange(12)
    if kind == 0 and isinstance(current, int) and not isinstance(current, bool):
        return max(
            -(2**63), min(2**64 - 1, current + rng.choice([-1, 1, -2, 2, current, -current]))
        )
    if kind == 1:
        return rng.choice(_EDGE_INTS)
    if kind == 2:
        return rng.choice(_EDGE_FLOATS)
    if kind == 3:
        return rng.choice([None, True, False])
    if kind == 4:
        return rng.choice(
            [
                "",
                "FACE",
                "U1",
                "U3",
                "CORE",
                "CENT",
                "NAME",
                "qmat",
                "faces-delta",
                "msgpack-zstd",
                "x" * 17,
                "\x00",
                "é",
                "karni-gotsman-2004",
            ]
        )
    if kind == 5:
        return bytes(rng.randrange(256) for _ in range(rng.choice([0, 1, 3, 4, 8, 12, 24])))
    if kind == 6 and isinstance(current, bytes) and current:
        out = bytearray(current)
        out[rng.randrange(len(out))] = rng.randrange(256)
        return bytes(out)
    if kind == 7 and depth < 3:
        return [_hostile_value(rng, None, depth + 1) for _ in range(rng.choice([0, 1, 2, 3, 9]))]
    if kind == 8 and depth < 3:
        return {rng.choice(["shape", "planes", "id", "x"]): _hostile_value(rng, None, depth + 1)}
    if kind == 9:
        return msgpack.ExtType(rng.choice([1, 5, 127]), b"\x00" * rng.choice([0, 4]))
    if kind == 10 and isinstance(current, list) and current:
        items = list(current)
        items[rng.randrange(len(items))] = _hostile_value(rng, None, depth + 1)
        return items
    return rng.choice(_EDGE_INTS + _EDGE_FLOATS)


def _containers_in(value: Any, path: tuple[Any, ...] = ()) -> list[tuple[tuple[Any, ...], Any]]:
    """Every (path, value) in a header tree, to pick one to change."""
    out = [(path, value)]
    if isinstance(value, dict):
        for key, item in value.items():
            out.extend(_containers_in(item, (*path, key)))
    elif isinstance(value, list):
        for index, item in enumerate(value):
            out.extend(_containers_in(item, (*path, index)))
    return out


def _set_path(root: Any, path: tuple[Any, ...], value: Any) -> None:
    for key in path[:-1]:
        root = root[key]
    root[path[-1]] = value


def _mutate_header(rng: random.Random, header: dict[str, Any]) -> None:
    """Change, delete or add one value anywhere in the header (the table included)."""
    paths = [p for p, _ in _containers_in(header) if p]
    if not paths or rng.random() < 0.1:
        header[rng.choice(["vertices", "frames", "ranks", "u2", "frame_rate", "x-new"])] = (
            _hostile_value(rng, None)
        )
        return
    path = rng.choice(paths)
    parent = header
    for key in path[:-1]:
        parent = parent[key]
    current = parent[path[-1]]
    if isinstance(parent, dict) and rng.random() < 0.15:
        del parent[path[-1]]
    else:
        _set_path(header, path, _hostile_value(rng, current))


def _mutate_table(rng: random.Random, sections: list[tuple[dict[str, Any], bytes]]) -> None:
    """Reorder, repeat, drop or relabel section entries."""
    if not sections:
        return
    what = rng.randrange(5)
    index = rng.randrange(len(sections))
    if what == 0:
        sections.insert(rng.randrange(len(sections) + 1), sections[index])
    elif what == 1:
        del sections[index]
    elif what == 2:
        rng.shuffle(sections)
    elif what == 3:
        entry, payload = sections[index]
        sections[index] = (
            {**entry, "id": rng.choice(["FACE", "U1", "U3", "CORE", "CENT", "NAME", "XTRA"])},
            payload,
        )
    else:
        entry, payload = sections[index]
        sections[index] = ({**entry, "critical": not entry.get("critical")}, payload)


def _mutate_payload(rng: random.Random, sections: list[tuple[dict[str, Any], bytes]]) -> None:
    """Decompress one section, change its content and compress it again, declaring the new
    size (or a wrong one): the integer-level checks behind zstd are reached."""
    import zstandard

    if not sections:
        return
    index = rng.randrange(len(sections))
    entry, payload = sections[index]
    try:
        raw = bytearray(zstandard.ZstdDecompressor().decompress(payload, max_output_size=1 << 20))
    except zstandard.ZstdError:
        raw = bytearray(payload)
    what = rng.randrange(8)
    if raw and what <= 2:  # a few bytes to anything
        for _ in range(rng.choice([1, 1, 2, 4])):
            raw[rng.randrange(len(raw))] = rng.randrange(256)
    elif raw and what == 3:  # a run of 0xFF: the largest values a plane can hold
        start = rng.randrange(len(raw))
        raw[start : start + rng.choice([1, 4, 16])] = b"\xff" * len(raw[start : start + 16])
    elif what == 4:  # grow or shrink the content
        raw = (
            raw[: rng.randrange(len(raw) + 1)]
            if rng.random() < 0.5
            else raw + bytes(rng.choice([1, 3, 4, 81]))
        )
    elif what == 5 and isinstance(entry.get("planes"), int) and entry["planes"] in (1, 2, 3):
        # the same integers in more planes: still valid, exercises the plane arithmetic
        planes = entry["planes"]
        count = len(raw) // planes
        extra = rng.choice([0, 255])
        raw = raw + bytes([extra]) * count
        entry = {**entry, "planes": planes + 1}
    compressor = zstandard.ZstdCompressor(
        level=1, write_content_size=rng.random() < 0.9, write_checksum=rng.random() < 0.2
    )
    new = compressor.compress(bytes(raw))
    if what == 6:
        new += rng.choice(
            [b"\x00", new, struct.pack("<II", 0x184D2A50, 0)]
        )  # trailing data, a second frame
    elif what == 7 and len(new) > 6:
        new = new[: rng.randrange(4, len(new))]  # a cut frame
    sections[index] = (entry, new)


def structural_mutation(data: bytes, rng: random.Random) -> bytes | None:
    """One structural edit of a container, re-signed; ``None`` if ``data`` is not one."""
    parsed = _lenient_parse(data)
    if parsed is None:
        return None
    fields, header, area = parsed
    sections = _sections(header, area)
    what = rng.randrange(10)
    if what <= 3 or sections is None:
        _mutate_header(rng, header)
    elif what <= 5:
        _mutate_table(rng, sections)
    else:
        _mutate_payload(rng, sections)
    if rng.random() < 0.05:  # the preamble: major, minor (u16) or flags (u32)
        which = rng.randrange(3)
        fields[which] = rng.choice(
            [0, 1, 2, 0xFFFF] if which < 2 else [0, 1, 0x8000, 0x10000, 0xFFFFFFFF]
        )
    return _pack(fields, header, sections, area, rng)


def resign(data: bytes) -> bytes:
    """Make the preamble's and header's CRC-32 right again after a byte-level mutation, so
    that it is judged on what it changed, not on the checksum."""
    from tuckercodec.internal import CRC, PREAMBLE, SIGNATURE

    if len(data) < 32 or data[:8] != SIGNATURE:
        return data
    out = bytearray(data)
    CRC.pack_into(out, 28, zlib.crc32(out[:28]))
    header_length = PREAMBLE.unpack_from(out, 8)[3]
    if 32 + header_length + 4 <= len(out):
        CRC.pack_into(out, 32 + header_length, zlib.crc32(out[32 : 32 + header_length]))
    return bytes(out)


def mutate(data: bytes, max_size: int, seed: int) -> bytes:
    """libFuzzer's custom mutator: byte mutations as they are, byte mutations re-signed, or a
    structural edit. It never raises: a failed edit falls back to libFuzzer's own."""
    import atheris

    rng = random.Random(seed)
    choice = rng.random()
    try:
        if choice < 0.45:
            out = structural_mutation(data, rng)
            if out is not None and len(out) <= max_size:
                return out
        mutated = atheris.Mutate(data, max_size)
        return resign(mutated) if choice < 0.75 else mutated
    except Exception:  # the mutator must not stop the run
        return atheris.Mutate(data, max_size)


# ------------------------------------------------------------------------------------------
# seeds


def make_seeds(folder: Path = CORPUS) -> list[Path]:
    """Write small valid files of shapes the conformance vectors lack into ``folder``: a point
    cloud, one frame, three vertices, padded polygons with repeated corners, names and a frame
    rate, many planes, fixed ranks, one vertex (built by hand: the encoder needs a KG error,
    which one vertex has not). The encoder is not byte-stable, so these are written once and
    committed like the vectors."""
    import numpy as np

    import tuckercodec as tc
    from tuckercodec.internal import pack_container, sections, sheet_triangles, streams, wave_sheet

    folder.mkdir(parents=True, exist_ok=True)
    frames = wave_sheet(8, 5)
    triangles = sheet_triangles(5)
    polygons = np.array(
        [[0, 1, 6, 5, -1], [1, 2, 7, -1, -1], [2, 3, 8, 8, 7], [10, 11, 16, 15, 10]]
    )
    files = {
        "seed-triangles.tkc": tc.encode(tc.MeshSequence(frames, triangles), target_kg=1.0),
        "seed-point-cloud.tkc": tc.encode(
            tc.MeshSequence(frames, np.zeros((0, 3), int)), target_kg=1.0
        ),
        "seed-one-frame.tkc": tc.encode(tc.MeshSequence(frames[:1], triangles), target_kg=1.0),
        "seed-three-vertices.tkc": tc.encode(
            tc.MeshSequence(frames[:, :3], np.array([[0, 1, 2]])), target_kg=1.0
        ),
        "seed-polygons.tkc": tc.encode(tc.MeshSequence(frames, polygons), target_kg=1.0),
        "seed-names-rate.tkc": tc.encode(
            tc.MeshSequence(
                frames, triangles, frame_names=[f"é{n}" for n in range(8)], frame_rate=30.0
            ),
            target_kg=1.0,
        ),
        "seed-many-planes.tkc": tc.encode(
            tc.MeshSequence(frames * 1000, triangles), target_kg=1e-4
        ),
        "seed-fixed-ranks.tkc": tc.encode(tc.MeshSequence(frames, triangles), ranks=(3, 2)),
    }
    one = np.ones(1, "<f4").tobytes()
    entry, compress = sections.entry, streams.compress

    def qmat(section_id: str, shape: list[int], steps: bytes, predict: bytes) -> dict[str, Any]:
        return entry(section_id, {"planes": 1, "shape": shape, "steps": steps, "predict": predict})

    files["seed-one-vertex.tkc"] = pack_container(
        {
            "vertices": 1,
            "frames": 2,
            "ranks": [1, 1],
            "u2": [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
        },
        [
            (entry("FACE", {"shape": [0, 3], "planes": 1}), compress(b"")),
            (qmat("U1", [1, 1], one, b"\x01"), compress(b"\x02")),
            (qmat("U3", [2, 1], one, b"\x01"), compress(b"\x02\x01")),
            (qmat("CORE", [3, 1], one, b"\x00"), compress(b"\x02\x04\x06")),
            (
                qmat("CENT", [2, 3], np.ones(3, "<f4").tobytes(), b"\x01\x00\x01"),
                compress(bytes([2, 1, 3, 3, 5, 0])),
            ),
            ({"id": "note", "critical": False, "codec": "text"}, b"an ancillary section"),
        ],
        flags=0x10000,
    )
    written = []
    for name, data in files.items():
        tc.decode(data)  # every seed is valid
        (folder / name).write_bytes(data)
        written.append(folder / name)
    return written


# ------------------------------------------------------------------------------------------
# the worker (inside libFuzzer)


def _limit_address_space(memory_mb: int) -> None:
    """Cap the address space at what the process holds now plus ``memory_mb``: a huge
    allocation then fails (and is reported) even if the pages would never be touched, which
    libFuzzer's RSS limit cannot see."""
    from tools.common import MIB, proc_status_kib

    vm = proc_status_kib("VmSize")
    try:
        import resource
    except ImportError:
        return  # not Unix: the RSS limit alone
    if vm is None:
        return  # not Linux: the RSS limit alone
    limit = vm * 1024 + memory_mb * MIB
    with contextlib.suppress(OSError, ValueError):
        resource.setrlimit(resource.RLIMIT_AS, (limit, limit))


def _quiet_check(data: bytes) -> None:
    """:func:`check_input` with its outcome, warnings and exceptions ignored: for what it
    allocates or executes, judged elsewhere."""
    with warnings.catch_warnings(), contextlib.suppress(Exception):
        warnings.simplefilter("ignore")
        check_input(data)


def _traced_peak_mb(data: bytes) -> float:
    """What one input allocates at its peak under tracemalloc (numpy's buffers included), MiB."""
    from tools.common import MIB, traced_peak

    return traced_peak(lambda: _quiet_check(data)) / MIB


def run_worker(crashes: Path, memory_mb: int, report_mb: int, libfuzzer_args: list[str]) -> None:
    """Fuzz in this process until libFuzzer stops (it exits the process).

    Besides crashes, an input that itself allocates more than ``report_mb`` is saved
    (``bigmem-``): libFuzzer's own RSS limit only stops the run at ``memory_mb``. To stay cheap,
    an input is measured (under tracemalloc) only when the process's peak RSS reaches a new
    height, ``report_mb`` above the start and then each quarter of it.
    """
    import atheris

    if "tuckercodec" in sys.modules:  # see the module's docstring
        raise RuntimeError("tuckercodec was imported before atheris could instrument it")
    with atheris.instrument_imports(include=["tuckercodec"]):
        import tuckercodec  # noqa: F401 - instrumented for coverage

    import numpy  # noqa: F401 - imported before the address-space cap

    from tools.common import lifetime_peak_rss_mib

    crashes.mkdir(parents=True, exist_ok=True)
    seen = {path.name.rsplit("-", 1)[0] for path in crashes.iterdir()}
    _limit_address_space(memory_mb)
    memory_alarm = [lifetime_peak_rss_mib() + report_mb]

    def save(name: str, data: bytes, notes: str) -> None:
        path = crashes / f"{name}-{hashlib.sha1(data).hexdigest()[:12]}"
        path.write_bytes(data)
        path.with_suffix(".txt").write_text(notes)
        print(f"\n=== new crash {name}: saved to {path}\n{notes}", file=sys.stderr, flush=True)

    def test_one_input(data: bytes) -> None:
        failure = None
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # as the test suite does (pyproject: filterwarnings)
            try:
                check_input(data)
            except Exception as error:  # anything here is the finding
                failure = error
        peak = lifetime_peak_rss_mib()
        if peak > memory_alarm[0]:  # the high-water mark only rises: look at each new height once
            memory_alarm[0] = peak + report_mb / 4
            # libFuzzer's own tables grow the process by ~64 MiB steps over millions of runs
            # (replaying the corpus outside libFuzzer stays flat): blame the input only if it
            # allocates that much itself
            traced = _traced_peak_mb(data)
            if traced > report_mb:
                save(
                    f"bigmem-{int(traced)}MiB",
                    data,
                    f"this input alone allocates {traced:.0f} MiB (traced)\n",
                )
            else:
                print(
                    f"(peak RSS {peak:.0f} MiB: growth over the run; the input at hand allocates "
                    f"{traced:.1f} MiB)",
                    file=sys.stderr,
                    flush=True,
                )
        if failure is None:
            return
        name = f"crash-{signature_of(failure)}"
        if name not in seen:
            seen.add(name)
            save(name, data, "".join(traceback.format_exception(failure)))

    atheris.Setup([sys.argv[0], *libfuzzer_args], test_one_input, custom_mutator=mutate)
    atheris.Fuzz()


# ------------------------------------------------------------------------------------------
# the driver


def seed_inputs() -> list[Path]:
    """The committed seeds: the conformance vectors and the corpus."""
    paths = sorted(VECTORS.glob("*.tkc"))
    if CORPUS.is_dir():
        paths += sorted(p for p in CORPUS.iterdir() if p.is_file() and p.suffix not in NOT_INPUTS)
    return paths


def saved_inputs(*folders: Path) -> list[Path]:
    """Every input file in the given folders (notes and tracebacks left out)."""
    out: list[Path] = []
    for folder in folders:
        if folder.is_dir():
            out += sorted(p for p in folder.iterdir() if p.is_file() and p.suffix not in NOT_INPUTS)
    return out


def _stat(text: str, name: str) -> int:
    found = re.findall(rf"stat::{name}:\s+(\d+)", text)
    return int(found[-1]) if found else 0


def fuzz(args: argparse.Namespace) -> dict[str, Any]:
    """Run the worker until the time or run budget is spent; restart it after a hang or an
    out-of-memory. Returns the summary."""
    # absolute: the worker runs from the repository's root (python -m tools.fuzz)
    work = Path(args.work).resolve() if args.work else Path(tempfile.mkdtemp(prefix="tkc-fuzz-"))
    work.mkdir(parents=True, exist_ok=True)
    for path in seed_inputs():
        shutil.copy(path, work / f"seed-{path.name}")
    crashes = Path(args.crashes).resolve()
    crashes.mkdir(parents=True, exist_ok=True)
    before = set(crashes.iterdir())
    started = time.monotonic()
    runs = restarts = peak_rss = 0
    env = {
        **os.environ,
        "OPENBLAS_NUM_THREADS": "1",
        "OMP_NUM_THREADS": "1",
        "MKL_NUM_THREADS": "1",
    }
    seed = args.seed
    while True:
        left = args.seconds - (time.monotonic() - started) if args.seconds else None
        if (left is not None and left < 2) or (args.runs and runs >= args.runs):
            break
        libfuzzer = [
            f"-timeout={args.timeout}",
            f"-rss_limit_mb={args.memory_mb}",
            f"-max_len={args.max_len}",
            f"-artifact_prefix={crashes}{os.sep}",
            "-print_final_stats=1",
            f"-seed={seed}",
            "-reload=0",
        ]
        if left is not None:
            libfuzzer.append(f"-max_total_time={int(left)}")
        if args.runs:
            libfuzzer.append(f"-runs={args.runs - runs}")
        command = [
            sys.executable,
            "-m",
            "tools.fuzz",
            "--worker",
            "--crashes",
            str(crashes),
            "--memory-mb",
            str(args.memory_mb),
            "--report-mb",
            str(args.report_mb),
            "--",
            *libfuzzer,
            str(work),
        ]
        try:
            child = subprocess.run(
                command,
                env=env,
                cwd=ROOT,
                capture_output=True,
                text=True,
                check=False,
                timeout=None if left is None else left + args.timeout + 60,
            )
            output = child.stderr
        except subprocess.TimeoutExpired as expired:
            output = (
                (expired.stderr or b"").decode(errors="replace")
                if isinstance(expired.stderr, bytes)
                else (expired.stderr or "")
            )
            print("the worker overran its time and was stopped", file=sys.stderr)
        if args.verbose:
            sys.stderr.write(output)
        else:
            for line in output.splitlines():
                if (
                    "=== new crash" in line
                    or "ERROR: libFuzzer" in line
                    or line.startswith("Done ")
                ):
                    print(line, file=sys.stderr)
        executed = _stat(output, "number_of_executed_units")
        if not executed:  # no final stats (killed): the last progress line
            progress = re.findall(r"^#(\d+)\s", output, flags=re.MULTILINE)
            executed = int(progress[-1]) if progress else 0
        runs += executed
        peak_rss = max(peak_rss, _stat(output, "peak_rss_mb"))
        if "-max_total_time" in " ".join(libfuzzer) and "Done " in output and "ERROR" not in output:
            break  # finished its time normally
        if args.runs and runs >= args.runs:
            break
        restarts += 1
        seed += 1
        if restarts > 50:
            print("more than 50 restarts: stopping", file=sys.stderr)
            break
    new = sorted(str(p) for p in set(crashes.iterdir()) - before if p.suffix not in NOT_INPUTS)
    summary = {
        "inputs_tried": runs,
        "seconds": round(time.monotonic() - started, 1),
        "restarts": restarts,
        "peak_rss_mb": peak_rss,
        "new_crashes": new,
        "work_corpus": str(work),
        "work_corpus_files": sum(1 for _ in work.iterdir()),
    }
    if args.merge:
        summary["corpus_after_merge"] = merge_corpus(work, args.corpus_kb)
    if not args.work:  # a temporary scratch corpus: nothing to keep once merged
        shutil.rmtree(work, ignore_errors=True)
        summary["work_corpus"] = None
    return summary


def _arcs(data: bytes) -> set[tuple[str, int, int]]:
    """The line-to-line transitions one input executes inside tuckercodec (a coverage
    signature, as coverage.py's branch mode counts them)."""
    import tuckercodec

    package = str(Path(tuckercodec.__file__).resolve().parent)
    arcs: set[tuple[str, int, int]] = set()

    def tracer(frame: Any, event: str, arg: Any) -> Any:
        if not frame.f_code.co_filename.startswith(package):
            return None
        last = [-frame.f_code.co_firstlineno]  # entry into the function

        def local(frame: Any, event: str, arg: Any) -> Any:
            if event == "line":
                arcs.add((frame.f_code.co_filename, last[0], frame.f_lineno))
                last[0] = frame.f_lineno
            return local

        return local

    previous = sys.gettrace()
    sys.settrace(tracer)
    try:
        _quiet_check(data)  # a crash still has coverage; it is reported elsewhere
    finally:
        sys.settrace(previous)
    return arcs


def merge_corpus(work: Path, budget_kb: int) -> dict[str, int]:
    """Add to tests/fuzz/corpus the inputs of ``work`` that execute a line transition no seed
    (vectors, corpus) and no input added before executes: smallest inputs first, until the
    corpus reaches ``budget_kb``. (libFuzzer's own -merge re-executes its binary, which an
    atheris script is not, so the merge is done here on Python line coverage.)"""
    CORPUS.mkdir(parents=True, exist_ok=True)
    covered: set[tuple[str, int, int]] = set()
    for path in seed_inputs():
        covered |= _arcs(path.read_bytes())
    size = sum(p.stat().st_size for p in saved_inputs(CORPUS))
    known = {hashlib.sha1(p.read_bytes()).hexdigest() for p in seed_inputs()}
    added = 0
    for path in sorted(saved_inputs(work), key=lambda p: (p.stat().st_size, p.name)):
        data = path.read_bytes()
        digest = hashlib.sha1(data).hexdigest()
        if digest in known or size + len(data) > budget_kb * 1024:
            continue
        new = _arcs(data) - covered
        if new:
            covered |= new
            (CORPUS / f"cov-{digest[:16]}").write_bytes(data)
            size += len(data)
            added += 1
    files = saved_inputs(CORPUS)
    return {"added": added, "files": len(files), "bytes": sum(p.stat().st_size for p in files)}


def replay(paths: list[Path]) -> int:
    """Check saved inputs outside libFuzzer; print one line each; the number that fail."""
    failures = 0
    for path in paths:
        started = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            try:
                outcome = check_input(path.read_bytes())
            except Exception as error:  # reported, not raised
                outcome = f"CRASH {signature_of(error)}: {error!r}"
                failures += 1
        print(f"{path}: {outcome} ({time.perf_counter() - started:.3f} s)")
    return failures


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m tools.fuzz",
        description=__doc__.split("\n\n")[0],
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument(
        "--seconds", type=float, default=0, help="stop after this long (default: 60 unless --runs)"
    )
    parser.add_argument("--runs", type=int, default=0, help="stop after this many inputs")
    parser.add_argument(
        "--timeout", type=int, default=10, help="seconds one input may take (a hang beyond)"
    )
    parser.add_argument("--memory-mb", type=int, default=2048, help="memory one process may use")
    parser.add_argument(
        "--report-mb", type=int, default=256, help="save an input that allocates more than this"
    )
    parser.add_argument(
        "--max-len", type=int, default=8192, help="largest input libFuzzer makes, bytes"
    )
    parser.add_argument("--seed", type=int, default=1, help="libFuzzer's random seed")
    parser.add_argument("--work", help="scratch corpus folder (default: a new temporary folder)")
    parser.add_argument("--crashes", default=str(CRASHES), help="where crashing inputs go")
    parser.add_argument(
        "--merge", action="store_true", help="fold new coverage into tests/fuzz/corpus"
    )
    parser.add_argument(
        "--merge-from", type=Path, help="only merge this scratch corpus into tests/fuzz/corpus"
    )
    parser.add_argument(
        "--corpus-kb", type=int, default=300, help="size budget of the committed corpus"
    )
    parser.add_argument("--json", help="also write the summary to this file")
    parser.add_argument("--verbose", action="store_true", help="show libFuzzer's whole output")
    parser.add_argument(
        "--replay",
        nargs="*",
        type=Path,
        help="check these inputs (default: corpus and regressions)",
    )
    parser.add_argument(
        "--make-seeds", action="store_true", help="write the hand-made seeds into tests/fuzz/corpus"
    )
    parser.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    args, rest = parser.parse_known_args(argv)
    if args.worker:
        run_worker(
            Path(args.crashes), args.memory_mb, args.report_mb, [a for a in rest if a != "--"]
        )
        return 0
    if args.make_seeds:
        for path in make_seeds():
            print(f"{path}: {path.stat().st_size} bytes")
        return 0
    if args.merge_from:
        print(json.dumps(merge_corpus(args.merge_from, args.corpus_kb)))
        return 0
    if args.replay is not None:
        return 1 if replay(args.replay or saved_inputs(CORPUS, REGRESSIONS, CRASHES)) else 0
    if rest:
        parser.error(f"unknown arguments {rest}")
    if not args.seconds and not args.runs:
        args.seconds = 60
    summary = fuzz(args)
    print(json.dumps(summary, indent=2))
    if args.json:
        Path(args.json).write_text(json.dumps(summary, indent=2) + "\n")
    return 1 if summary["new_crashes"] else 0


if __name__ == "__main__":
    sys.exit(main())
