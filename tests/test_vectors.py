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
        tuckercodec.decode(data)  # open and reconstruct every frame
    assert type(raised.value) is error  # the most specific class, not just a subclass
    assert raised.value.rule == expected["rule"]  # the rule of §11, not a message fragment
    assert f"[{expected['rule']}]" in str(raised.value)  # what the CLI prints


def test_every_rule_of_the_spec_has_a_vector():
    text = (SPEC / "FORMAT.md").read_text()
    rules = set(re.findall(r"\b(R\d\d-[a-z0-9-]+[a-z0-9])", text))
    vectors = {json.loads(p.read_text()).get("rule") for p in VECTORS} - {None}
    assert rules == vectors


def _repacked(header_change) -> bytes:
    """v1-wave-triangles with its header changed and the checksums made right again."""
    import sys

    sys.path.insert(0, str(SPEC.parent / "tools"))
    from make_vectors import Parts

    parts = Parts((SPEC / "vectors" / "v1-wave-triangles.tkc").read_bytes())
    header_change(parts.header)
    return parts.pack()


def _with_raw_header_entry(raw_key_and_value: bytes) -> bytes:
    """v1-wave-triangles with one more header entry, given as raw msgpack bytes (Python cannot
    build values nested beyond its recursion limit), checksums made right again."""
    import struct
    import zlib

    data = (SPEC / "vectors" / "v1-wave-triangles.tkc").read_bytes()
    header_length = struct.unpack_from("<I", data, 16)[0]
    header = data[32 : 32 + header_length]
    assert 0x80 <= header[0] < 0x8F  # a fixmap: its low bits count the keys
    new_header = bytes([header[0] + 1]) + header[1:] + raw_key_and_value
    body = data[32 + header_length + 4 :]
    head = bytearray(data[:28])
    struct.pack_into("<IQ", head, 16, len(new_header), 32 + len(new_header) + 4 + len(body))
    return b"".join([bytes(head), struct.pack("<I", zlib.crc32(bytes(head))), new_header,
                     struct.pack("<I", zlib.crc32(new_header)), body])


@pytest.mark.parametrize("depth", [10, 999, 1023, 1100])
def test_deeply_nested_header_values_are_handled_without_recursion(depth):
    data = _with_raw_header_entry(b"\xa6x-deep" + b"\x91" * depth + b"\x01")
    if depth < 1024:
        Decoder(data)  # valid: an unknown key is ignored, however deep its value
    else:
        with pytest.raises(tuckercodec.FormatError, match="1024"):
            Decoder(data)


def test_a_reconstruction_that_overflows_is_a_format_error():
    data = _repacked(lambda h: h.__setitem__("u2", [1e308] * 9))
    with pytest.raises(tuckercodec.FormatError, match="overflows"):
        Decoder(data).positions()
