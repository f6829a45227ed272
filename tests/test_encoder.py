"""The encoder: each way of asking for a file (a KG target, fixed ranks, a size in bpfv) gives a
file whose decoded error meets what was asked and whose report and header say what the decoder
really returns, on ordinary, unusual and real sequences; or a clear, typed error. Never a wrong
file, never an untyped exception.
"""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

import tuckercodec as tc
from tests.support.compressed import assert_same_faces
from tests.support.sequences import grid_faces, load_shared_npz, shared_file, wave_sequence
from tuckercodec import MeshSequence, decode, encode, encode_with_report, info, kg_error


@pytest.fixture(scope="module")
def wave() -> MeshSequence:
    return MeshSequence(wave_sequence(frames=30, grid=12), grid_faces(12))


# ------------------------------------------------------------------------------------------
# targets and modes


@pytest.mark.parametrize("target", [2.0, 0.5, 0.1, 0.02])
def test_decoded_error_meets_the_target(wave, target):
    result = encode_with_report(wave, target_kg=target)
    decoded = decode(result.data)
    measured = kg_error(wave, decoded)
    assert measured <= target
    # the report and the header carry what the decoder really returns
    assert math.isclose(result.report.kg, measured, rel_tol=1e-9)
    header = info(result.data)
    assert header.kg is not None and math.isclose(header.kg, measured, rel_tol=1e-9)
    assert header.kg_definition == "karni-gotsman-2004" and header.target_kg == target
    assert header.total_bytes == len(result.data) == result.report.total_bytes
    assert header.bpfv == pytest.approx(8 * len(result.data) / (30 * 144))
    assert_same_faces(decoded.faces, wave.faces)
    assert decoded.frame_names == wave.frame_names


def test_tighter_targets_cost_more_bytes(cloth):
    sizes = [len(encode(cloth, target_kg=t)) for t in (1.0, 0.1, 0.02)]
    assert sizes[0] < sizes[1] < sizes[2]


def test_quantization_spends_part_of_the_budget(cloth):
    report = encode_with_report(cloth, target_kg=0.1).report
    # both truncation and quantization contribute, and the file is far below raw float32
    assert 0 < report.truncation_kg < report.kg <= 0.1
    assert report.ratio > 10
    assert report.exact_ranks is not None and report.bound_ranks is not None


def test_bound_selection_also_meets_the_target(cloth):
    exact = encode_with_report(cloth, target_kg=0.1, select="exact").report
    bound = encode_with_report(cloth, target_kg=0.1, select="bound").report
    assert bound.kg <= 0.1 and exact.kg <= 0.1
    assert bound.select == "bound"


def test_fixed_ranks(cloth):
    analysis = tc.analyze(cloth)
    result = encode_with_report(cloth, ranks=(10, 6))
    assert result.report.ranks == (10, 6) and info(result.data).ranks == (10, 6)
    truncation = analysis.kg(10, 6)
    assert result.report.truncation_kg == pytest.approx(truncation)
    assert truncation <= kg_error(cloth, decode(result.data)) <= 1.05 * truncation * (1 + 1e-9)


def test_target_size(cloth):
    small = encode_with_report(cloth, target_bpfv=2.5).report
    large = encode_with_report(cloth, target_bpfv=5.0).report
    assert small.bpfv <= 2.5 and large.bpfv <= 5.0
    assert large.kg < small.kg
    with pytest.raises(ValueError, match="faces alone"):
        encode(cloth, target_bpfv=0.01)


def test_modes_are_exclusive_and_checked(wave):
    with pytest.raises(ValueError, match="not target_kg and ranks"):
        encode(wave, target_kg=0.1, ranks=(2, 2))
    for bad in (0, -1, float("nan"), float("inf")):
        with pytest.raises(ValueError, match="positive finite"):
            encode(wave, target_kg=bad)
    with pytest.raises(ValueError, match="ranks must be"):
        encode(wave, ranks=(0, 3))
    with pytest.raises(ValueError, match="ranks must be"):
        encode(wave, ranks=(5, 10_000))
    with pytest.raises(ValueError, match="select"):
        encode(wave, select="guess")


def test_metadata_travels(wave):
    sequence = MeshSequence(
        wave.vertices, wave.faces, [f"walk{n}.obj" for n in range(30)], frame_rate=24.0
    )
    data = encode(sequence, target_kg=1.0)
    decoded = decode(data)
    assert decoded.frame_names == sequence.frame_names and decoded.frame_rate == 24.0
    assert info(data).frame_rate == 24.0


def test_polygon_faces_round_trip():
    vertices = wave_sequence(frames=12, grid=6)
    index = np.arange(36).reshape(6, 6)
    quads = np.stack([index[:-1, :-1], index[1:, :-1], index[1:, 1:], index[:-1, 1:]], -1).reshape(
        -1, 4
    )
    quads[::3, 3] = -1  # some triangles among the quads
    sequence = MeshSequence(vertices, quads)
    decoded = decode(encode(sequence, target_kg=0.5))
    assert_same_faces(decoded.faces, quads)
    assert kg_error(sequence, decoded) <= 0.5


def test_point_cloud_without_faces():
    sequence = MeshSequence(wave_sequence(frames=10, grid=5), np.zeros((0, 3), dtype=np.int64))
    decoded = decode(encode(sequence, target_kg=0.5))
    assert decoded.faces.shape == (0, 3) and kg_error(sequence, decoded) <= 0.5


def test_sequences_that_cannot_be_encoded():
    points = MeshSequence(np.ones((4, 5, 3)), np.zeros((0, 3), dtype=np.int64))
    with pytest.raises(tc.InputError, match="denominator is zero"):
        encode(points)


def test_a_still_sequence_is_encoded(wave):
    still = MeshSequence(np.repeat(wave.vertices[:1], 6, axis=0), wave.faces)
    result = encode_with_report(still, target_kg=0.1)
    assert result.report.ranks[1] == 1
    assert kg_error(still, decode(result.data)) <= 0.1


def test_coordinates_whose_squares_overflow_are_refused():
    huge = MeshSequence(wave_sequence(frames=4, grid=4) * 1e200, grid_faces(4))
    with pytest.raises(tc.InputError, match="too large"):
        encode(huge)


# ------------------------------------------------------------------------------------------
# unusual sequences and arguments: a file that meets the target, or a clear, typed error


def _strip(frames: int = 10, vertices: int = 30, seed: int = 0) -> MeshSequence:
    """A small moving triangle strip."""
    rng = np.random.default_rng(seed)
    t = np.linspace(0.0, 1.0, frames)[:, None, None]
    positions = rng.random((1, vertices, 3)) + 0.1 * np.sin(
        6 * t + 3 * rng.random((1, vertices, 3))
    )
    faces = np.array([[i, i + 1, i + 2] for i in range(vertices - 2)], dtype=np.int64).reshape(
        -1, 3
    )
    return MeshSequence(positions, faces)


def _assert_meets(sequence: MeshSequence, data: bytes, target: float) -> None:
    decoded = tc.decode(data)
    assert decoded.vertices.shape == sequence.vertices.shape
    assert_same_faces(decoded.faces, sequence.faces)
    assert tc.kg_error(sequence, decoded) <= target


def _variants() -> dict[str, MeshSequence]:
    base = _strip()
    duplicated = base.vertices.copy()
    duplicated[:, 5] = duplicated[:, 4]
    return {
        "one frame": _strip(frames=1),
        "two vertices": MeshSequence(_strip(vertices=2).vertices, np.zeros((0, 3), dtype=np.int64)),
        "identical frames": MeshSequence(np.repeat(base.vertices[:1], 10, axis=0), base.faces),
        "duplicate vertices": MeshSequence(duplicated, base.faces),
        "coordinates near 1e30": MeshSequence(base.vertices * 1e30, base.faces),
        "coordinates near 1e-30": MeshSequence(base.vertices * 1e-30, base.faces),
        "ten sizes off the origin": MeshSequence(base.vertices + 10.0, base.faces),
    }


@pytest.mark.parametrize("name", list(_variants()))
@pytest.mark.parametrize("target", [1.0, 0.01, 1e-6])
def test_unusual_sequences_meet_the_target(name, target):
    sequence = _variants()[name]
    result = tc.encode_with_report(sequence, target_kg=target)
    assert result.report.kg <= target
    _assert_meets(sequence, result.data, target)


@pytest.mark.parametrize("name", list(_variants()))
def test_unusual_sequences_with_fixed_ranks_and_sizes(name):
    sequence = _variants()[name]
    r1, r3 = tc.analyze(sequence).max_ranks
    full = tc.encode_with_report(sequence, ranks=(r1, r3))
    assert full.report.kg <= 1e-3  # full ranks lose nothing: only quantization, kept tiny
    sized = tc.encode_with_report(
        sequence, target_bpfv=8 * len(full.data) / (sequence.frame_count * sequence.vertex_count)
    )
    assert len(sized.data) <= len(full.data)


def test_absurdly_loose_target_gives_the_coarsest_valid_file():
    sequence = _strip()
    result = tc.encode_with_report(sequence, target_kg=1e9)
    assert result.report.ranks == (1, 1)
    _assert_meets(sequence, result.data, 1e9)


@pytest.mark.parametrize("target", [0, -1, -0.0, math.inf, math.nan, "0.1", True])
def test_targets_that_are_not_positive_numbers_are_refused(target):
    with pytest.raises(ValueError, match="target_kg must be a positive finite number"):
        tc.encode(_strip(), target_kg=target)


@pytest.mark.parametrize("ranks", [(31, 1), (1, 11), (31, 11)])
def test_ranks_beyond_the_tensor_are_refused(ranks):
    with pytest.raises(
        ValueError, match="ranks must be two integers with 1 <= i <= 30 and 1 <= k <= 10"
    ):
        tc.encode(_strip(), ranks=ranks)


@pytest.mark.parametrize("ranks", [(0, 1), (1, 0), (-1, 2), (1.5, 2), ("a", 2), (1,), 7])
def test_ranks_that_are_not_two_positive_integers_are_refused_before_any_work(ranks):
    # EncodeOptions checks their form; the tensor's bounds are known only with the sequence
    with pytest.raises(ValueError, match="ranks must be two integers, each at least 1"):
        tc.EncodeOptions(ranks=ranks)
    with pytest.raises(ValueError, match="ranks must be two integers, each at least 1"):
        tc.encode(_strip(), ranks=ranks)


def test_a_size_no_file_can_meet_is_refused_with_the_smallest_size():
    with pytest.raises(
        tc.UnreachableTargetError, match=r"no file fits 0\.001 bpfv: even the coarsest one needs"
    ):
        tc.encode(_strip(), target_bpfv=0.001)


@pytest.mark.parametrize(
    ("positions", "message"),
    [
        (np.repeat(np.ones((4, 1, 3)), 5, axis=1), "denominator is zero"),  # every frame a point
        (np.ones((4, 1, 3)), "denominator is zero"),  # one vertex
        # a shape 1e-14 across, 1 from the origin: float64 rounding, not a shape
        (
            1.0 + 1e-14 * np.random.default_rng(1).random((4, 30, 3)),
            "single point to float64's precision",
        ),
        (np.random.default_rng(2).random((4, 6, 3)) * 1e300, "too large"),
        (np.random.default_rng(3).random((4, 6, 3)) * 1e-300, "too small"),
    ],
)
def test_sequences_without_a_measurable_shape_are_refused(positions, message):
    sequence = MeshSequence(positions, np.zeros((0, 3), dtype=np.int64))
    for kwargs in ({"target_kg": 0.1}, {"ranks": (1, 1)}, {"target_bpfv": 100.0}):
        with pytest.raises(tc.InputError, match=message):
            tc.encode(sequence, **kwargs)


def test_far_from_the_origin_a_tight_target_is_refused_with_what_is_reachable():
    base = _strip()
    far = MeshSequence(base.vertices + 1e7, base.faces)  # 1e7 times the strip's size
    with pytest.raises(tc.UnreachableTargetError, match="too far from the origin") as refused:
        tc.encode(far, target_kg=0.1)
    found = re.search(r"already costs a KG error of ([0-9.]+)\. ", str(refused.value))
    assert found is not None
    floor = float(found.group(1))
    assert 0.1 < floor < 10
    # just above the floor it can be met, with the centroids at their coarsest usable step
    target = 1.1 * floor
    _assert_meets(far, tc.encode(far, target_kg=target), target)
    # and a size target falls back to the smallest reachable error instead of failing
    sized = tc.encode_with_report(far, target_bpfv=50.0)
    assert floor <= sized.report.kg * 1.01
    _assert_meets(far, sized.data, sized.report.kg * (1 + 1e-9))


# ------------------------------------------------------------------------------------------
# the real sequences: targets and sizes (NOTES.md reference + plain zstd cost of the faces)


REFERENCE_BPFV = {  # geometry at KG 1, 0.5, 0.1, 0.05, 0.02, and the faces
    "chicken": ((0.55, 0.76, 1.40, 1.74, 2.20), 0.13),
    "samba": ((0.79, 1.36, 3.97, 5.77, 9.09), 0.34),
    "horse-gallop": ((0.99, 1.65, 3.94, 5.26, 7.26), 1.11),
}


TARGETS = (1.0, 0.5, 0.1, 0.05, 0.02)


def _real(name: str) -> MeshSequence:
    if name == "horse-gallop":
        return tc.load_sequence(shared_file("horse-gallop"), progress=False)
    vertices, faces = load_shared_npz(f"{name}.npz")
    return MeshSequence(vertices, faces)


@pytest.mark.slow
@pytest.mark.parametrize("name", ["chicken", "samba", "horse-gallop", "cloth-vellum"])
def test_real_sequences_meet_every_target_within_the_reference_size(name):
    sequence = _real(name)
    analysis = tc.analyze(sequence)
    for n, target in enumerate(TARGETS):
        result = encode_with_report(sequence, target_kg=target, analysis=analysis)
        assert kg_error(sequence, decode(result.data)) <= target, (name, target)
        if name in REFERENCE_BPFV:
            geometry, faces = REFERENCE_BPFV[name]
            assert result.report.bpfv <= geometry[n] + faces, (name, target, result.report.bpfv)
