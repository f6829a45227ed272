"""A size target uses its budget, not only keeps under it: the whole file never exceeds B bits per
frame per vertex and fills at least 0.98 of it where B is reachable; the budget fillers find
such a D even when the size jumps between nearly equal D, as zstd's strongest levels make it."""

from __future__ import annotations

import math

import pytest

import tuckercodec as tc
from tuckercodec.encoder import fill, search
from tuckercodec.io.samples import sample_path


@pytest.fixture(scope="module")
def cloth() -> tc.MeshSequence:
    return tc.load_sequence(sample_path(), progress=False)


@pytest.mark.parametrize("budget", [1.0, 2.0])
def test_the_sample_fills_its_budget_and_never_exceeds_it(cloth, budget):
    result = tc.encode_with_report(cloth, target_bpfv=budget)
    size = 8 * len(result.data) / (cloth.frame_count * cloth.vertex_count)
    assert search.FILL_LEAST * budget <= size <= budget
    # the header's error is the decoded one (Karni-Gotsman), as for a KG target
    decoded = tc.Decoder(result.data).positions()
    assert tc.kg_error(cloth.vertices, decoded) == pytest.approx(result.report.kg, rel=1e-6)


def test_a_larger_budget_gives_a_smaller_error(cloth):
    small = tc.encode_with_report(cloth, target_bpfv=1.0).report
    large = tc.encode_with_report(cloth, target_bpfv=2.0).report
    assert large.kg < small.kg


def _line(step: float) -> float:
    return 10_000.0 - 800.0 * math.log(step)


def _jumpy(step: float) -> float:
    """A line that, for about one D in two, falls 7 % below itself: zstd 19 on a large U1."""
    lucky = int(abs(math.log(step)) * 1e6) % 2 == 0
    return _line(step) * (0.93 if lucky else 1.0)


@pytest.mark.parametrize("size", [_line, _jumpy])
@pytest.mark.parametrize("aim", [9_000.0, 12_000.0, 14_500.0])
def test_the_erratic_filler_lands_in_the_window_without_exceeding_it(size, aim):
    window = (0.98 * aim, aim)
    measured: list[tuple[float, float]] = []

    def size_of(step: float) -> tuple[float, float]:
        measured.append((step, size(step)))
        return measured[-1][1], step

    # a model whose slope is half the truth, from a D far from the answer
    filled, tried = fill.fill_erratic(size_of, (1.0, 10_000.0, -400.0), window, (1e-9, 1e9), 8)
    assert tried == len(measured)
    assert window[0] <= measured[-1][1] <= window[1]  # it stopped in the window
    # and keeps the smallest D that fits (the smallest error): a lucky one may pack smaller
    assert filled is not None and filled.size <= window[1]
    assert filled.step == min(step for step, bytes_ in measured if bytes_ <= window[1])


@pytest.mark.parametrize("size", [_line, _jumpy])
def test_the_trial_filler_keeps_the_smallest_step_that_fits(size):
    window = (11_900.0, 12_000.0)
    seen: list[tuple[float, float]] = []

    def size_of(step: float) -> tuple[float, None]:
        seen.append((step, size(step)))
        return seen[-1][1], None

    filled, _ = fill.fill(size_of, 1.0, -100.0, window, (1e-9, 1e9), 6)
    assert filled is not None and filled.size <= window[1]
    fitting = [step for step, bytes_ in seen if bytes_ <= window[1]]
    assert filled.step == min(fitting)
    assert filled.slope < 0


def test_a_filler_reports_none_when_no_step_within_the_limits_fits():
    def size_of(step: float) -> tuple[float, None]:
        return _line(step), None

    # the line reaches 5,000 bytes only at D = e**6.25, beyond the upper limit
    filled, tried = fill.fill(size_of, 1.0, -800.0, (4_900.0, 5_000.0), (1e-3, 10.0), 6)
    assert filled is None and tried <= 6
    filled, _ = fill.fill_erratic(
        size_of, (1.0, 10_000.0, -800.0), (4_900.0, 5_000.0), (1e-3, 10.0), 4
    )
    assert filled is None


def test_the_segmented_encoder_fills_its_budget_too(cloth):
    result = tc.encode_with_report(cloth, target_bpfv=1.0, segment_frames=30)
    assert result.report.segments == 2
    size = 8 * len(result.data) / (cloth.frame_count * cloth.vertex_count)
    assert search.FILL_LEAST <= size <= 1.0
    decoded = tc.Decoder(result.data).positions()
    assert tc.kg_error(cloth.vertices, decoded) == pytest.approx(result.report.kg, rel=1e-6)
