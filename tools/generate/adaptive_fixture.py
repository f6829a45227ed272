"""Write tests/js/adaptive_fixture.json: adaptive streams (spec/FORMAT.md §6.14) made by the
reference coder (``tuckercodec/format/adaptive.py``), with what the reference decoder makes of
each, for the JavaScript decoder's unit test (tests/js/adaptive.test.mjs, run by ``npm test``
without Python).

    python -m tools.generate.adaptive_fixture            # tests/js/adaptive_fixture.json
    python -m tools.generate.adaptive_fixture --check    # exit 1 unless it is as committed

Each case is a payload (base64), the section's rows, cols and planes, its coding order (the
ascending one, or U1's from a small mesh given by its faces, with the reference's order, sources
and ends so that the JavaScript order is checked too) and the verdict: the stream's integers in
stream order (column-major), or the rule it breaks. The verdict is the reference's: its
``decode_columns``, then every integer zigzagged below 2^(8·planes) (R46 otherwise), as §6.14
says. Cases: streams of small, wide and boundary integers in both orders; the stream of no
integers; each way a stream is refused (too short, a first byte other than 0, cut, a byte after
its end, a last ``code`` not below ``range``, more integers than 32768 per byte, an integer
outside the planes); and streams damaged at seeded random bytes, whatever the reference makes of
them. Cases of 5 to 8 planes (``wide``: the 64-bit integers of a RESD chunk, §6.9, version 1.7,
which the JavaScript decodes with decodeAdaptiveWide) give their integers as decimal strings,
as JSON's numbers hold only 53 bits. Cases marked ``uniform`` are uniform streams (§6.8,
version 1.9: faces-traverse's places with ``ranks`` 1, the JavaScript's decodeUniform) of
``count`` values over ``total``, made and judged by ``tuckercodec/format/uniform.py``: places at
both ends of each range and on both sides of the short codes' bound, totals from 1 to 2^31, each
way such a stream is refused, and damaged copies. Everything is deterministic (seeded, pure Python
integers): ``--check`` regenerates it.
"""

from __future__ import annotations

import argparse
import base64
import json
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from tuckercodec import FormatError
from tuckercodec.internal import adaptive, mesh_prediction, uniform

OUT = Path(__file__).resolve().parents[2] / "tests" / "js" / "adaptive_fixture.json"
#: Damaged copies of a stream, each with one byte changed at a seeded place.
DAMAGED_PER_STREAM = 12


def mesh_faces() -> tuple[np.ndarray, int]:
    """A small mesh: a 5 × 6 grid of triangles, a quad strip of 8 vertices (padded with -1
    beside the triangles) and two vertices on no face; ``(faces M × 4, K)``."""
    rows, cols = 5, 6
    faces: list[list[int]] = []
    for r in range(rows - 1):
        for c in range(cols - 1):
            a, b = r * cols + c, r * cols + c + 1
            faces += [[a, b, a + cols, -1], [b, b + cols, a + cols, -1]]
    base = rows * cols
    for q in range(3):
        a = base + 2 * q
        faces.append([a, a + 2, a + 3, a + 1])
    return np.array(faces, dtype=np.int64), base + 8 + 2


@dataclass(frozen=True)
class Section:
    """What a stream is decoded as: its section's shape and planes, and its coding order."""

    rows: int
    cols: int
    planes: int
    order: adaptive.CodingOrder


def sequence(rows: int, cols: int, planes: int) -> Section:
    """A section coded in the ascending order (U3, CORE, CENT)."""
    return Section(rows, cols, planes, adaptive.sequence_order(rows))


def verdict(payload: bytes, section: Section) -> dict[str, Any]:
    """The reference's integers (stream order) or rule for a stream."""
    try:
        columns = adaptive.decode_columns(
            payload, section.cols, section.rows, section.order, "fixture"
        )
    except FormatError as error:
        return {"rule": error.rule}
    values = [int(v) for v in columns.reshape(-1)]
    if any((2 * v if v >= 0 else -2 * v - 1) >= 2 ** (8 * section.planes) for v in values):
        return {"rule": "R46-adaptive-stream"}
    return {"integers": values}


def case(name: str, payload: bytes, section: Section, **extra: Any) -> dict[str, Any]:
    found = verdict(payload, section)
    if section.planes > 4:
        extra = {**extra, "wide": True}
        if "integers" in found:
            found = {"integers": [str(v) for v in found["integers"]]}
    return {
        "name": name,
        "payload": base64.b64encode(payload).decode(),
        "rows": section.rows,
        "cols": section.cols,
        "planes": section.planes,
        "mesh": section.order.mesh,
        **extra,
        **found,
    }


def encoded(name: str, columns: np.ndarray, section: Section, **extra: Any) -> dict[str, Any]:
    """The case of ``columns`` (cols, rows) as the reference encodes them."""
    return case(name, adaptive.encode_columns(columns, section.order), section, **extra)


def damaged(name: str, payload: bytes, section: Section, seed: int) -> list[dict[str, Any]]:
    """Copies of a stream with one byte replaced, at seeded places (the first byte never: that
    case is its own)."""
    rng = np.random.default_rng(seed)
    out = []
    for n in range(DAMAGED_PER_STREAM):
        broken = bytearray(payload)
        at = int(rng.integers(1, len(payload)))
        broken[at] = (broken[at] + int(rng.integers(1, 256))) % 256
        out.append(case(f"{name}-damaged-{n}", bytes(broken), section))
    return out


def spread(rng: np.random.Generator, shape: tuple[int, int]) -> np.ndarray:
    """Integers whose magnitudes are spread over every bit length up to 17: 2^k plus or minus
    a little, k uniform in 0..16, either sign."""
    k = rng.integers(0, 17, size=shape)
    magnitude = (1 << k) + rng.integers(-1, 2, size=shape) * (k > 1)
    return (magnitude * rng.choice([-1, 1], size=shape)).astype(np.int64)


def sequence_cases() -> list[dict[str, Any]]:
    """U3, CORE and CENT's ascending order."""
    rng = np.random.default_rng(1)
    small = np.rint(rng.laplace(0.0, 2.0, size=(3, 40)) * (rng.random((3, 40)) < 0.7))
    small[:, 5:9] = 0  # a run of zeros
    section = sequence(40, 3, 1)
    payload = adaptive.encode_columns(small.astype(np.int64), section.order)
    out = [case("sequence-small", payload, section)]
    out += damaged("sequence-small", payload, section, seed=11)
    out.append(case("sequence-cut", payload[:-1], section))
    out.append(case("sequence-byte-after", payload + b"\0", section))
    out.append(case("sequence-first-byte", b"\x01" + payload[1:], section))
    out.append(case("sequence-short", b"\0\0\0\0", sequence(0, 0, 1)))
    none = adaptive.encode_columns(np.zeros((0, 0), dtype=np.int64), sequence(0, 0, 1).order)
    out.append(case("sequence-none", none, sequence(0, 0, 1)))
    # read to its end, but code (0xFFFFFFFF) is not below range (0xFFFFFFFF); a stream with
    # integers whose code is not below its range decodes ones until an exponent is too long
    out.append(case("sequence-bad-ending", b"\0\xff\xff\xff\xff", sequence(0, 0, 1)))
    # more integers than 32768 per byte of payload: refused before anything is decoded
    out.append(case("sequence-too-many", none, sequence(32768 * len(none) + 1, 1, 1)))
    wide = rng.integers(-(2**31), 2**31, size=(2, 30), dtype=np.int64)
    wide[0, :6] = [-(2**31), 2**31 - 1, 0, 1, -1, 2**16]
    wide[1, :4] = [2**30, -(2**30), 3, -3]
    out.append(encoded("sequence-wide", wide, sequence(30, 2, 4)))
    # magnitudes of every size up to 2^17, so that every class of both kinds is met
    out.append(encoded("sequence-classes", spread(rng, (3, 200)), sequence(200, 3, 3)))
    one = np.array([[5], [-7], [0], [1 << 20], [-(1 << 12)]], dtype=np.int64)
    out.append(encoded("sequence-one-row", one, sequence(1, 5, 3)))
    return out + bound_cases()


def bound_cases() -> list[dict[str, Any]]:
    """Integers at the planes' bound: -2^(8P-1) and 2^(8P-1)-1 fit, 2^(8P-1) does not, nor an
    integer of 41 bits in four planes."""
    out = []
    for name, values, planes in [
        ("bound-fits", [127, -128, 0], 1),
        ("bound-positive", [128, 0, 0], 1),
        ("bound-negative", [0, -129, 0], 1),
        ("bound-fits-2", [-(2**15), 2**15 - 1, 1], 2),
        ("bound-positive-2", [1, 2**15, 1], 2),
        ("bound-long", [2**40, 0, 0], 4),
    ]:
        out.append(encoded(name, np.array([values], dtype=np.int64), sequence(3, 1, planes)))
    return out


def wide_cases() -> list[dict[str, Any]]:
    """Integers of up to 63 bits in 5 to 8 planes (a RESD chunk's, §6.9), in the ascending
    order: magnitudes of every bit length, the bounds of 5 and 8 planes, an integer of 64 bits
    (-2^63, which only the reference's Python coder writes), and damaged copies."""
    rng = np.random.default_rng(3)
    out = []
    for planes in (5, 6, 7, 8):
        top = 8 * planes - 1  # magnitudes below 2^top fit
        k = rng.integers(0, top, size=(4, 50))
        low = rng.integers(0, 1 << 62, size=(4, 50), dtype=np.int64)
        leading = np.left_shift(np.int64(1), k)  # a bit length k + 1, the bits under it random
        columns = (leading | (low & (leading - 1))) * rng.choice([-1, 1], size=(4, 50))
        columns[:, 10:14] = 0  # a run of zeros
        columns[0, 20:23] = [1, -1, 2]
        section = sequence(50, 4, planes)
        payload = adaptive.encode_columns(columns, section.order)
        out.append(case(f"wide-{planes}", payload, section))
        if planes in (5, 8):
            # mostly small integers, a few wide: damage leaves some such streams readable
            mixed = np.rint(rng.laplace(0.0, 30.0, size=(6, 40))).astype(np.int64)
            mixed[rng.random((6, 40)) < 0.05] = columns[0, np.argmax(np.abs(columns[0]))]
            section = sequence(40, 6, planes)
            payload = adaptive.encode_columns(mixed, section.order)
            out.append(case(f"wide-mixed-{planes}", payload, section))
            out += damaged(f"wide-mixed-{planes}", payload, section, seed=20 + planes)
            for back in (2, 3, 4, 5):  # in the last bytes, where damage may leave it readable
                broken = bytearray(payload)
                broken[-back] ^= 0x5A
                name = f"wide-mixed-{planes}-damaged-end-{back}"
                out.append(case(name, bytes(broken), section))
    for name, values, planes in [
        ("wide-bound-fits-5", [2**39 - 1, -(2**39), 0], 5),
        ("wide-bound-positive-5", [2**39, 0, 0], 5),
        ("wide-bound-negative-5", [0, -(2**39) - 1, 0], 5),
        ("wide-bound-fits-8", [2**63 - 1, -(2**63 - 1), 1], 8),
        ("wide-small-8", [0, -3, 2**32, -(2**32), 2**31], 8),
    ]:
        out.append(
            encoded(name, np.array([values], dtype=np.int64), sequence(len(values), 1, planes))
        )
    longest = sequence(3, 1, 8)
    payload = adaptive._encode_columns_python(
        np.array([[0, -(2**63), 0]], dtype=np.int64), longest.order
    )
    out.append(case("wide-64-bits", payload, longest))
    return out


def mesh_cases() -> list[dict[str, Any]]:
    """U1's mesh order on a small mesh, smooth columns and rough ones."""
    faces, vertices = mesh_faces()
    steps = mesh_prediction(faces, vertices).mean_steps
    order = adaptive.mesh_order(vertices, steps.rows, steps.sources, steps.source_ends)
    rng = np.random.default_rng(2)
    columns = np.cumsum(rng.integers(-3, 4, size=(4, vertices)), axis=1).astype(np.int64)
    columns[2] = rng.integers(-300, 301, size=vertices)
    columns[3] = spread(rng, (1, vertices))[0]
    mesh = {
        "faces": faces.reshape(-1).tolist(),
        "face_count": int(faces.shape[0]),
        "face_width": int(faces.shape[1]),
        "order": order.order.tolist(),
        "ends": order.ends.tolist(),
        "sources": order.sources.tolist(),
    }
    section = Section(vertices, 4, 3, order)
    payload = adaptive.encode_columns(columns, order)
    out = [case("mesh", payload, section, topology=mesh)]
    out += damaged("mesh", payload, section, seed=12)
    return out


def uniform_case(name: str, payload: bytes, count: int, total: int) -> dict[str, Any]:
    """A uniform stream's case: its values, or the rule the reference refuses it with."""
    try:
        found: dict[str, Any] = {
            "integers": uniform.decode_uniform(payload, count, total, "fixture").tolist()
        }
    except FormatError as error:
        found = {"rule": error.rule}
    text = base64.b64encode(payload).decode()
    return {"name": name, "uniform": True, "payload": text, "count": count, "total": total, **found}


def uniform_places(rng: np.random.Generator, count: int, total: int) -> np.ndarray:
    """``count`` places over ``total`` (place i in 0..total-i-1): random ones, with the
    ends of each range and the values beside its short codes' bound u (u - 1 takes k bits,
    u takes k + 1) among them."""
    n = total - np.arange(count)
    places = (rng.random(count) * n).astype(np.int64)
    k = np.floor(np.log2(n)).astype(np.int64)
    u = (np.int64(2) << k) - n
    kind = rng.integers(0, 6, size=count)
    places = np.where(kind == 0, 0, places)
    places = np.where(kind == 1, n - 1, places)
    places = np.where(kind == 2, u - 1, places)
    return np.where((kind == 3) & (u < n), u, places)


def uniform_cases() -> list[dict[str, Any]]:
    """Uniform streams (§6.8, version 1.9) as the reference codes them, and refused ones."""
    rng = np.random.default_rng(4)
    out = []
    for total in (1, 2, 3, 5, 8, 100, 1000, 4097):
        count = min(total, 300)
        places = uniform_places(rng, count, total)
        payload = uniform.encode_uniform(places, total)
        out.append(uniform_case(f"uniform-{total}", payload, count, total))
    top = 1 << 31  # the largest total: places of 31 bits, n = 2^31 exactly at first
    places = np.array([top - 1, 0, top - 3, (1 << 30) - 1, 1 << 30], dtype=np.int64)
    payload = uniform.encode_uniform(places, top)
    out.append(uniform_case("uniform-2-31", payload, len(places), top))
    out.append(uniform_case("uniform-2-31-some", payload[:-1], len(places), top))
    places = uniform_places(rng, 200, 700)
    payload = uniform.encode_uniform(places, 700)
    out.append(uniform_case("uniform-700-of-200", payload, 200, 700))
    for n in range(DAMAGED_PER_STREAM):
        broken = bytearray(payload)
        at = int(rng.integers(1, len(payload)))
        broken[at] = (broken[at] + int(rng.integers(1, 256))) % 256
        out.append(uniform_case(f"uniform-700-of-200-damaged-{n}", bytes(broken), 200, 700))
    for back in (2, 3, 4, 5):  # in the last bytes, where damage may leave it readable
        broken = bytearray(payload)
        broken[-back] ^= 0x5A
        out.append(uniform_case(f"uniform-700-of-200-damaged-end-{back}", bytes(broken), 200, 700))
    out.append(uniform_case("uniform-cut", payload[:-1], 200, 700))
    out.append(uniform_case("uniform-byte-after", payload + b"\0", 200, 700))
    out.append(uniform_case("uniform-first-byte", b"\x01" + payload[1:], 200, 700))
    none = uniform.encode_uniform(np.zeros(0, dtype=np.int64), 5)
    out.append(uniform_case("uniform-none", none, 0, 5))
    out.append(uniform_case("uniform-short", b"\0\0\0\0", 0, 5))
    out.append(uniform_case("uniform-bad-ending", b"\0\xff\xff\xff\xff", 0, 5))
    # more values than 32768 per byte: refused before anything is decoded
    many = 32768 * len(none) + 1
    out.append(uniform_case("uniform-too-many", none, many, many))
    return out


def fixture() -> str:
    cases = sequence_cases() + wide_cases() + mesh_cases() + uniform_cases()
    return json.dumps({"about": __doc__.split("\n\n")[0], "cases": cases}, indent=1) + "\n"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--check", action="store_true", help="exit 1 unless the file is current")
    args = parser.parse_args(argv)
    text = fixture()
    if args.check:
        current = OUT.read_text() if OUT.exists() else ""
        if current != text:
            print(f"{OUT} is not what this script writes: run it again", file=sys.stderr)
            return 1
        return 0
    OUT.write_text(text)
    print(f"wrote {OUT}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
