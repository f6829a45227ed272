"""OBJ vertex text made by array operations (tuckercodec.io.common.float_text): byte for byte what
``repr`` of every value gives, on random float64 and float32 values at every scale, random bit
patterns, and the edge values (zeros of both signs, subnormals, the largest and smallest
normals, powers of two and ten, the ends of the positional range, ties, integers)."""

from __future__ import annotations

import numpy as np
import pytest

from tuckercodec.io import obj
from tuckercodec.io.common import float_text as shortest


def _by_repr(vertices: np.ndarray) -> bytes:
    """The text of the per-value formatter this replaces: repr of each float, three a line."""
    return "".join(f"v {x!r} {y!r} {z!r}\n" for x, y, z in vertices.tolist()).encode("ascii")


def _check(values: np.ndarray) -> None:
    values = np.asarray(values, dtype=np.float64).reshape(-1)
    values = np.concatenate([values, np.zeros(-len(values) % 3)]).reshape(-1, 3)
    made, expected = shortest.vertex_text(values), _by_repr(values)
    if made != expected:  # name the first line that differs
        pairs = zip(made.decode().splitlines(), expected.decode().splitlines(), strict=False)
        first = next((pair for pair in pairs if pair[0] != pair[1]), None)
        pytest.fail(f"differs from repr: {first}")


RNG = np.random.default_rng(24)


@pytest.mark.parametrize("scale", [1e-300, 1e-9, 1e-5, 1e-4, 1e-3, 0.1, 1.0, 10.0, 1e6, 1e15, 1e17])
def test_random_float64_at_every_scale(scale):
    _check(RNG.standard_normal(9_000) * scale)


@pytest.mark.parametrize("scale", [1e-5, 1e-2, 1.0, 1e3, 1e7])
def test_random_float32_values_widened_as_write_obj_widens_them(scale):
    _check((RNG.standard_normal(9_000) * scale).astype(np.float32))


def test_random_bit_patterns():
    values = RNG.integers(0, 2**64, 60_000, dtype=np.uint64).view(np.float64)
    _check(values[np.isfinite(values)])


def test_every_binary_exponent_of_the_positional_range_and_its_ends():
    exponents = np.arange(-20, 60)
    mantissas = RNG.random((len(exponents), 200)) + 1.0
    values = np.ldexp(mantissas, exponents[:, None])
    ends = np.array([np.nextafter(1e-4, 0), 1e-4, np.nextafter(1e-4, 1), 1e16, 2.0**49, 2.0**53])
    _check(np.concatenate([values.ravel(), ends, -ends, np.nextafter(ends, np.inf)]))


def test_edge_values():
    tiny = np.finfo(np.float64).tiny
    edge = [0.0, -0.0, 5e-324, -5e-324, tiny, np.nextafter(tiny, 0), -tiny]
    edge += [np.finfo(np.float64).max, -np.finfo(np.float64).max, 1e22, 1e23, 9007199254740993.0]
    edge += [0.1, 0.2, 0.3, 1 / 3, 2 / 3, 0.5, 0.25, 0.125, 1.0, -1.0, 100.0, 1e15, 123456.789]
    edge += [9.999999999999999e-05, 0.00010000000000000002, 1234567890123456.0, 4.35, 0.0001]
    edge += [float(2**k) for k in range(-30, 60)] + [10.0**k for k in range(-8, 18)]
    edge += [float(f"0.{'9' * n}") for n in range(1, 18)]
    _check(np.array(edge))


def test_integers_halves_and_values_near_decimal_ties():
    integers = RNG.integers(-(10**6), 10**6, 6_000).astype(np.float64)
    halves = RNG.integers(-(10**6), 10**6, 6_000) / 64.0
    decimals = np.concatenate([np.round(RNG.standard_normal(600), n) for n in range(1, 17)])
    _check(np.concatenate([integers, halves, decimals, np.nextafter(decimals, np.inf)]))


def test_non_finite_values_are_repr_too():
    # write_obj refuses them before formatting; the formatter itself still gives repr's text
    _check(np.array([np.nan, np.inf, -np.inf, 1.5, -np.nan, 0.1]))


def test_an_empty_array_and_a_single_vertex():
    assert shortest.vertex_text(np.zeros((0, 3))) == b""
    _check(np.array([-0.0, 1e-7, 3.25]))


def test_write_obj_writes_the_text_of_repr(tmp_path):
    vertices = np.concatenate([RNG.standard_normal((500, 3)), RNG.standard_normal((5, 3)) * 1e-6])
    vertices[3] = [-0.0, 0.0, 5e-324]
    faces = np.array([[0, 1, 2], [2, 3, 4]])
    obj.write_obj(tmp_path / "a.obj", vertices, faces)
    expected = _by_repr(vertices) + b"f 1 2 3\nf 3 4 5\n"
    assert (tmp_path / "a.obj").read_bytes() == expected


def test_blocks_of_rows_join_to_the_text_of_the_whole(monkeypatch):
    # rows left to repr (1e20, subnormals) first, last and inside blocks of 7 rows
    monkeypatch.setattr(shortest, "BLOCK_ROWS", 7)
    values = RNG.standard_normal(3 * 50)
    values[[0, 20, 21, 22, 64, 149]] = [1e20, 5e-324, -1e-300, 2.0**60, -1e17, 1e300]
    _check(values)
