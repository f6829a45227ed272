"""EncodeOptions and Encoder (tuckercodec.encoder): every option in one object, checked once,
carried as JSON, and the one-shot functions as shorthand for the Encoder."""

from __future__ import annotations

import json

import numpy as np
import pytest

import tuckercodec as tc
from tests.support.sequences import grid_faces, wave_sequence
from tuckercodec.encoder import encode_frames, encode_source
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


def test_options_and_keywords_are_not_mixed(wave):
    with pytest.raises(ValueError, match="give options or target_kg, not both"):
        tc.encode(wave, target_kg=0.5, options=tc.EncodeOptions(target_kg=0.2))


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
