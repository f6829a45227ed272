"""The JavaScript decoder (tuckercodec/web/tkc/, written from spec/FORMAT.md) against the
conformance vectors of spec/vectors (§12), in node: every valid vector decodes to the digests,
header facts, names and reconstruction its JSON gives, and every invalid one fails with its rule
and error class, as the Python decoder does. The same observations in a browser are in
test_viewer_browser.py."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest
from js_decoder import run_node

VECTORS = Path(__file__).resolve().parents[1] / "spec" / "vectors"
EXPECTED = {p.name: json.loads(p.read_text()) for p in sorted(VECTORS.glob("*.json"))}
VALID = [name for name, e in EXPECTED.items() if e["valid"]]
INVALID = [name for name, e in EXPECTED.items() if not e["valid"]]


@pytest.fixture(scope="module")
def observed() -> dict[str, Any]:
    """What the JavaScript decoder makes of every vector (tests/js/conformance_observe.mjs)."""
    return run_node("conformance.mjs", VECTORS)


def test_every_vector_observed(observed):
    assert sorted(observed) == sorted(EXPECTED)
    crashed = {name: o["message"] for name, o in observed.items() if o.get("crashed")}
    assert not crashed, f"the decoder threw something other than a TkcError: {crashed}"


@pytest.mark.parametrize("name", VALID)
def test_valid_vector(observed, name):
    expected, got = EXPECTED[name], observed[name]
    assert got["accepted"], got.get("message")
    for key, value in expected["header"].items():
        assert got["header"][key] == value, key
    assert got["frame_names"] == expected["frame_names"]
    assert got["segments"] == expected.get("segments", [])
    assert got["sha256"] == expected["sha256"]  # bit for bit (§6.3)
    reference = got["reference"]
    tolerance = expected["tolerance"]["relative_to_max_abs"] * reference["max_abs_reference"]
    assert reference["max_abs_difference"] <= tolerance + 1e-12  # §8


@pytest.mark.parametrize("name", INVALID)
def test_invalid_vector(observed, name):
    expected, got = EXPECTED[name], observed[name]
    assert not got["accepted"], f"accepted a file that breaks {expected['rule']}"
    assert (got["rule"], got["kind"]) == (expected["rule"], expected["error"]), got["message"]
    assert got["message"].endswith(f"[{expected['rule']}]")
