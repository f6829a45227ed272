"""Each promise of a file has one home (tuckercodec.encoder.promises), and the error-bounded
modes one way into the corrections (corrections.Corrector.file): an encode whole and one in
segments take the same steps, each once, and the header states what those steps decided."""

from __future__ import annotations

from collections import Counter
from typing import Any

import numpy as np
import pytest

from tests.support.sequences import grid_faces, wave_sequence
from tuckercodec import EncodeOptions, Encoder, MeshSequence, info
from tuckercodec.encoder import corrections, promises
from tuckercodec.errors import InternalError, UnreachableTargetError
from tuckercodec.measures.distortion import Displacement


@pytest.fixture(scope="module")
def wave() -> MeshSequence:
    return MeshSequence(wave_sequence(24, 8, seed=5), grid_faces(8))


@pytest.fixture
def calls(monkeypatch) -> Counter[str]:
    """How often each step ran: the corrections' one way in, each promise's check, and the
    header's claims (each wrapped, still doing its work)."""
    counted: Counter[str] = Counter()

    def counting(owner: Any, name: str) -> None:
        step = getattr(owner, name)

        def wrapper(*args: Any, **kwargs: Any) -> Any:
            counted[name] += 1
            return step(*args, **kwargs)

        monkeypatch.setattr(owner, name, wrapper)

    counting(corrections.Corrector, "file")
    for name in ("check_kg", "check_bound", "check_lossless", "header_claims"):
        counting(promises, name)
    return counted


@pytest.mark.parametrize("segment_frames", [None, 12], ids=["whole", "segmented"])
@pytest.mark.parametrize(
    ("mode", "checked"),
    [
        ({"max_error": "0.05%"}, "check_bound"),
        ({"max_error": "0.05%", "target_kg": 0.5}, "check_bound"),
        ({"lossless": True}, "check_lossless"),
    ],
    ids=["max_error", "max_error+kg", "lossless"],
)
def test_whole_and_segmented_encodes_take_the_one_step_of_each_promise(
    wave, calls, segment_frames, mode, checked
):
    options = EncodeOptions(segment_frames=segment_frames, **mode)
    result = Encoder(options).encode_with_report(wave)
    segments = 1 if segment_frames is None else result.report.segments
    assert segments == (1 if segment_frames is None else 2)
    assert calls["file"] == 1  # the one way into the corrections
    assert calls["header_claims"] == 1  # the one place the header's claims are decided
    assert calls["check_kg"] == 1  # once, from the header's claims
    assert calls[checked] == segments  # the positions of the file, or of each segment
    other = "check_lossless" if checked == "check_bound" else "check_bound"
    assert calls[other] == 0
    header = info(result.data)
    assert header.target_kg == options.target_kg
    assert header.lossless is options.lossless
    assert header.max_distance == result.report.max_distance
    assert header.target_max_distance == result.report.max_error


@pytest.mark.parametrize("segment_frames", [None, 12], ids=["whole", "segmented"])
def test_a_file_without_corrections_states_its_kg_target_through_the_same_step(
    wave, calls, segment_frames
):
    data = Encoder(EncodeOptions(target_kg=0.5, segment_frames=segment_frames)).encode(wave)
    assert calls["file"] == 0
    assert (calls["header_claims"], calls["check_kg"]) == (1, 1)
    assert info(data).target_kg == 0.5 and info(data).max_distance is None


def test_the_header_claims_a_kg_target_only_in_kg_mode():
    worst = Displacement(0.25, 3, 7)
    assert promises.header_claims(EncodeOptions(), 0.09) == promises.HeaderClaims(0.1, {})
    assert promises.header_claims(EncodeOptions(ranks=(3, 2)), 5.0).target_kg is None
    assert promises.header_claims(EncodeOptions(target_bpfv=2.0), 5.0).target_kg is None
    bounded = promises.header_claims(EncodeOptions(max_error=0.5), 5.0, worst, 0.5)
    assert bounded == promises.HeaderClaims(
        None,
        {
            "max_distance": 0.25,
            "max_distance_at": [3, 7],
            "target_max_distance": 0.5,
            "lossless": False,
        },
    )
    both = promises.header_claims(EncodeOptions(max_error=0.5, target_kg=1.0), 0.9, worst, 0.5)
    assert both.target_kg == 1.0 and both.error["target_max_distance"] == 0.5
    lossless = promises.header_claims(EncodeOptions(lossless=True), 0.0, Displacement(0, 0, 0))
    assert lossless.target_kg is None
    assert lossless.error["lossless"] is True and lossless.error["target_max_distance"] is None


def test_a_file_above_its_kg_target_is_a_bug_not_an_unreachable_target():
    with pytest.raises(InternalError, match=r"KG error 0\.2 is above the target 0\.1") as found:
        promises.header_claims(EncodeOptions(target_kg=0.1), 0.2)
    assert "bug in tuckercodec: please report it" in str(found.value)
    assert not isinstance(found.value, ValueError)  # no search's retry swallows it
    promises.check_kg(EncodeOptions(ranks=(2, 2)), 50.0)  # no KG promise, nothing to break


def test_a_lossless_file_that_differs_is_a_bug_and_a_missed_bound_is_unreachable():
    original = np.zeros((2, 3, 3))
    decoded = original.copy()
    promises.check_lossless(decoded, original)
    decoded[1, 2, 0] = 5e-324
    with pytest.raises(InternalError, match=r"frame 1, vertex 2\). This is a bug"):
        promises.check_lossless(decoded, original)
    promises.check_bound(Displacement(0.5, 0, 0), 0.5)
    promises.check_bound(Displacement(9.0, 0, 0), None)  # lossless: no bound
    with pytest.raises(UnreachableTargetError, match=r"vertex 2 of frame 1 decodes 0\.6"):
        promises.check_bound(Displacement(0.6, 1, 2), 0.5)
