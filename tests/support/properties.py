"""Property tests: the hypothesis settings and strategies the format and reader tests share."""

from __future__ import annotations

import os
import sys
import tempfile
from pathlib import Path
from typing import Any

from hypothesis import HealthCheck, settings
from hypothesis import strategies as st

#: Hypothesis for the format tests: deterministic in CI and no example database written into
#: the repository (each test sets its own ``max_examples``).
HYPOTHESIS_SETTINGS: dict[str, Any] = {
    "deadline": None,
    "database": None,
    "derandomize": True,
    "suppress_health_check": [HealthCheck.too_slow, HealthCheck.data_too_large],
}

#: ``TUCKERCODEC_HYPOTHESIS_EXAMPLES`` scales the number of examples of each property test of
#: the readers (for a long local run); CI runs the default, derandomized so that every run tries
#: the same inputs (the long, random exploration is tools/fuzz's job).
EXAMPLES = int(os.environ.get("TUCKERCODEC_HYPOTHESIS_EXAMPLES", "0")) or None
PROPERTY = settings(
    max_examples=EXAMPLES or 400,
    deadline=None,
    database=None,
    derandomize=EXAMPLES is None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)

#: Values of any msgpack type, out-of-range numbers and odd floats among them.
msgpack_leaves = (
    st.none()
    | st.booleans()
    | st.integers(-(2**63), 2**64 - 1)
    | st.sampled_from([0, 1, -1, 2, 3, 81, 24, 6])
    | st.floats(allow_nan=True, allow_infinity=True)
    | st.text(max_size=20)
    | st.binary(max_size=40)
)
#: Anything msgpack can hold: leaves in lists and maps, nested.
msgpack_values = st.recursive(
    msgpack_leaves,
    lambda children: (
        st.lists(children, max_size=6) | st.dictionaries(st.text(max_size=10), children, max_size=6)
    ),
    max_leaves=25,
)


@st.composite
def mutations(draw: st.DrawFn, base: bytes, tokens: list[bytes]) -> bytes:
    """``base`` after 1 to 8 random edits: bytes flipped, set, inserted, deleted, lines
    duplicated or dropped, tokens inserted, or the end cut off."""
    data = bytearray(base)
    for _ in range(draw(st.integers(1, 8))):
        kind = draw(st.sampled_from(["flip", "set", "insert", "delete", "token", "line", "cut"]))
        at = draw(st.integers(0, len(data)))
        if kind == "flip" and at < len(data):
            data[at] ^= 1 << draw(st.integers(0, 7))
        elif kind == "set" and at < len(data):
            data[at] = draw(st.integers(0, 255))
        elif kind == "insert":
            data[at:at] = draw(st.binary(min_size=1, max_size=8))
        elif kind == "delete":
            del data[at : at + draw(st.integers(1, 16))]
        elif kind == "token":
            data[at:at] = draw(st.sampled_from(tokens))
        elif kind == "line":
            lines = bytes(data).split(b"\n")
            row = draw(st.integers(0, len(lines) - 1))
            if draw(st.booleans()):
                lines.insert(row, lines[row])
            else:
                del lines[row]
            data = bytearray(b"\n".join(lines))
        elif kind == "cut":
            del data[at:]
    return bytes(data)


def scratch_folder() -> Path:
    """A scratch folder for the property tests of one module (function-scoped fixtures do not
    mix with ``given``); the module removes it in its ``teardown_module``."""
    return Path(tempfile.mkdtemp(prefix="tkc-property-"))


def report_examples(examples_run: dict[str, int]) -> None:
    """Print how many examples each property test of a module ran (shown with ``pytest -s``)."""
    if examples_run:
        sys.stdout.write(
            "\nhypothesis examples run: "
            + ", ".join(f"{name} {count}" for name, count in examples_run.items())
            + f"; total {sum(examples_run.values())}\n"
        )
