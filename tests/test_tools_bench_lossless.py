"""tools.bench lossless: every peer's round trip bit for bit, in float32 and float64, and the
suite's tables, on a few frames of the built-in sample (the cloth), untimed.

fpzip, pcodec and Blosc2 (``pip install '.[bench]'``) are tested only where they are installed,
and skip saying so elsewhere.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from tools import bench, common
from tools.bench import lossless
from tools.bench.peers import base, blosc, fpz, pco, zstd
from tuckercodec import MeshSequence


@pytest.fixture(scope="module")
def short():
    sequence = common.load(common.SAMPLE)
    return MeshSequence(sequence.vertices[:6], sequence.faces)


@pytest.fixture(scope="module")
def doubles(short):
    # float64 values that no float32 holds: each peer must keep all 64 bits
    return MeshSequence(short.vertices * (1.0 + 2.0**-40), short.faces)


PEERS = [
    (zstd.run_zstd_lossless, "zstandard"),
    (fpz.run_fpzip, "fpzip"),
    (pco.run_pcodec, "pcodec"),
    (blosc.run_blosc2, "blosc2"),
]


@pytest.mark.parametrize(("run", "module"), PEERS)
@pytest.mark.parametrize("precision", ["short", "doubles"])
def test_every_setting_of_a_peer_is_bit_exact_in_the_values_own_precision(
    run, module, precision, request
):
    pytest.importorskip(module, reason=f"{module} is not installed (pip install '.[bench]')")
    sequence = request.getfixturevalue(precision)
    values = base.own_precision(sequence)
    assert values.dtype == (np.float32 if precision == "short" else np.float64)
    trials = run(sequence, values)
    assert len(trials) >= len(base.LAYOUTS)  # every layout tried
    for trial in trials:
        assert trial.decoded.dtype == values.dtype
        assert lossless.bit_exact(values, trial.decoded), trial.setting
        assert trial.connectivity_bytes == len(base.faces_once(sequence))
        assert trial.total_bytes > trial.connectivity_bytes


def test_bit_exactness_compares_bits_after_narrowing_to_the_inputs_precision():
    values = np.array([[[1.5, -0.0, 3.0]]], dtype=np.float32)
    assert lossless.bit_exact(values, values.astype(np.float64))
    assert not lossless.bit_exact(values, np.array([[[1.5, 0.0, 3.0]]]))  # the sign of zero
    one_ulp = values.copy()
    one_ulp[0, 0, 2] = np.nextafter(np.float32(3.0), np.float32(4.0))
    assert not lossless.bit_exact(values, one_ulp)
    assert not lossless.bit_exact(values, values[:, :, :2])


def test_the_suite_reports_the_smallest_file_of_each_coder(short, tmp_path, capsys):
    pytest.importorskip("fpzip", reason="fpzip is not installed (pip install '.[bench]')")
    path = tmp_path / "short.npz"
    np.savez(path, V=short.vertices.astype(np.float32), F=short.faces)
    out = tmp_path / "lossless"
    args = ["lossless", str(path), "--coders", "fpzip,zstd-19", "--repeat", "2"]
    args += ["--out", str(out)]
    assert bench.main(args) == 0
    text = capsys.readouterr().out
    summary = next(line for line in text.splitlines() if line.startswith("| short | float32 |"))
    cells = [cell.strip() for cell in summary.strip("|").split("|")]
    entries = json.loads((out / "results.json").read_text())
    chosen = {e["coder"]: e for e in entries if e["chosen"]}
    assert float(cells[2]) == pytest.approx(chosen["fpzip"]["bpfv"], abs=0.005)
    smallest = min(chosen, key=lambda coder: chosen[coder]["bytes"])
    assert cells[4] == smallest
    for coder, entry in chosen.items():  # each coder's smallest file over every setting
        assert entry["bytes"] == min(e["bytes"] for e in entries if e["coder"] == coder)
        assert entry["exact"] and entry["decode_mb_s"] > 0
    assert "Misses: none." in text
    assert bench.main(args) == 2  # results are never replaced without --force
    assert "--force" in capsys.readouterr().err


@pytest.mark.parametrize("precision", ["short", "doubles"])
def test_tuckercodec_lossless_gives_back_every_bit(precision, request):
    sequence = request.getfixturevalue(precision)
    values = base.own_precision(sequence)
    (entry,) = lossless.measure(
        precision, "tuckercodec", lossless.CODERS["tuckercodec"][1], sequence, values, 1
    )
    assert entry.error is None
    assert entry.exact and entry.chosen
    assert not entry.float64_differences  # the float64 output is the input's values too
    assert entry.decode_mb_s is not None and entry.decode_mb_s > 0


def test_the_decode_is_timed_part_by_part_for_the_lossless_and_the_plain_file(short):
    lossless_file, plain = lossless.decode_parts("short", short, 1)
    assert (lossless_file.file, plain.file) == ("lossless", "KG 0.1")
    assert lossless_file.bytes > plain.bytes  # every bit costs more than KG 0.1
    for parts in (lossless_file, plain):
        assert parts.open_seconds > 0 and parts.positions_seconds > 0
        assert parts.mb_s == pytest.approx(short.vertices.size * 4 / 1e6 / parts.decode_seconds)


@pytest.mark.parametrize("bits", [8, 14])
def test_quantized_caches_take_few_values_within_half_a_step(bits):
    rng = np.random.default_rng(3)
    positions = rng.normal(size=(12, 40, 3)) * np.array([1.0, 5.0, 0.2])
    quantized = lossless.quantized(positions, bits)
    assert quantized.dtype == np.float32
    span = positions.max(axis=(0, 1)) - positions.min(axis=(0, 1))
    for axis in range(3):
        assert len(np.unique(quantized[..., axis])) <= 2**bits
        error = np.abs(quantized[..., axis] - positions[..., axis]).max()
        assert error <= 0.5 * span[axis] / (2**bits - 1) * (1 + 1e-3) + 1e-6 * span[axis]
