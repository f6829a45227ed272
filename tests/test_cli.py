"""The command line, run in-process through ``main`` and once as a real console script."""

from __future__ import annotations

import csv
import json
import re
import shutil
import subprocess
import sys
import unicodedata
from typing import Any

import numpy as np
import pytest

from tests.support.sequences import grid_faces, wave_sequence
from tuckercodec import __version__
from tuckercodec.cli import main
from tuckercodec.encoder import corrections
from tuckercodec.errors import InternalError


@pytest.fixture
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
    assert [(r[0], r[1]) for r in rows] == [
        ("1", "exact"),
        ("1", "bound"),
        ("0.1", "exact"),
        ("0.1", "bound"),
    ]
    for row in rows:
        assert float(row[6]) <= float(row[0])  # exact KG of the pick meets the target
        assert float(row[7]) >= float(row[6])  # the estimate bounds it


def test_rd_writes_csv_and_plots_and_refuses_to_overwrite(wave_npz, tmp_path, capsys):
    pytest.importorskip("matplotlib")
    table, plot, heatmap = tmp_path / "rd.csv", tmp_path / "rd.png", tmp_path / "heat.png"
    args = [
        "rd",
        str(wave_npz),
        "--csv",
        str(table),
        "--plot",
        str(plot),
        "--heatmap",
        str(heatmap),
    ]
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
    assert main([*args, "--force"]) == 0
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


def test_a_single_frame_is_a_sequence_like_any_other(tmp_path, capsys):
    one = tmp_path / "one.npz"
    np.savez(one, V=wave_sequence(1, 4), F=grid_faces(4))
    assert main(["rd", str(one)]) == 0
    assert main(["encode", str(one), "-o", str(tmp_path / "one.tkc"), "--kg", "0.5"]) == 0
    assert (
        main(
            [
                "decode",
                str(tmp_path / "one.tkc"),
                "-o",
                str(tmp_path / "one-back.npz"),
                "--reference",
                str(one),
            ]
        )
        == 0
    )


def test_usage_errors_exit_2(capsys):
    with pytest.raises(SystemExit) as exit_info:
        main(["rd", "x.npz", "--targets", "0.1,-3"])
    assert exit_info.value.code == 2
    with pytest.raises(SystemExit) as exit_info:
        main([])
    assert exit_info.value.code == 2


@pytest.mark.parametrize(
    "verb",
    [
        [],
        ["rd"],
        ["demo"],
        ["encode"],
        ["decode"],
        ["info"],
        ["eval"],
        ["render"],
        ["convert"],
        ["formats"],
        ["blender-addon"],
    ],
)
def test_help_on_every_verb(verb, capsys):
    with pytest.raises(SystemExit) as exit_info:
        main([*verb, "--help"])
    assert exit_info.value.code == 0
    assert "usage: tuckercodec" in capsys.readouterr().out


def test_demo_runs_on_the_builtin_sample(capsys):
    assert main(["demo", "--targets", "0.5"]) == 0
    out = capsys.readouterr().out
    assert "60 frames, 3101 vertices, 5912 faces" in out
    row = next(line.split() for line in out.splitlines() if line.strip().startswith("0.5"))
    assert float(row[6]) <= 0.5  # the decoded KG error, measured by the demo itself


def test_console_script_version():
    script = shutil.which("tuckercodec")
    command = [script] if script else [sys.executable, "-m", "tuckercodec.cli"]
    done = subprocess.run([*command, "--version"], capture_output=True, text=True, check=False)
    assert done.returncode == 0
    assert done.stdout.startswith(f"tuckercodec {__version__}, ")


def test_outputs_are_checked_before_the_work(wave_npz, tmp_path, capsys):
    missing = tmp_path / "no-such-folder" / "rd.csv"
    assert main(["rd", str(wave_npz), "--csv", str(missing)]) == 1
    err = capsys.readouterr().err
    assert "no-such-folder: the output folder does not exist" in err and "HOSVD" not in err
    assert main(["rd", str(wave_npz), "--plot", str(tmp_path / "rd.txt")]) == 2
    assert "must end in .png" in capsys.readouterr().err
    assert not (tmp_path / "rd.txt").exists()


# ------------------------------------------------------------------------------------------
# the codec's verbs


def test_encode_decode_info_eval(wave_npz, tmp_path, capsys):
    packed = tmp_path / "wave.tkc"
    assert main(["encode", str(wave_npz), "-o", str(packed), "--kg", "0.5"]) == 0
    out = capsys.readouterr().out
    assert "decoded KG error" in out and "bpfv" in out and "smaller than raw float32" in out
    assert "Karni-Gotsman" in out

    assert main(["info", str(packed), "--json"]) == 0
    header = json.loads(capsys.readouterr().out)
    assert header["frames"] == 20 and header["vertices"] == 64 and header["kg"] <= 0.5
    assert header["total_bytes"] == packed.stat().st_size

    frames = tmp_path / "frames"
    assert (
        main(
            [
                "decode",
                str(packed),
                "-o",
                str(frames),
                "--frames",
                "5:8",
                "--reference",
                str(wave_npz),
            ]
        )
        == 0
    )
    out = capsys.readouterr().out
    assert "3 of 20 frames" in out and "of the 3 frames decoded" in out
    assert len(list(frames.glob("*.obj"))) == 3
    assert (
        sum(line.startswith("f ") for line in next(frames.glob("*.obj")).read_text().splitlines())
        == 98
    )

    assert (
        main(["decode", str(packed), "-o", str(tmp_path / "all.npz"), "--reference", str(wave_npz)])
        == 0
    )
    out = capsys.readouterr().out
    actual = float(out.split("actual KG error against")[1].split(":")[1].split()[0])
    assert actual <= 0.5
    assert main(["eval", str(wave_npz), str(tmp_path / "all.npz"), "--json"]) == 0
    figures = json.loads(capsys.readouterr().out)
    assert figures["kg"] == pytest.approx(header["kg"], rel=1e-6)
    assert main(["eval", str(wave_npz), str(packed)]) == 0  # a compressed file is decoded
    assert "worst vertex" in capsys.readouterr().out


# ------------------------------------------------------------------------------------------
# the worst vertex beside the KG error: what a bound on every vertex (--max-error) promises

WORST = re.compile(r"worst vertex (?:against \S+: )?(\S+) at frame (\d+), vertex (\d+) \((.*)\)")


def brute_worst(original: np.ndarray, decoded: np.ndarray) -> tuple[float, int, int]:
    """The largest Euclidean distance between matching vertices and its (frame, vertex)."""
    distances = np.linalg.norm(original - decoded, axis=2)
    frame, vertex = np.unravel_index(int(np.argmax(distances)), distances.shape)
    return float(distances[frame, vertex]), int(frame), int(vertex)


def printed_worst(line: str) -> tuple[float, int, int]:
    found = WORST.search(line)
    assert found is not None, line
    assert "largest Euclidean distance" in found[4] and "sequence's units" in found[4]
    return float(found[1]), int(found[2]), int(found[3])


def assert_worst(line: str, distance: float, frame: int, vertex: int) -> None:
    """The line names this frame and vertex, and this distance to the 6 digits printed."""
    printed, *at = printed_worst(line)
    assert printed == pytest.approx(distance, rel=1e-5) and at == [frame, vertex], line


def line_with(out: str, words: str) -> str:
    lines = [line for line in out.splitlines() if words in line]
    assert len(lines) == 1, out
    return lines[0]


def test_decode_and_eval_report_the_worst_vertex_beside_the_kg(wave_npz, tmp_path, capsys):
    packed = tmp_path / "wave.tkc"
    assert main(["encode", str(wave_npz), "-o", str(packed), "--kg", "0.5"]) == 0
    original = np.load(wave_npz)["V"]
    capsys.readouterr()
    everything = tmp_path / "all.npz"
    assert main(["decode", str(packed), "-o", str(everything), "--reference", str(wave_npz)]) == 0
    out = capsys.readouterr().out
    decoded = np.load(everything)["V"]
    distance, frame, vertex = brute_worst(original, decoded)
    lines = out.splitlines()
    kg_at = next(n for n, line in enumerate(lines) if line.startswith("actual KG error against"))
    assert lines[kg_at + 1].startswith(f"actual worst vertex against {wave_npz}: ")
    assert_worst(lines[kg_at + 1], distance, frame, vertex)

    # a range of frames: the worst of those frames, numbered as in the file
    part = tmp_path / "part.npz"
    args = ["decode", str(packed), "-o", str(part), "--frames", "11:15"]
    assert main([*args, "--reference", str(wave_npz)]) == 0
    line = line_with(capsys.readouterr().out, "actual worst vertex against")
    distance, frame, vertex = brute_worst(original[11:15], np.load(part)["V"])
    assert_worst(line, distance, 11 + frame, vertex)
    assert "of the 4 frames decoded" in line

    # the same range as a glTF decomposition: the .tkc's worst vertex of those frames
    glb = tmp_path / "part.glb"
    args = ["decode", str(packed), "-o", str(glb), "--frames", "11:15"]
    assert main([*args, "--reference", str(wave_npz)]) == 0
    line = line_with(capsys.readouterr().out, "actual worst vertex against")
    assert_worst(line, distance, 11 + frame, vertex)

    # eval: text beside the KG error, and JSON with the keys info --json uses
    assert main(["eval", str(wave_npz), str(everything)]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].startswith("KG error") and lines[1].startswith("worst vertex")
    distance, frame, vertex = brute_worst(original, decoded)
    assert_worst(lines[1], distance, frame, vertex)
    assert main(["eval", str(wave_npz), str(everything), "--json"]) == 0
    figures = json.loads(capsys.readouterr().out)
    assert figures["max_distance"] == distance and figures["max_distance_at"] == [frame, vertex]
    assert "largest Euclidean distance" in figures["max_distance_definition"]

    # a file without the header keys says where to measure it
    assert main(["info", str(packed)]) == 0
    line = line_with(capsys.readouterr().out, "worst vertex")
    assert "not recorded in the file" in line and "--max-error or --lossless" in line
    assert main(["info", str(packed), "--json"]) == 0
    header = json.loads(capsys.readouterr().out)
    assert header["max_distance"] is None and header["max_distance_at"] is None
    assert header["lossless"] is None


def test_info_and_decode_print_the_worst_vertex_a_file_records(wave_npz, tmp_path, capsys):
    """A file with the error keys of spec §4.1 (1.3), written here by hand over a real file."""
    from tests.support.compressed import Parts

    packed = tmp_path / "wave.tkc"
    assert main(["encode", str(wave_npz), "-o", str(packed), "--kg", "0.5"]) == 0
    parts = Parts(packed.read_bytes())
    parts.header["error"].update(
        max_distance=0.0125, max_distance_at=[3, 7], target_max_distance=0.02, lossless=False
    )
    bounded = tmp_path / "bounded.tkc"
    bounded.write_bytes(parts.pack())
    parts.header["error"].update(max_distance=0.0, max_distance_at=[0, 0], lossless=True)
    parts.header["error"]["target_max_distance"] = None
    exact = tmp_path / "exact.tkc"
    exact.write_bytes(parts.pack())
    capsys.readouterr()

    assert main(["info", str(bounded)]) == 0
    out = capsys.readouterr().out
    line = line_with(out, "worst vertex")
    assert printed_worst(line) == (0.0125, 3, 7) and line.endswith(", bound 0.02")
    lines = out.splitlines()
    assert lines.index(line) == 1 + next(n for n, x in enumerate(lines) if "KG error" in x)
    assert "lossless" not in out
    assert main(["info", str(bounded), "--json"]) == 0
    header = json.loads(capsys.readouterr().out)
    assert header["max_distance"] == 0.0125 and header["max_distance_at"] == [3, 7]
    assert header["target_max_distance"] == 0.02 and header["lossless"] is False

    assert main(["info", str(exact)]) == 0
    out = capsys.readouterr().out
    assert printed_worst(line_with(out, "worst vertex")) == (0.0, 0, 0)
    assert "bound" not in out
    assert "lossless: the encoder checked the decoded values to be the input's" in out

    assert main(["decode", str(bounded), "-o", str(tmp_path / "b.npz")]) == 0
    line = line_with(capsys.readouterr().out, "file:")
    assert "KG error recorded by the encoder" in line
    assert line.endswith("; worst vertex 0.0125 at frame 3, vertex 7, bound 0.02")


def test_encode_prints_the_worst_vertex_and_the_bound_it_measured(
    wave_npz, tmp_path, capsys, monkeypatch
):
    """What the encoder's report holds is printed beside its KG error (the report's fields are
    set here, as the encoder of --max-error and --lossless sets them)."""
    import dataclasses

    from tuckercodec.encoder import Encoder, EncodeResult

    measured: dict[str, Any] = {
        "max_distance": 0.00123456789,
        "max_distance_at": (4, 9),
        "max_error": 0.002,
        "corrections": "grid",
    }
    real = Encoder.encode_source

    def encode_source(self, frames, **kwargs):
        result = real(self, frames, **kwargs)
        return EncodeResult(result.data, dataclasses.replace(result.report, **measured))

    monkeypatch.setattr(Encoder, "encode_source", encode_source)
    assert main(["encode", str(wave_npz), "-o", str(tmp_path / "a.tkc"), "--ranks", "4,4"]) == 0
    lines = capsys.readouterr().out.splitlines()
    kg_at = next(n for n, line in enumerate(lines) if "decoded KG error" in line)
    assert lines[kg_at + 1].startswith("decoded worst vertex 0.00123457 at frame 4, vertex 9 (")
    assert printed_worst(lines[kg_at + 1]) == (0.00123457, 4, 9)
    assert lines[kg_at + 2].startswith("bound on every vertex 0.002 (--max-error")
    assert lines[kg_at + 2].endswith("; corrections (spec §6.9) in the grid domain")
    assert not any("lossless" in line for line in lines)

    measured.update(max_distance=0.0, max_distance_at=(0, 0), max_error=None, lossless=True)
    measured["corrections"] = "float32"
    assert main(["encode", str(wave_npz), "-o", str(tmp_path / "b.tkc"), "--ranks", "4,4"]) == 0
    lines = capsys.readouterr().out.splitlines()
    kg_at = next(n for n, line in enumerate(lines) if "decoded KG error" in line)
    assert printed_worst(lines[kg_at + 1]) == (0.0, 0, 0)
    assert lines[kg_at + 2] == (
        "lossless: the decoded values checked to be the input's, bit for bit; "
        "corrections (spec §6.9) in the float32 domain"
    )
    assert not any("bound on every vertex" in line for line in lines)

    monkeypatch.setattr(Encoder, "encode_source", real)  # every whole encode measures it
    assert main(["encode", str(wave_npz), "-o", str(tmp_path / "c.tkc"), "--ranks", "4,4"]) == 0
    out = capsys.readouterr().out
    assert "decoded worst vertex" in out and "bound on every vertex" not in out


def test_encode_never_overwrites_without_force(wave_npz, tmp_path, capsys):
    packed = tmp_path / "wave.tkc"
    packed.write_bytes(b"precious")
    assert main(["encode", str(wave_npz), "-o", str(packed)]) == 1
    assert "already exists" in capsys.readouterr().err
    assert packed.read_bytes() == b"precious"
    assert main(["encode", str(wave_npz), "-o", str(packed), "--force", "--ranks", "4,4"]) == 0
    assert packed.read_bytes()[:4] == b"\x89TKC"
    assert not list(tmp_path.glob(".*.tmp"))


def test_corrupt_files_exit_3_naming_the_file(wave_npz, tmp_path, capsys):
    packed = tmp_path / "wave.tkc"
    assert main(["encode", str(wave_npz), "-o", str(packed)]) == 0
    data = packed.read_bytes()
    cut = tmp_path / "cut.tkc"
    cut.write_bytes(data[:-10])
    flipped = tmp_path / "flipped.tkc"
    flipped.write_bytes(data[:-5] + bytes([data[-5] ^ 0x10]) + data[-4:])
    capsys.readouterr()
    for path, verb, words, rule in (
        (cut, "info", "cut short", "R10-file-truncated"),
        (cut, "decode", "cut short", "R10-file-truncated"),
        (flipped, "decode", "CRC-32", "R19-section-crc"),
    ):
        args = [verb, str(path)] + (["-o", str(tmp_path / "out")] if verb == "decode" else [])
        assert main(args) == 3
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and str(path) in err and words in err and "Traceback" not in err
        assert err.rstrip().endswith(f"[{rule}]")  # the rule of spec/FORMAT.md §11
    assert not (tmp_path / "out").exists()


def test_a_target_no_file_can_meet_exits_5(wave_npz, tmp_path, capsys):
    packed = tmp_path / "tiny.tkc"
    assert main(["encode", str(wave_npz), "-o", str(packed), "--bpfv", "0.01"]) == 5
    err = capsys.readouterr().err
    assert err.startswith("tuckercodec: target cannot be met: no file fits 0.01 bpfv")
    assert len(err.splitlines()) == 1 and not packed.exists()


def test_a_bug_exits_70_in_one_line_asking_for_a_report(wave_npz, tmp_path, capsys, monkeypatch):
    """An impossible state found by the encoder's own checks is tuckercodec's bug: exit 70 and
    one line saying so, not "loosen the target", no traceback and no file."""

    def read_back_wrong(*args: Any, **kwargs: Any) -> None:
        raise InternalError("the corrections of frames 0..19 read back differently")

    monkeypatch.setattr(corrections, "check_written", read_back_wrong)
    packed = tmp_path / "bounded.tkc"
    command = ["encode", str(wave_npz), "-o", str(packed), "--max-error", "0.001%"]
    assert main(command) == 70
    err = capsys.readouterr().err
    assert err == (
        "tuckercodec: internal error: the corrections of frames 0..19 read back differently. "
        "This is a bug in tuckercodec: please report it\n"
    )
    assert not packed.exists()


def test_a_missing_optional_package_exits_6_naming_the_extra(
    wave_npz, tmp_path, capsys, monkeypatch
):
    monkeypatch.setitem(sys.modules, "matplotlib", None)  # "import matplotlib" now fails
    monkeypatch.setitem(sys.modules, "matplotlib.pyplot", None)
    assert main(["rd", str(wave_npz), "--plot", str(tmp_path / "rd.png")]) == 6
    err = capsys.readouterr().err
    assert "tuckercodec[plot]" in err and len(err.splitlines()) == 1


def test_encode_usage_errors_exit_2(wave_npz, tmp_path, capsys):
    packed = str(tmp_path / "x.tkc")
    for args in (
        ["--kg", "0.1", "--ranks", "2,2"],
        ["--kg", "-1"],
        ["--ranks", "2"],
        ["--bpfv", "zero"],
    ):
        with pytest.raises(SystemExit) as exit_info:
            main(["encode", str(wave_npz), "-o", packed, *args])
        assert exit_info.value.code == 2
    assert main(["encode", str(wave_npz), "-o", packed, "--ranks", "500,2"]) == 2
    assert "ranks must be" in capsys.readouterr().err
    assert main(["decode", str(wave_npz), "-o", str(tmp_path / "o")]) == 3  # not a compressed file
    assert "not a tuckercodec file" in capsys.readouterr().err


def test_decode_frame_options_and_reference_checks(wave_npz, tmp_path, capsys):
    packed = tmp_path / "wave.tkc"
    assert main(["encode", str(wave_npz), "-o", str(packed), "--kg", "1"]) == 0
    assert (
        main(
            ["decode", str(packed), "-o", str(tmp_path / "last"), "--frames=-1", "--format", "npz"]
        )
        == 0
    )
    out = capsys.readouterr().out
    assert "1 of 20 frames" in out and str(tmp_path / "last.npz") in out  # the path really written
    assert (tmp_path / "last.npz").exists()
    with pytest.raises(SystemExit) as exit_info:
        main(["decode", str(packed), "-o", str(tmp_path / "x"), "--frames", "5:2"])
    assert exit_info.value.code == 2 and "5:2 is empty" in capsys.readouterr().err
    short = tmp_path / "short.npz"
    np.savez(short, V=wave_sequence(5, 8), F=grid_faces(8))
    assert (
        main(["decode", str(packed), "-o", str(tmp_path / "r.npz"), "--reference", str(short)]) == 4
    )
    assert "has 5 frames" in capsys.readouterr().err
    assert not (tmp_path / "r.npz").exists()  # checked before anything was written


def test_eval_names_the_file_at_fault(wave_npz, tmp_path, capsys):
    garbage = tmp_path / "garbage.tkc"
    garbage.write_bytes(b"not a compressed file at all")
    assert main(["eval", str(wave_npz), str(garbage)]) == 3
    err = capsys.readouterr().err
    assert str(garbage) in err and "not a tuckercodec file" in err
    short = tmp_path / "short.npz"
    np.savez(short, V=wave_sequence(5, 8), F=grid_faces(8))
    assert main(["eval", str(wave_npz), str(short)]) == 4
    err = capsys.readouterr().err
    assert str(short) in err and str(wave_npz) in err


# ------------------------------------------------------------------------------------------
# eval's STED and plot, render

PNG = b"\x89PNG\r\n\x1a\n"


@pytest.fixture
def packed(wave_npz, tmp_path):
    path = tmp_path / "wave.tkc"
    assert main(["encode", str(wave_npz), "-o", str(path), "--kg", "1"]) == 0
    return path


def test_eval_reports_sted_with_its_parameters_and_definition(wave_npz, packed, capsys):
    from tuckercodec import load_sequence, read_compressed, sted
    from tuckercodec.measures.perceptual import STED_DEFINITION

    capsys.readouterr()
    assert main(["eval", str(wave_npz), str(packed), "--json"]) == 0
    figures = json.loads(capsys.readouterr().out)
    expected = sted(load_sequence(wave_npz, progress=False), read_compressed(packed).sequence())
    assert figures["sted"] == pytest.approx(expected.to_dict())
    assert figures["sted"]["definition"] == STED_DEFINITION
    assert (figures["sted"]["width"], figures["sted"]["window"]) == (1, 5)
    assert figures["sted"]["value"] > 0

    assert (
        main(
            [
                "eval",
                str(wave_npz),
                str(packed),
                "--json",
                "--sted-width",
                "2",
                "--sted-window",
                "3",
            ]
        )
        == 0
    )
    wider = json.loads(capsys.readouterr().out)["sted"]
    narrower = figures["sted"]
    assert (wider["width"], wider["window"]) == (2, 3) and wider["spatial"] != narrower["spatial"]

    assert main(["eval", str(wave_npz), str(packed)]) == 0
    out = capsys.readouterr().out
    line = next(line for line in out.splitlines() if line.startswith("STED "))
    assert f"{expected.value:.6g}" in line and "width 1, window 5, dt 0.0003, c 9.144e-05" in line
    assert STED_DEFINITION in out
    for bad in ("0", "x"):
        with pytest.raises(SystemExit) as exit_info:
            main(["eval", str(wave_npz), str(packed), "--sted-width", bad])
        assert exit_info.value.code == 2


def test_eval_without_faces_reports_no_sted(tmp_path, capsys):
    cloud = tmp_path / "cloud.npz"
    np.savez(cloud, V=wave_sequence(6, 4), F=np.zeros((0, 3), dtype=np.int32))
    assert main(["eval", str(cloud), str(cloud), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["sted"] is None
    assert main(["eval", str(cloud), str(cloud)]) == 0
    assert "STED not measured" in capsys.readouterr().out


def test_eval_plot_writes_a_png_and_never_overwrites(wave_npz, packed, tmp_path, capsys):
    pytest.importorskip("matplotlib")
    plot = tmp_path / "frames.png"
    assert main(["eval", str(wave_npz), str(packed), "--plot", str(plot)]) == 0
    assert f"wrote {plot}" in capsys.readouterr().out
    assert plot.read_bytes()[:8] == PNG
    before = plot.read_bytes()
    assert main(["eval", str(wave_npz), str(packed), "--plot", str(plot)]) == 1
    err = capsys.readouterr().err
    assert "already exists" in err and "--force" in err and len(err.splitlines()) == 1
    assert plot.read_bytes() == before
    assert main(["eval", str(wave_npz), str(packed), "--plot", str(plot), "--force", "--json"]) == 0
    json.loads(capsys.readouterr().out)  # the JSON stays clean: nothing else on stdout
    assert main(["eval", str(wave_npz), str(packed), "--plot", str(tmp_path / "frames.txt")]) == 2
    assert "must end in .png" in capsys.readouterr().err
    assert not list(tmp_path.glob(".*.tmp"))


def test_render_draws_a_frame_with_and_without_a_reference(wave_npz, packed, tmp_path, capsys):
    pytest.importorskip("matplotlib")
    plain, coloured = tmp_path / "plain.png", tmp_path / "error.png"
    assert main(["render", str(wave_npz), "--frame", "3", "-o", str(plain)]) == 0
    assert "frame 3 of 20, 64 vertices" in capsys.readouterr().out
    assert (
        main(
            ["render", str(packed), "--frame=-1", "-o", str(coloured), "--reference", str(wave_npz)]
        )
        == 0
    )
    out = capsys.readouterr().out
    assert "frame 19 of 20" in out and "vertex error up to" in out
    for path in (plain, coloured):
        assert path.read_bytes()[:8] == PNG
    assert (
        main(["render", "sample", "--frame", "0", "-o", str(tmp_path / "cloth.svg"), "--up", "z"])
        == 0
    )
    assert (tmp_path / "cloth.svg").read_text().lstrip().startswith("<?xml")


def test_render_decodes_only_the_frame_it_draws(packed, tmp_path, monkeypatch):
    pytest.importorskip("matplotlib")
    from tuckercodec import Decoder

    asked = []
    original = Decoder.positions

    def positions(self, frames=None):
        result = original(self, frames)
        asked.append(len(result))
        return result

    monkeypatch.setattr(Decoder, "positions", positions)
    assert main(["render", str(packed), "--frame", "7", "-o", str(tmp_path / "one.png")]) == 0
    assert asked == [1]


def test_render_errors_are_one_line_and_nothing_is_overwritten(wave_npz, packed, tmp_path, capsys):
    pytest.importorskip("matplotlib")
    image = tmp_path / "img.png"
    image.write_bytes(b"precious")
    capsys.readouterr()
    for source in (wave_npz, packed):
        assert main(["render", str(source), "--frame", "20", "-o", str(tmp_path / "new.png")]) == 2
        err = capsys.readouterr().err
        assert f"frame 20 does not exist: {source} has 20 frames (0..19)" in err
        assert len(err.splitlines()) == 1 and "Traceback" not in err
    assert main(["render", str(packed), "--frame=-21", "-o", str(tmp_path / "new.png")]) == 2
    assert "frame -21 does not exist" in capsys.readouterr().err
    assert not (tmp_path / "new.png").exists()

    assert main(["render", str(packed), "--frame", "2", "-o", str(image)]) == 1
    assert "already exists" in capsys.readouterr().err
    assert image.read_bytes() == b"precious"
    assert main(["render", str(packed), "--frame", "2", "-o", str(image), "--force"]) == 0
    assert image.read_bytes()[:8] == PNG

    short = tmp_path / "short.npz"
    np.savez(short, V=wave_sequence(5, 8), F=grid_faces(8))
    assert (
        main(
            [
                "render",
                str(packed),
                "--frame",
                "2",
                "-o",
                str(tmp_path / "r.png"),
                "--reference",
                str(short),
            ]
        )
        == 4
    )
    err = capsys.readouterr().err
    assert str(short) in err and "has 5 frames" in err and len(err.splitlines()) == 1
    # a frame beyond the short reference: still the mismatch, not a missing frame
    assert (
        main(
            [
                "render",
                str(packed),
                "--frame",
                "10",
                "-o",
                str(tmp_path / "r.png"),
                "--reference",
                str(short),
            ]
        )
        == 4
    )
    assert "has 5 frames" in capsys.readouterr().err
    garbage = tmp_path / "garbage.tkc"
    garbage.write_bytes(b"not a compressed file at all")
    assert main(["render", str(garbage), "--frame", "0", "-o", str(tmp_path / "g.png")]) == 3
    assert str(garbage) in capsys.readouterr().err
    assert main(["render", str(packed), "--frame", "0", "-o", str(tmp_path / "r.jpeg")]) == 2
    assert "must end in .png" in capsys.readouterr().err
    assert not any((tmp_path / name).exists() for name in ("r.png", "g.png", "r.jpeg"))
    assert not list(tmp_path.glob(".*.tmp"))


def test_decode_help_names_only_suffixes_it_writes(capsys):
    # it named .vtu, which no format writes: 'decode -o y.vtu' made a folder of OBJ files
    from tuckercodec.io import formats

    with pytest.raises(SystemExit):
        main(["decode", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    listed = text.split("chosen by its suffix (")[1].split(")")[0]
    written = {s for f in formats() if f.write is not None for s in f.suffixes}
    assert set(re.findall(r"\.[a-z0-9]+", listed)) <= written


@pytest.mark.parametrize(
    ("verb", "name", "inside"),
    [
        ("convert", "out.zarr", "vertices/notes.txt"),
        ("decode", "out.zarr", "notes.txt"),
        ("decode", "frames", "notes.txt"),
        ("convert", "frames", "notes/todo.txt"),
        ("convert", "out.pvd", "notes.txt"),  # its frames' folder, out/
    ],
)
def test_force_replaces_only_a_folder_it_wrote(
    verb, name, inside, wave_npz, packed, tmp_path, capsys
):
    """--force once deleted the whole existing folder of a zarr store, or the frames of a folder
    it did not write; now a user's file anywhere inside keeps the folder, with exit 1 naming
    it, and a folder the tool wrote is replaced."""
    if name.endswith(".zarr"):
        pytest.importorskip("zarr")
    source = str(packed) if verb == "decode" else str(wave_npz)
    output = tmp_path / "out" / name
    output.parent.mkdir()
    args = [verb, source, "-o", str(output)] if verb == "decode" else [verb, source, str(output)]
    assert main(args) == 0
    folder = output.with_suffix("") if name.endswith(".pvd") else output
    mine = folder / inside
    mine.parent.mkdir(exist_ok=True)
    mine.write_text("mine")
    capsys.readouterr()
    assert main([*args, "--force"]) == 1
    err = capsys.readouterr().err.strip()
    assert err.startswith(f"tuckercodec: {folder} holds files tuckercodec did not write")
    assert "--force would delete 1 entry" in err and "\n" not in err
    assert mine.read_text() == "mine"
    assert not [p for p in output.parent.iterdir() if p.name.startswith(".")]  # nothing left
    if mine.parent == folder:
        mine.unlink()
    else:
        shutil.rmtree(mine.parent)
    assert main([*args, "--force"]) == 0
    assert not [p for p in output.parent.iterdir() if p.name.startswith(".")]


@pytest.mark.parametrize("name", ["out.zarr", "frames"])
def test_force_refuses_a_folder_the_tool_did_not_write(name, wave_npz, tmp_path, capsys):
    if name.endswith(".zarr"):
        pytest.importorskip("zarr")
    folder = tmp_path / name
    (folder / "src").mkdir(parents=True)
    (folder / "src" / "main.py").write_text("print(1)")
    assert main(["convert", str(wave_npz), str(folder), "--force"]) == 1
    err = capsys.readouterr().err.strip()
    assert err.startswith(f"tuckercodec: {folder} was not written by tuckercodec")
    assert "would delete 1 entry (src/)" in err
    assert (folder / "src" / "main.py").read_text() == "print(1)"


def test_info_escapes_the_files_strings_so_a_terminal_runs_none_of_them(packed, capsys):
    """info printed the file's encoder and error definition raw: a crafted file could send a
    terminal escape sequences (clear the screen, set the title, reorder the line)."""
    from tests.support.compressed import Parts

    parts = Parts(packed.read_bytes())
    hostile = "evil\x1b]0;owned\x07\x1b[2J\u202e\x9b\u2028\\x1b"
    parts.header["encoder"] = hostile
    parts.header["error"] = {**parts.header["error"], "definition": "kg\x1b[31m" + hostile}
    crafted = packed.with_name("crafted.tkc")
    crafted.write_bytes(parts.pack())
    capsys.readouterr()
    assert main(["info", str(crafted)]) == 0
    out = capsys.readouterr().out
    assert not [c for c in out if unicodedata.category(c) in {"Cc", "Cf", "Zl"} and c != "\n"]
    assert r"written by evil\x1b]0;owned\x07\x1b[2J\u202e\x9b\u2028\\x1b" in out
    assert r"(kg\x1b[31mevil" in out
    assert main(["info", str(crafted), "--json"]) == 0
    text = capsys.readouterr().out
    assert text.isascii() and "\x1b" not in text  # JSON escapes them itself
    assert json.loads(text)["encoder"] == hostile
