"""The command line, run in-process through ``main`` and once as a real console script."""

from __future__ import annotations

import csv
import shutil
import subprocess
import sys

import numpy as np
import pytest
from conftest import grid_faces, wave_sequence

from tuckercodec import __version__
from tuckercodec.cli import main


@pytest.fixture()
def wave_npz(tmp_path):
    path = tmp_path / "wave.npz"
    np.savez(path, V=wave_sequence(20, 8), F=grid_faces(8))
    return path


def test_rd_prints_exact_and_bound_choices(wave_npz, capsys):
    assert main(["rd", str(wave_npz), "--targets", "1,0.1"]) == 0
    out = capsys.readouterr().out
    assert "20 frames, 64 vertices, 98 faces" in out
    assert "Karni-Gotsman" in out
    rows = [line.split() for line in out.splitlines() if line.strip()[:1].isdigit()]
    assert [(r[0], r[1]) for r in rows] == [("1", "exact"), ("1", "bound"), ("0.1", "exact"), ("0.1", "bound")]
    for row in rows:
        assert float(row[6]) <= float(row[0])  # exact KG of the pick meets the target
        assert float(row[7]) >= float(row[6])  # the estimate bounds it


def test_rd_writes_csv_and_plots_and_refuses_to_overwrite(wave_npz, tmp_path, capsys):
    pytest.importorskip("matplotlib")
    table, plot, heatmap = tmp_path / "rd.csv", tmp_path / "rd.png", tmp_path / "heat.png"
    args = ["rd", str(wave_npz), "--csv", str(table), "--plot", str(plot), "--heatmap", str(heatmap)]
    assert main(args) == 0
    with open(table, newline="") as handle:
        rows = list(csv.DictReader(handle))
    assert {row["curve"] for row in rows} == {"hosvd_exact", "hosvd_bound", "pca"}
    exact = [row for row in rows if row["curve"] == "hosvd_exact"]
    assert np.all(np.diff([float(r["kg_exact"]) for r in exact]) < 0)
    for path in (plot, heatmap):
        assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"

    before = table.read_bytes()
    capsys.readouterr()
    assert main(args) == 1
    err = capsys.readouterr().err
    assert "already exists" in err and "--force" in err and "Traceback" not in err
    assert table.read_bytes() == before
    assert main(args + ["--force"]) == 0
    assert not list(tmp_path.glob(".*.tmp"))


def test_bad_input_is_one_line_and_exit_4(tmp_path, capsys):
    bad = tmp_path / "bad.npz"
    np.savez(bad, V=np.zeros((3, 4)), F=np.zeros((1, 3), dtype=np.int32))
    assert main(["rd", str(bad)]) == 4
    err = capsys.readouterr().err.strip()
    assert err.startswith("tuckercodec: bad input:") and str(bad) in err
    assert len(err.splitlines()) == 1

    empty = tmp_path / "empty"
    empty.mkdir()
    assert main(["rd", str(empty)]) == 4
    assert str(empty) in capsys.readouterr().err


def test_single_frame_is_refused_with_exit_4(tmp_path, capsys):
    one = tmp_path / "one.npz"
    np.savez(one, V=wave_sequence(1, 4), F=grid_faces(4))
    assert main(["rd", str(one)]) == 4
    assert "at least 2 frames" in capsys.readouterr().err


def test_usage_errors_exit_2(capsys):
    with pytest.raises(SystemExit) as exit_info:
        main(["rd", "x.npz", "--targets", "0.1,-3"])
    assert exit_info.value.code == 2
    with pytest.raises(SystemExit) as exit_info:
        main([])
    assert exit_info.value.code == 2


@pytest.mark.parametrize("verb", [[], ["rd"], ["demo"]])
def test_help_on_every_verb(verb, capsys):
    with pytest.raises(SystemExit) as exit_info:
        main(verb + ["--help"])
    assert exit_info.value.code == 0
    assert "usage: tuckercodec" in capsys.readouterr().out


def test_demo_runs_on_the_builtin_sample(capsys):
    assert main(["demo", "--targets", "0.5"]) == 0
    out = capsys.readouterr().out
    assert "60 frames, 3101 vertices, 5912 faces" in out


def test_console_script_version():
    script = shutil.which("tuckercodec")
    command = [script] if script else [sys.executable, "-m", "tuckercodec.cli"]
    done = subprocess.run(command + ["--version"], capture_output=True, text=True, check=False)
    assert done.returncode == 0
    assert done.stdout.strip() == f"tuckercodec {__version__}"


def test_outputs_are_checked_before_the_work(wave_npz, tmp_path, capsys):
    missing = tmp_path / "no-such-folder" / "rd.csv"
    assert main(["rd", str(wave_npz), "--csv", str(missing)]) == 1
    err = capsys.readouterr().err
    assert "no-such-folder: the output folder does not exist" in err and "HOSVD" not in err
    assert main(["rd", str(wave_npz), "--plot", str(tmp_path / "rd.txt")]) == 2
    assert "must end in .png" in capsys.readouterr().err
    assert not (tmp_path / "rd.txt").exists()
