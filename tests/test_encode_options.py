"""EncodeOptions and Encoder (tuckercodec.encoder): every option in one object, checked once,
carried as JSON, and the one-shot functions as shorthand for the Encoder."""

from __future__ import annotations

import dataclasses
import inspect
import json
from collections.abc import Callable
from typing import Any

import numpy as np
import pytest

import tuckercodec as tc
from tests.support.sequences import grid_faces, wave_sequence
from tuckercodec.encoder import encode_frames, encode_source, resolve_options
from tuckercodec.model.sources import SequenceFrames


@pytest.fixture(scope="module")
def wave():
    return tc.MeshSequence(wave_sequence(frames=30, grid=12), grid_faces(12))


def test_the_default_options_meet_a_kg_error_of_a_tenth():
    options = tc.EncodeOptions()
    assert options.mode == "kg"
    assert options.kg_target == 0.1
    assert options.target_kg is None


@pytest.mark.parametrize(
    "fields",
    [
        {},
        {"target_kg": 0.5, "level": 5},
        {"ranks": (3, 4), "select": "bound"},
        {"target_bpfv": 2.0, "segment_frames": 10, "max_memory": 10**9, "basis": "own"},
        {"target_kg": 1, "jobs": 2},
        {"scheduler": "tcp://127.0.0.1:8786"},
    ],
)
def test_options_travel_as_json_and_come_back_equal(fields):
    options = tc.EncodeOptions(**fields)
    config = json.loads(json.dumps(options.to_config()))
    assert tc.EncodeOptions.from_config(config) == options


def test_values_are_normalized_once():
    # JSON and numpy hand over lists, floats and numpy scalars: each is made the declared type
    options = tc.EncodeOptions(ranks=[3.0, np.int64(4)], level=7.0)  # type: ignore[arg-type]
    assert options.ranks == (3, 4) and type(options.ranks[0]) is int and options.level == 7
    assert type(tc.EncodeOptions(target_kg=np.float32(0.5)).target_kg) is float  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("fields", "message"),
    [
        ({"target_kg": 0.1, "target_bpfv": 1.0}, "not target_kg and target_bpfv"),
        ({"target_kg": -1}, "target_kg must be a positive finite number"),
        ({"target_bpfv": float("nan")}, "target_bpfv must be a positive finite number"),
        ({"target_kg": True}, "target_kg must be a positive finite number"),
        ({"ranks": (0, 2)}, "ranks must be two integers, each at least 1"),
        ({"select": "guess"}, "select must be 'exact' or 'bound'"),
        ({"basis": "mine"}, "basis must be one of shared, own"),
        ({"level": 23}, "level must be an integer from 1 to 22"),
        ({"level": 2.5}, "level must be an integer from 1 to 22"),
        ({"segment_frames": 0}, "segment_frames must be an integer >= 1"),
        ({"max_memory": -5}, "max_memory must be an integer >= 1"),
        ({"jobs": 0}, "jobs must be an integer >= 1"),
        ({"jobs": 2, "scheduler": "tcp://127.0.0.1:1"}, "jobs or scheduler, not both"),
        ({"scheduler": 5}, "scheduler must be an address"),
    ],
)
def test_a_bad_option_is_refused_naming_it(fields, message):
    with pytest.raises(ValueError, match=message):
        tc.EncodeOptions(**fields)


def test_a_config_with_an_unknown_field_is_refused_naming_it():
    with pytest.raises(ValueError, match="unknown encode options: colour"):
        tc.EncodeOptions.from_config({"target_kg": 0.1, "colour": "red"})


#: Every way in that encodes with options: each takes ``(source, options=None, **fields)``.
FRONT_DOORS: dict[str, Callable[..., Any]] = {
    "encode": tc.encode,
    "encode_with_report": tc.encode_with_report,
    "encode_source": encode_source,
    "encode_frames": encode_frames,
    "encode_file": tc.encode_file,
}
FIELD_NAMES = {field.name for field in dataclasses.fields(tc.EncodeOptions)}
#: A value other than the default for every field, in two sets that may be given together
#: (lossless stands alone).
EVERY_FIELD: list[dict[str, Any]] = [
    {
        "target_kg": 0.5,
        "select": "bound",
        "level": 5,
        "segment_frames": 4,
        "max_memory": 10**9,
        "basis": "own",
        "scheduler": "tcp://127.0.0.1:1",
        "max_error": "1%",
    },
    {"ranks": (3, 2), "jobs": 2, "max_error": 0.01},
    {
        "target_bpfv": 3.0,
        "face_order": "given",
        "field_targets": (("speed", "max:0.01"),),
        "format_version": "1.5",
    },
    {"lossless": True, "field_target": "rel:0.5", "attachments": False},
]


def test_every_field_is_named_in_the_sets_of_values():
    assert {name for fields in EVERY_FIELD for name in fields} == FIELD_NAMES


def test_every_front_door_has_the_same_signature_pattern():
    for name, door in FRONT_DOORS.items():
        parameters = list(inspect.signature(door).parameters.values())
        kinds = [parameter.kind for parameter in parameters]
        at = [parameter.name for parameter in parameters].index("options")
        # the source (and encode_file's output) first, then options, positional or keyword
        assert at == (2 if name == "encode_file" else 1), name
        assert all(kind is inspect.Parameter.POSITIONAL_OR_KEYWORD for kind in kinds[: at + 1])
        assert parameters[at].default is None, name
        # what is not an option is keyword-only; the options' fields come as **fields
        assert all(kind is inspect.Parameter.KEYWORD_ONLY for kind in kinds[at + 1 : -1]), name
        assert kinds[-1] is inspect.Parameter.VAR_KEYWORD and parameters[-1].name == "fields"
        assert not FIELD_NAMES & {parameter.name for parameter in parameters}, name
        assert "EncodeOptions" in (door.__doc__ or ""), name  # the docstring says so


class _Captured(Exception):
    """Raised by a stand-in Encoder with the options a front door built."""

    def __init__(self, options: tc.EncodeOptions):
        super().__init__()
        self.options = options


def _capture(options: tc.EncodeOptions, **_: object) -> None:
    raise _Captured(options)


@pytest.mark.parametrize("fields", EVERY_FIELD, ids=lambda fields: ",".join(fields))
@pytest.mark.parametrize("door", list(FRONT_DOORS))
def test_every_front_door_takes_every_field(door, fields, monkeypatch, wave, tmp_path):
    monkeypatch.setattr(tc.encoder.shorthands, "Encoder", _capture)
    monkeypatch.setattr(tc.files, "Encoder", _capture)
    source = wave if door in ("encode", "encode_with_report") else SequenceFrames(wave)
    where = [tmp_path / "w.tkc"] if door == "encode_file" else []
    with pytest.raises(_Captured) as captured:
        FRONT_DOORS[door](source, *where, **fields)
    assert captured.value.options == tc.EncodeOptions(**fields)
    # the same fields put over options, whole
    base = tc.EncodeOptions(level=7)
    with pytest.raises(_Captured) as captured:
        FRONT_DOORS[door](source, *where, base, **fields)
    assert captured.value.options == dataclasses.replace(base, **fields)


@pytest.mark.parametrize("door", list(FRONT_DOORS))
def test_a_keyword_that_is_not_an_option_is_a_type_error_naming_it(door, wave, tmp_path):
    where = [tmp_path / "w.tkc"] if door == "encode_file" else []
    with pytest.raises(TypeError, match="'colour'"):
        FRONT_DOORS[door](wave, *where, target_kg=0.5, colour="red")
    with pytest.raises(TypeError, match="EncodeOptions"):
        FRONT_DOORS[door](wave, *where, options={"target_kg": 0.5})
    assert not (tmp_path / "w.tkc").exists()


def test_keywords_are_put_over_options_as_replace_does(wave):
    options = tc.EncodeOptions(target_kg=0.2, level=5)
    expected = tc.Encoder(tc.EncodeOptions(target_kg=0.5, level=5)).encode(wave)
    assert tc.encode(wave, options, target_kg=0.5) == expected
    assert tc.encode(wave, target_kg=0.5, options=options) == expected
    assert resolve_options(options) is options
    assert resolve_options() == tc.EncodeOptions()
    # the result is checked whole: a keyword of another mode than the options' is refused
    with pytest.raises(ValueError, match="not target_kg and ranks"):
        tc.encode(wave, options, ranks=(4, 3))
    with pytest.raises(ValueError, match="lossless stands alone"):
        tc.encode(wave, options, lossless=True)


def test_a_bound_and_lossless_go_through_encode_and_encode_file(wave, tmp_path):
    source = wave_npz(wave, tmp_path)
    for fields in ({"max_error": "0.5%"}, {"lossless": True}, {"target_kg": 0.5, "level": 3}):
        expected = tc.Encoder(tc.EncodeOptions(**fields)).encode_with_report(wave)
        assert tc.encode(wave, **fields) == expected.data
        output = tmp_path / f"{'-'.join(fields)}.tkc"
        report = tc.encode_file(source, output, **fields)
        assert output.read_bytes() == expected.data
        assert report.lossless == expected.report.lossless
        assert report.max_error == expected.report.max_error
    assert tc.decode(tc.encode(wave, lossless=True)).vertices.tobytes() == wave.vertices.tobytes()


def test_every_way_in_writes_the_same_bytes(wave, tmp_path):
    options = tc.EncodeOptions(target_kg=0.5)
    expected = tc.Encoder(options).encode(wave)
    assert tc.encode(wave, target_kg=0.5) == expected
    assert tc.encode(wave, options=options) == expected
    assert tc.encode_with_report(wave, options=options).data == expected
    assert encode_source(SequenceFrames(wave), options=options).data == expected
    report = tc.encode_file(wave_npz(wave, tmp_path), tmp_path / "w.tkc", options=options)
    assert (tmp_path / "w.tkc").read_bytes() == expected
    assert report.total_bytes == len(expected)


def wave_npz(sequence, folder):
    path = folder / "wave.npz"
    tc.save_sequence(sequence, path)
    return path


def test_the_encoder_decides_whole_or_segmented_in_one_place(wave):
    whole = tc.Encoder(tc.EncodeOptions(target_kg=0.5))
    segmented = tc.Encoder(tc.EncodeOptions(target_kg=0.5, segment_frames=10))
    tiny_memory = tc.Encoder(tc.EncodeOptions(target_kg=0.5, max_memory=1000))
    assert not whole.segments(wave.frame_count, wave.vertex_count)
    assert segmented.segments(wave.frame_count, wave.vertex_count)
    assert tiny_memory.segments(wave.frame_count, wave.vertex_count)
    assert tc.info(whole.encode(wave)).segments == ()
    assert len(tc.info(segmented.encode(wave)).segments) == 3
    report = segmented.encode_with_report(wave).report
    assert report.segments == 3 and report.kg <= 0.5
    # encode_frames segments whatever the size: the same bytes as asking for segments
    assert encode_frames(
        SequenceFrames(wave), target_kg=0.5, segment_frames=10
    ).data == segmented.encode(wave)


def test_a_segmented_encode_refuses_the_bound_selection(wave):
    encoder = tc.Encoder(tc.EncodeOptions(target_kg=0.5, segment_frames=10, select="bound"))
    with pytest.raises(ValueError, match="exact error"):
        encoder.encode(wave)


def test_asking_for_workers_of_a_whole_encode_says_it_runs_here(wave):
    lines: list[str] = []
    encoder = tc.Encoder(tc.EncodeOptions(target_kg=0.5, jobs=2), progress=lines.append)
    assert encoder.encode(wave) == tc.encode(wave, target_kg=0.5)
    assert any("encoded whole, in this process" in line for line in lines)


def test_an_encoder_takes_only_options():
    with pytest.raises(TypeError, match="expected EncodeOptions"):
        tc.Encoder({"target_kg": 0.1})  # type: ignore[arg-type]
