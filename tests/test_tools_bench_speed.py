"""tools.bench speed: this checkout against the package at a baseline revision, run on a few
frames of the built-in sample with HEAD as the baseline; no timing is asserted, only that
every measure ran, that the same file decodes to the same positions and OBJ text in both
packages, and that a difference or a failing child is reported as such."""

from __future__ import annotations

import shutil
import subprocess

import pytest

from tools import bench, common
from tools.bench import speed
from tuckercodec import MeshSequence, save_sequence


def _has_git() -> bool:
    if shutil.which("git") is None:
        return False
    found = subprocess.run(
        ["git", "-C", str(common.REPO), "cat-file", "-e", "HEAD"], capture_output=True
    )
    return found.returncode == 0


@pytest.fixture(scope="module")
def short(tmp_path_factory):
    sequence = common.load(common.SAMPLE)
    path = tmp_path_factory.mktemp("speed") / "short.npz"
    save_sequence(MeshSequence(sequence.vertices[:5], sequence.faces), path, progress=False)
    return path


def _rows(out: str, first_cell: str) -> list[list[str]]:
    return [
        [cell.strip() for cell in line.strip().strip("|").split("|")]
        for line in out.splitlines()
        if line.startswith(f"| {first_cell} |")
    ]


@pytest.mark.skipif(not _has_git(), reason="needs git and the repository's history")
def test_every_measure_runs_against_the_baseline_and_agrees_with_it(short, tmp_path, capsys):
    out_folder = tmp_path / "results"
    argv = ["speed", str(short), "--baseline", "HEAD", "--repeat", "1", "--warmup", "0"]
    assert bench.main([*argv, "--out", str(out_folder)]) == 0
    out = capsys.readouterr().out
    rows = _rows(out, "short")
    encodes = [row for row in rows if row[1] in ("0.1", "0.02")]
    assert [row[1] for row in encodes] == ["0.1", "0.02"]
    assert all(row[-1] == "ok" for row in encodes)  # decoded KG within the target
    decodes = {row[1]: row for row in rows if row[1] in ("own", "baseline's")}
    assert decodes["baseline's"][-1] == "yes"  # bit-identical positions of the same file
    (obj,) = [row for row in rows if row[1] == "5"]  # five OBJ files, the short input's frames
    assert obj[-1] == "yes"  # the same text from both packages
    assert "Verdicts against the speed targets" in out
    assert "FAILED" not in out and "machine: " in out and "command: python -m tools.bench" in out
    assert (out_folder / speed.MARKER).read_text() == out
    assert not list(out_folder.glob("*.obj-*"))  # the OBJ folders are removed once hashed
    # the folder holds results now: refused without --force, before anything runs
    assert bench.main([*argv, "--out", str(out_folder)]) == 2


def test_a_child_that_fails_stops_its_measure_and_names_itself(tmp_path):
    nowhere = speed.Package("nowhere", tmp_path)  # no tuckercodec there to import
    measure = speed.interleaved([("old", nowhere, {"kind": "decode", "file": "x"})], 2, 1)
    assert measure.samples == {"old": []}
    assert len(measure.errors) == 1 and measure.errors[0].startswith("nowhere: exit 1")


def _decode_samples(hashes: tuple[str, str]) -> speed.Measure:
    sample = {"open_frame": 0.2, "positions": 0.4}
    old, new = ({**sample, "hash": value} for value in hashes)
    faster = {"open_frame": 0.05, "positions": 0.1, "hash": hashes[1]}
    return speed.Measure({"old": [old], "new": [faster], "new on old file": [new]})


def test_positions_that_differ_are_a_failure_and_speed_ups_are_judged():
    report = speed.Report()
    same = speed.SequenceResult("samba", decode=_decode_samples(("a", "a")))
    speed.decode_table(report, [same])
    assert not report.failures
    assert report.verdicts[0].startswith("samba: `Decoder(bytes)` + first frame at least 3x: met")
    assert "NOT met" in report.verdicts[0]  # the baseline's file decodes no faster here
    report = speed.Report()
    differs = speed.SequenceResult("samba", decode=_decode_samples(("a", "b")))
    speed.decode_table(report, [differs])
    assert report.failures == ["samba: the baseline's file decodes to other positions now"]
    assert "| samba | baseline's | 0.2000 | 0.2000 | 1.00 |" in "\n".join(report.lines)


def test_obj_text_that_differs_is_a_failure():
    report = speed.Report()
    old = {"seconds": 3.0, "hashes": {"a.obj": "1"}, "bytes": 10}
    new = {"seconds": 1.0, "hashes": {"a.obj": "2"}, "bytes": 10}
    result = speed.SequenceResult("horse", obj=speed.Measure({"old": [old], "new": [new]}))
    speed.obj_table(report, [result])
    assert report.failures == ["horse: the OBJ text differs from the baseline's"]
    assert "NOT met" in report.verdicts[0]


def test_the_large_files_target_counts_the_import_a_lazy_package_pays_in_the_call(tmp_path):
    # the old package imports everything before the call, the new one inside it: judged on the
    # sum, the new one is 2x here, not the 5x its call alone would show
    def sample(imported: float, first: float) -> dict[str, object]:
        return {
            "import": imported,
            "first": first,
            "first_with_import": imported + first,
            "first_peak": 100 * speed.MB,
            "later": [0.01],
        }

    measure = speed.Measure({"old": [sample(1.0, 3.0)], "new": [sample(0.0, 2.0)]})
    large = speed.LargeResult(tmp_path / "large.tkc", [1], measure, "made now")
    report = speed.Report()
    speed.large_table(report, large)
    text = "\n".join(report.lines)
    assert "| import tuckercodec + open + frame 0 (s) | 4.000 | 2.000 | 2.00 |" in text
    assert "| open + frame 0 (s) | 3.000 | 2.000 | 1.50 |" in text
    assert "first frame at least 5x: NOT met (2.00x)" in report.verdicts[0]
