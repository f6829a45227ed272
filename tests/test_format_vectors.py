"""Conformance: every vector in spec/vectors/ decodes as its JSON says (spec/FORMAT.md §12)."""

from __future__ import annotations

import hashlib
import json
import re
import struct
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import tuckercodec
from tools.generate import vectors as make_vectors
from tuckercodec import Decoder, info
from tuckercodec.internal import HEAD_SIZE

SPEC = Path(__file__).resolve().parents[1] / "spec"
VECTORS = sorted((SPEC / "vectors").glob("*.json"))


def _load(path: Path) -> tuple[dict[str, Any], bytes]:
    expected = json.loads(path.read_text())
    return expected, (path.parent / expected["file"]).read_bytes()


def test_vectors_exist():
    assert len(VECTORS) >= 3, "spec/vectors/ is empty: run python -m tools.generate.vectors"


@pytest.mark.parametrize(
    "path", [p for p in VECTORS if json.loads(p.read_text())["valid"]], ids=lambda p: p.stem
)
def test_valid_vector(path):
    expected, data = _load(path)
    decoder = Decoder(data)
    header = info(data)
    for key, value in expected["header"].items():
        got = getattr(header, key)
        assert (list(got) if isinstance(got, tuple) else got) == value, key
    assert decoder.frame_names == expected["frame_names"]
    assert make_vectors.segment_index(decoder) == expected.get("segments", [])
    assert make_vectors.digests(decoder) == expected["sha256"]  # every dequantized array
    if not decoder.segmented:  # the same arrays through the 1.0 attributes
        arrays = {"u1": decoder.u1, "u3": decoder.u3, "core": decoder.core}
        for name, array in arrays.items():
            data_bytes = np.ascontiguousarray(array, dtype="<f8").tobytes()
            assert hashlib.sha256(data_bytes).hexdigest() == expected["sha256"][name], name
    reference = np.load(path.parent / expected["reference"], allow_pickle=False)
    positions = decoder.positions()
    scale = np.abs(reference).max()
    tolerance = expected["tolerance"]["relative_to_max_abs"] * scale + 1e-12  # spec/FORMAT.md §8
    np.testing.assert_allclose(positions, reference, rtol=0, atol=tolerance)
    # any single frame decodes alone to the same positions
    last = reference.shape[0] - 1
    np.testing.assert_allclose(decoder.frame(last), reference[last], rtol=0, atol=tolerance)
    if "attributes" in expected:  # format 1.5: every value and index, bit for bit
        got = make_vectors.attachments_of(decoder)
        assert got == {key: expected[key] for key in got}
    if "fields" in expected:  # format 1.5: grid and exact bit for bit, tucker within §8's bound
        assert make_vectors.fields_of(decoder, path.stem) == expected["fields"]
        for field, entry in zip(decoder.fields(), expected["fields"], strict=True):
            if "reference" in entry:
                want = np.load(path.parent / entry["reference"], allow_pickle=False)
                bound = entry["tolerance"]["relative_to_max_abs"] * np.abs(want).max() + 1e-12
                np.testing.assert_allclose(field.values, want, rtol=0, atol=bound)
    if "residual" in expected:  # format 1.3 (§6.9, §8.1): the integers, and every bit
        assert make_vectors.corrections_of(decoder) == expected["residual"]
        assert positions.tobytes() == reference.tobytes()
        assert decoder.frame(last).tobytes() == reference[last].tobytes()


@pytest.mark.parametrize(
    "path", [p for p in VECTORS if not json.loads(p.read_text())["valid"]], ids=lambda p: p.stem
)
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
    parts = make_vectors.Parts((SPEC / "vectors" / "v1-wave-triangles.tkc").read_bytes())
    header_change(parts.header)
    return parts.pack()


def _with_raw_header_entry(raw_key_and_value: bytes) -> bytes:
    """v1-wave-triangles with one more header entry, given as raw msgpack bytes (Python cannot
    build values nested beyond its recursion limit), checksums made right again."""
    data = (SPEC / "vectors" / "v1-wave-triangles.tkc").read_bytes()
    header_length = struct.unpack_from("<I", data, 16)[0]
    header = data[HEAD_SIZE : HEAD_SIZE + header_length]
    assert 0x80 <= header[0] < 0x8F  # a fixmap: its low bits count the keys
    new_header = bytes([header[0] + 1]) + header[1:] + raw_key_and_value
    return make_vectors.Parts(data).pack(header_bytes=new_header)


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


# ------------------------------------------------------------------------------------------
# the writer, tools.generate.vectors (never run into spec/vectors/ here)

#: Written from a fresh encode of v1-wave-triangles, not from the committed file: the header's
#: error.kg differs in its last digit, and nothing else (checked below).
FROM_ANOTHER_ENCODE = {"R36-reconstruction-finite"}


def test_the_invalid_vectors_come_from_the_committed_valid_one(tmp_path):
    """Each invalid vector is the committed v1-wave-triangles with one rule broken: written
    again from it into a temporary folder, the files and their JSON are the committed ones."""
    good = (SPEC / "vectors" / "v1-wave-triangles.tkc").read_bytes()
    segmented = (SPEC / "vectors" / "v1.1-segments-shared.tkc").read_bytes()
    traversed = (SPEC / "vectors" / "v1.2-traverse-triangles.tkc").read_bytes()
    corrected = (SPEC / "vectors" / "v1.3-lossless-float32.tkc").read_bytes()
    attached = (SPEC / "vectors" / "v1.5-attributes.tkc").read_bytes()
    coded = (SPEC / "vectors" / "v1.6-adaptive.tkc").read_bytes()
    faces_coded = (SPEC / "vectors" / "v1.6-faces-adaptive.tkc").read_bytes()
    corrected_adaptively = (SPEC / "vectors" / "v1.7-lossless-adaptive.tkc").read_bytes()
    codebooks = (SPEC / "vectors" / "v1.8-lossless-codebooks.tkc").read_bytes()
    uniform_ranks = (SPEC / "vectors" / "v1.9-faces-uniform-ranks.tkc").read_bytes()
    count = make_vectors.write_invalid(
        tmp_path,
        good,
        segmented,
        traversed,
        corrected,
        attached,
        coded,
        faces_coded,
        corrected_adaptively,
        codebooks,
        uniform_ranks,
    )
    assert count == len([p for p in VECTORS if not json.loads(p.read_text())["valid"]])
    for path in sorted(tmp_path.iterdir()):
        committed = (SPEC / "vectors" / path.name).read_bytes()
        if path.stem in FROM_ANOTHER_ENCODE and path.suffix == ".tkc":
            parts = make_vectors.Parts(committed)
            parts.header["error"] = make_vectors.Parts(good).header["error"]
            committed = parts.pack()
        assert path.read_bytes() == committed, path.name


def test_the_writer_writes_every_vector_elsewhere_and_never_overwrites(tmp_path, capsys):
    out = tmp_path / "vectors"
    assert make_vectors.main(["--out", str(out)]) == 0
    assert sorted(p.name for p in out.iterdir()) == sorted(
        p.name for p in (SPEC / "vectors").iterdir()
    )
    for path in out.glob("*.json"):  # the invalid ones alike; the valid ones' digests may differ
        written = json.loads(path.read_text())
        committed = json.loads((SPEC / "vectors" / path.name).read_text())
        assert written.keys() == committed.keys(), path.name
        if not committed["valid"]:
            assert written == committed
        else:  # today's encoder, held to the version each vector's name says
            version = written["header"]["format_version"]
            assert version == committed["header"]["format_version"], path.name
            assert version == make_vectors.named_version(path.stem), path.name
    assert make_vectors.main(["--out", str(out)]) == 1
    assert "--force" in capsys.readouterr().err


def test_the_writer_refuses_a_file_of_another_version_than_its_name(tmp_path):
    assert make_vectors.named_version("v1-wave-triangles") == "1.0"
    assert make_vectors.named_version("v1.3-lossless-float32") == "1.3"
    good = (SPEC / "vectors" / "v1-wave-triangles.tkc").read_bytes()
    with pytest.raises(ValueError, match=r"v1\.2-renamed is a file of format 1\.0"):
        make_vectors.write_valid(tmp_path, "v1.2-renamed", good, "a 1.0 file named for 1.2")
    assert not list(tmp_path.iterdir())
