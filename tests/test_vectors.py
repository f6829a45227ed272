"""Conformance: every vector in spec/vectors/ decodes as its JSON says (spec/FORMAT.md §12)."""

from __future__ import annotations

import hashlib
import json
import re
from pathlib import Path

import numpy as np
import pytest

import tuckercodec
from tuckercodec import Decoder, info

SPEC = Path(__file__).resolve().parents[1] / "spec"
VECTORS = sorted((SPEC / "vectors").glob("*.json"))


def _load(path: Path) -> tuple[dict, bytes]:
    expected = json.loads(path.read_text())
    return expected, (path.parent / expected["file"]).read_bytes()


def test_vectors_exist():
    assert len(VECTORS) >= 3, "spec/vectors/ is empty: run python tools/make_vectors.py"


@pytest.mark.parametrize("path", [p for p in VECTORS if json.loads(p.read_text())["valid"]], ids=lambda p: p.stem)
def test_valid_vector(path):
    expected, data = _load(path)
    decoder = Decoder(data)
    header = info(data)
    for key, value in expected["header"].items():
        got = getattr(header, key)
        assert (list(got) if isinstance(got, tuple) else got) == value, key
    assert decoder.frame_names == expected["frame_names"]
    arrays = {"faces": (decoder.faces, "<i8"), "u1": (decoder.u1, "<f8"), "u3": (decoder.u3, "<f8"),
              "core": (decoder.core, "<f8"), "centroids": (decoder.centroids, "<f8")}
    for name, (array, dtype) in arrays.items():
        digest = hashlib.sha256(np.ascontiguousarray(array, dtype=dtype).tobytes()).hexdigest()
        assert digest == expected["sha256"][name], f"dequantized {name} differs"
    reference = np.load(path.parent / expected["reference"], allow_pickle=False)
    positions = decoder.positions()
    scale = np.abs(reference).max()
    tolerance = expected["tolerance"]["relative_to_max_abs"] * scale + 1e-12  # spec/FORMAT.md §8
    np.testing.assert_allclose(positions, reference, rtol=0, atol=tolerance)
    # any single frame decodes alone to the same positions
    last = reference.shape[0] - 1
    np.testing.assert_allclose(decoder.frame(last), reference[last], rtol=0, atol=tolerance)


@pytest.mark.parametrize("path", [p for p in VECTORS if not json.loads(p.read_text())["valid"]], ids=lambda p: p.stem)
def test_invalid_vector(path):
    expected, data = _load(path)
    error = getattr(tuckercodec, expected["error"])
    with pytest.raises(error) as raised:
        Decoder(data)
    assert type(raised.value) is error  # the most specific class, not just a subclass
    assert expected["message_contains"] in str(raised.value)


def test_every_rule_of_the_spec_has_a_vector():
    text = (SPEC / "FORMAT.md").read_text()
    rules = set(re.findall(r"\b(R\d\d-[a-z0-9-]+[a-z0-9])", text))
    vectors = {json.loads(p.read_text()).get("rule") for p in VECTORS} - {None}
    assert rules == vectors
