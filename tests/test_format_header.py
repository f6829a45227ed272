"""The header (spec/FORMAT.md §4): every field set to zero, negative, huge and every wrong type,
and arbitrary headers over the real sections of a valid file, re-signed with correct CRCs so
that the checks behind the CRCs are reached.

A changed field fails with a FormatError unless the spec lets it be anything: an unknown key,
the informative ``encoder`` and ``error`` fields, a valid ``frame_rate``, and any finite ``u2``
(the decoder does not check that U2 is orthogonal). ``info --json`` stays strict JSON whatever
the informative ``error`` map claims.
"""

from __future__ import annotations

import json
from typing import Any

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import tuckercodec
from tests.support.compressed import (
    HOSTILE,
    MISSING,
    VALID,
    Parts,
    accept_either,
    check_decoded,
    outcome,
    raw_file,
    vector,
)
from tests.support.properties import HYPOTHESIS_SETTINGS, msgpack_values
from tuckercodec import LimitError
from tuckercodec.format.container import pack_container


def _set(header: dict[str, Any], path: tuple[str | int, ...], value: Any) -> None:
    target: Any = header  # maps and lists, as the path goes down
    for key in path[:-1]:
        target = target[key]
    if value is MISSING:
        if isinstance(target, dict):
            target.pop(path[-1], None)  # a key the vector may not have (error.max_distance)
        else:
            del target[path[-1]]
    else:
        target[path[-1]] = value


EVERYTHING = set(HOSTILE) | {"missing"}


#: Header paths -> (hostile values, by HOSTILE's names, under which the file stays valid;
#: values that may or may not make the reconstruction overflow, R36). All others must fail.
HEADER_FIELDS: dict[tuple[str | int, ...], tuple[set[str], set[str]]] = {
    ("vertices",): (set(), set()),
    ("frames",): (set(), set()),
    ("ranks",): (set(), set()),
    ("ranks", 0): (set(), set()),
    ("ranks", 1): (set(), set()),
    ("u2",): (set(), set()),
    # any finite float: the decoder does not check that U2 is orthogonal
    ("u2", 0): ({"float zero"}, {"float 2**64", "1e308", "-1e308"}),
    ("u2", 8): ({"float zero"}, {"float 2**64", "1e308", "-1e308"}),
    ("frame_rate",): (
        {"float 2**64", "1e308", "none", "missing"},
        set(),
    ),  # positive finite, nil or absent
    ("encoder",): (EVERYTHING, set()),  # informative only (§4)
    ("error",): (EVERYTHING, set()),
    ("error", "kg"): (EVERYTHING, set()),
    ("error", "definition"): (EVERYTHING, set()),
    ("error", "max_distance"): (EVERYTHING, set()),  # the keys of 1.3, as informative
    ("error", "max_distance_at"): (EVERYTHING, set()),
    ("error", "target_max_distance"): (EVERYTHING, set()),
    ("error", "lossless"): (EVERYTHING, set()),
    ("sections",): (set(), set()),
}


@pytest.mark.parametrize("path", list(HEADER_FIELDS), ids=lambda p: ".".join(map(str, p)))
def test_every_header_field_set_to_every_hostile_value(path):
    allowed, either = HEADER_FIELDS[path]
    for label, value in [*HOSTILE.items(), ("missing", MISSING)]:
        parts = Parts(vector("v1-wave-triangles"))
        parts.header["frame_rate"] = 24.0
        if path == ("sections",):
            header = {**parts.header, "sections": None}
            if value is not MISSING:
                header["sections"] = value
            else:
                del header["sections"]
            data = raw_file(header, parts.area())
        else:
            _set(parts.header, path, value)
            data = parts.pack()
        error, sequence = outcome(data)
        if label in allowed:
            assert error is None and sequence is not None, f"{path} = {label}: {error}"
            check_decoded(data, sequence)
        elif label in either:
            if sequence is not None:
                check_decoded(data, sequence)
        else:
            assert error is not None, f"{path} = {label} was accepted"
        if path in {("vertices",), ("frames",)} and label in {"2**31", "2**63", "2**64-1"}:
            assert type(error) is LimitError, f"{path} = {label}: {error!r}"


@pytest.mark.parametrize("label", list(HOSTILE))
def test_info_as_json_is_strict_json_whatever_the_error_map_claims(label):
    """The informative ``error`` values are not checked (§4.1), but ``FileInfo.to_dict`` (what
    ``tuckercodec info --json`` prints) must stay valid JSON: no bare NaN or Infinity."""
    parts = Parts(vector("v1-wave-triangles"))
    parts.header["error"] = {
        "kg": HOSTILE[label],
        "target_kg": HOSTILE[label],
        "definition": HOSTILE[label],
        "max_distance": HOSTILE[label],
        "max_distance_at": HOSTILE[label],
        "target_max_distance": HOSTILE[label],
        "lossless": HOSTILE[label],
    }
    text = json.dumps(tuckercodec.info(parts.pack()).to_dict(), allow_nan=False)
    assert json.loads(text)["vertices"] == 81


def test_info_reads_the_worst_vertex_keys_of_the_error_map():
    """§4.1 (1.3): ``max_distance``, ``max_distance_at``, ``target_max_distance`` and
    ``lossless``, read when they have their types and treated as absent otherwise."""
    parts = Parts(vector("v1-wave-triangles"))  # 24 frames of 81 vertices
    plain = tuckercodec.info(parts.pack())
    assert (plain.max_distance, plain.max_distance_at) == (None, None)
    assert (plain.target_max_distance, plain.lossless) == (None, None)
    assert {"max_distance", "max_distance_at", "target_max_distance", "lossless"} <= set(
        plain.to_dict()
    )
    parts.header["error"].update(
        max_distance=0.0125, max_distance_at=[23, 80], target_max_distance=0.02, lossless=False
    )
    read = tuckercodec.info(parts.pack())
    assert (read.max_distance, read.max_distance_at) == (0.0125, (23, 80))
    assert (read.target_max_distance, read.lossless) == (0.02, False)
    as_json = read.to_dict()
    assert as_json["max_distance"] == 0.0125 and as_json["max_distance_at"] == [23, 80]
    assert as_json["target_max_distance"] == 0.02 and as_json["lossless"] is False
    parts.header["error"].update(max_distance=0, target_max_distance=None, lossless=True)
    read = tuckercodec.info(parts.pack())  # an int is a number; nil is "no bound"
    assert (read.max_distance, read.target_max_distance, read.lossless) == (0.0, None, True)
    for wrong in (
        {"max_distance": True, "max_distance_at": [24, 0]},  # a bool; frame 24 of 0..23
        {"max_distance": "0.1", "max_distance_at": [0, 81]},  # a str; vertex 81 of 0..80
        {"max_distance": [0.1], "max_distance_at": [1, 2, 3]},
        {"max_distance": None, "max_distance_at": [True, 0]},
        {"max_distance": {}, "max_distance_at": [-1, 0]},
        {"max_distance": b"\x01", "max_distance_at": [1.0, 2.0]},
        {"max_distance": None, "max_distance_at": {"frame": 1, "vertex": 2}},
    ):
        parts.header["error"].update(wrong, target_max_distance="0.2", lossless=1)
        read = tuckercodec.info(parts.pack())
        assert (read.max_distance, read.max_distance_at) == (None, None), wrong
        assert (read.target_max_distance, read.lossless) == (None, None), wrong


# ------------------------------------------------------------------------------------------
# hypothesis: arbitrary headers, re-signed so that the semantic checks are reached


HEADER_KEYS = ["vertices", "frames", "ranks", "u2", "frame_rate", "encoder", "error", "x-unknown"]


@settings(max_examples=300, **HYPOTHESIS_SETTINGS)
@given(
    header=st.dictionaries(
        st.sampled_from(HEADER_KEYS) | st.text(max_size=8), msgpack_values, max_size=8
    ),
    name=st.sampled_from(VALID),
)
def test_arbitrary_headers_over_real_sections(header, name):
    """Any header map at all, with a vector's real sections (pack_container re-signs the CRCs)."""
    parts = Parts(vector(name))
    header.pop("sections", None)
    accept_either(pack_container(header, parts.sections))


@settings(max_examples=300, **HYPOTHESIS_SETTINGS)
@given(name=st.sampled_from(VALID), key=st.sampled_from(HEADER_KEYS), value=msgpack_values)
def test_one_header_field_arbitrary(name, key, value):
    """A valid header with one field replaced by anything msgpack can hold."""
    parts = Parts(vector(name))
    parts.header[key] = value
    error = accept_either(parts.pack())
    if key in {"vertices", "frames", "ranks"} and value != Parts(vector(name)).header[key]:
        # a size changed: no section's shape can still match it (u2 may change to any finite
        # floats, which is still a valid file)
        assert error is not None
