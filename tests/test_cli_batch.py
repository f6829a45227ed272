"""The batch verb: many inputs encoded the same way, each into OUTDIR/<name>.tkc, in this
process or on Dask workers (--jobs); the same bytes wherever they are encoded; a failing input
reported in one line while the others are written; every output checked before any work."""

from __future__ import annotations

import io
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import tuckercodec
from tests.support.inputs import write_cube_frames
from tests.support.sequences import grid_faces, wave_sequence
from tuckercodec.cli import batch, main
from tuckercodec.cli.batch import EXIT_SOME_FAILED, output_name
from tuckercodec.io.samples import sample_path
from tuckercodec.system.parallel import DaskExecutor, open_executor

#: One BLAS thread, as each Dask worker has (tuckercodec.system.parallel.WORKER_ENVIRONMENT): the
#: encoder's recorded KG errors (header floats) change in their last digits with the thread
#: count, the rest of the file does not.
ONE_THREAD = {"OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1"}


@pytest.fixture
def wave_inputs(tmp_path) -> list[Path]:
    """Two small sequences that encode in milliseconds."""
    folder = tmp_path / "in"
    folder.mkdir()
    paths = [folder / "wave.npz", folder / "wave2.npz"]
    for seed, path in enumerate(paths):
        np.savez(path, V=wave_sequence(12, 6, seed=seed), F=grid_faces(6))
    return paths


def _bad(folder: Path) -> Path:
    path = folder / "bad.npz"
    path.write_bytes(b"not a zip archive")
    return path


def _outputs(folder: Path) -> dict[str, bytes]:
    return {path.name: path.read_bytes() for path in sorted(folder.glob("*.tkc"))}


def _error_lines(err: str) -> list[str]:
    return [line for line in err.splitlines() if line.startswith("tuckercodec: ")]


def test_the_same_bytes_in_process_and_on_one_or_two_workers(tmp_path, capfd):
    pytest.importorskip("distributed", reason="dask.distributed is not installed (extra [dask])")
    folder = tmp_path / "in"
    folder.mkdir()
    shutil.copy(sample_path(), folder / "cloth.npz")
    cloth = tuckercodec.load_sequence(sample_path(), progress=False)
    np.savez(folder / "cloth-20.npz", V=cloth.vertices[:20], F=cloth.faces)
    write_cube_frames(folder / "cube", 6)
    inputs = [str(folder / name) for name in ("cloth.npz", "cloth-20.npz", "cube")]
    inputs.append(str(_bad(folder)))
    common = ["--kg", "0.5"]

    # in process, in a Python of its own with one BLAS thread
    command = [sys.executable, "-m", "tuckercodec", "batch", *inputs, *common]
    in_process = subprocess.run(
        [*command, "-o", str(tmp_path / "here")],
        capture_output=True,
        text=True,
        env={**os.environ, **ONE_THREAD},
        check=False,
        timeout=600,
    )
    assert in_process.returncode == EXIT_SOME_FAILED, in_process.stderr
    lines = {"in process": _error_lines(in_process.stderr)}
    for jobs in ("1", "2"):
        out = tmp_path / f"jobs{jobs}"
        capfd.readouterr()
        assert main(["batch", *inputs, "-o", str(out), "--jobs", jobs, *common]) == 7
        lines[f"jobs {jobs}"] = _error_lines(capfd.readouterr().err)

    written = _outputs(tmp_path / "here")
    assert sorted(written) == ["cloth-20.tkc", "cloth.tkc", "cube.tkc"]
    assert _outputs(tmp_path / "jobs1") == written
    assert _outputs(tmp_path / "jobs2") == written
    for name in written:
        kg = tuckercodec.info(tmp_path / "here" / name).kg
        assert kg is not None and kg <= 0.5
    assert lines["jobs 1"] == lines["jobs 2"] == lines["in process"]
    assert len(lines["in process"]) == 1 and "bad.npz" in lines["in process"][0]


def test_a_running_cluster_reads_the_inputs_by_their_absolute_paths(
    wave_inputs, tmp_path, monkeypatch, capsys
):
    pytest.importorskip("distributed", reason="dask.distributed is not installed (extra [dask])")
    with open_executor(1) as running:  # its worker keeps the working folder it started in
        monkeypatch.chdir(tmp_path)
        assert isinstance(running, DaskExecutor) and running.cluster is not None
        address = running.cluster.scheduler_address
        inputs = [str(path.relative_to(tmp_path)) for path in wave_inputs]
        assert main(["batch", *inputs, "sample", "-o", "out", "--scheduler", address]) == 0
    assert sorted(_outputs(tmp_path / "out")) == ["sample.tkc", "wave.tkc", "wave2.tkc"]
    assert "3 of 3 written to out" in capsys.readouterr().out


def test_without_dask_jobs_is_one_line_naming_the_extra(wave_inputs, tmp_path, capsys, monkeypatch):
    monkeypatch.setitem(sys.modules, "distributed", None)  # as if not installed
    assert main(["batch", str(wave_inputs[0]), "-o", str(tmp_path / "out"), "--jobs", "2"]) == 6
    stdout, stderr = capsys.readouterr()
    assert stdout == ""
    assert stderr.count("\n") == 1 and "pip install 'tuckercodec[dask]'" in stderr


def test_a_failing_input_is_reported_and_the_others_are_written(wave_inputs, tmp_path, capsys):
    folder = wave_inputs[0].parent
    bad, missing = _bad(folder), folder / "missing.npz"
    inputs = [str(wave_inputs[0]), str(bad), str(missing), str(wave_inputs[1])]
    out = tmp_path / "out"
    assert main(["batch", *inputs, "-o", str(out), "--ranks", "4,5"]) == EXIT_SOME_FAILED
    stdout, stderr = capsys.readouterr()
    assert sorted(_outputs(out)) == ["wave.tkc", "wave2.tkc"]
    assert tuckercodec.info(out / "wave2.tkc").ranks == (4, 5)
    errors = _error_lines(stderr)
    assert len(errors) == 2, stderr
    assert errors[0].startswith(f"tuckercodec: bad input: {bad}: ")
    assert str(missing) in errors[1]
    assert "Traceback" not in stderr
    # not a terminal: a line per finished input, then the summary
    assert f"[1/4] {wave_inputs[0]} -> {out / 'wave.tkc'}: 12 frames, 36 vertices" in stdout
    assert f"[2/4] {bad}: failed" in stdout
    rows = {line.split()[0]: line for line in stdout.splitlines() if line.startswith(str(folder))}
    assert rows[str(wave_inputs[1])].split()[1:5] == ["12", "36", "(4,", "3,"]
    assert rows[str(wave_inputs[1])].endswith("ok")
    assert rows[str(bad)].endswith(errors[0].removeprefix("tuckercodec: "))
    assert "KG: KG (Karni-Gotsman 2004)" in stdout
    assert f"2 of 4 written to {out}, 2 failed" in stdout


def test_a_bug_in_one_task_shows_its_traceback_and_the_rest_go_on(
    wave_inputs, tmp_path, capsys, monkeypatch
):
    encode = batch.encode_job

    def buggy(job):
        if job.source.endswith("wave.npz"):
            raise TypeError("an encoder bug")
        return encode(job)

    monkeypatch.setattr(batch, "encode_job", buggy)
    out = tmp_path / "out"
    assert main(["batch", *map(str, wave_inputs), "-o", str(out)]) == EXIT_SOME_FAILED
    stderr = capsys.readouterr().err
    assert "Traceback" in stderr and "an encoder bug" in stderr
    assert "tuckercodec: internal error: TypeError: an encoder bug" in stderr
    assert sorted(_outputs(out)) == ["wave2.tkc"]


def test_ctrl_c_keeps_what_was_written_and_says_what_was_not_run(
    wave_inputs, tmp_path, capsys, monkeypatch
):
    encode = batch.encode_job

    def interrupted(job):
        if job.source.endswith("wave2.npz"):
            raise KeyboardInterrupt
        return encode(job)

    monkeypatch.setattr(batch, "encode_job", interrupted)
    out = tmp_path / "out"
    assert main(["batch", *map(str, wave_inputs), "-o", str(out)]) == 130
    stdout, stderr = capsys.readouterr()
    assert sorted(_outputs(out)) == ["wave.tkc"]
    assert stdout.splitlines()[-3].endswith("not run (interrupted)")
    assert f"1 of 2 written to {out}, 1 not run" in stdout
    assert stderr == "tuckercodec: interrupted\n"


def test_two_inputs_with_one_output_name_are_a_usage_error(tmp_path, capsys):
    for folder in ("a", "b"):
        (tmp_path / folder).mkdir()
        np.savez(tmp_path / folder / "x.npz", V=wave_sequence(4, 4), F=grid_faces(4))
    out = tmp_path / "out"
    first, second = tmp_path / "a" / "x.npz", tmp_path / "b" / "x.npz"
    assert main(["batch", str(first), str(second), "-o", str(out)]) == 2
    stderr = capsys.readouterr().err
    assert stderr == (
        f"tuckercodec: {first} and {second} would both be written to {out / 'x.tkc'}: encode "
        "them in separate batches, or rename one\n"
    )
    assert not out.exists()  # nothing was done
    assert main(["batch", str(first), str(first), "-o", str(out)]) == 2


def test_existing_outputs_are_refused_before_any_work_unless_forced(wave_inputs, tmp_path, capsys):
    out = tmp_path / "out"
    out.mkdir()
    (out / "wave2.tkc").write_bytes(b"keep me")
    args = ["batch", *map(str, wave_inputs), "-o", str(out)]
    assert main(args) == 1
    assert capsys.readouterr().err == (
        f"tuckercodec: {out / 'wave2.tkc'} already exists (pass --force to replace outputs)\n"
    )
    assert _outputs(out) == {"wave2.tkc": b"keep me"}  # wave.tkc was not written either
    assert main([*args, "--force"]) == 0
    assert tuckercodec.info(out / "wave2.tkc").frames == 12
    (out / "wave.tkc").write_bytes(b"")
    assert main(args) == 1
    assert "(and 1 more)" in capsys.readouterr().err


def test_the_output_folder_is_made_but_must_be_a_folder(wave_inputs, tmp_path, capsys):
    out = tmp_path / "deep" / "out"
    assert main(["batch", str(wave_inputs[0]), "-o", str(out)]) == 0
    assert sorted(_outputs(out)) == ["wave.tkc"]
    capsys.readouterr()
    not_folder = tmp_path / "file"
    not_folder.write_text("")
    assert main(["batch", str(wave_inputs[0]), "-o", str(not_folder)]) == 2
    assert "names a folder" in capsys.readouterr().err


def test_jobs_and_scheduler_are_one_or_the_other(wave_inputs, tmp_path, capsys):
    with pytest.raises(SystemExit):
        main(["batch", str(wave_inputs[0]), "-o", str(tmp_path), "--jobs", "2", "--scheduler", "x"])
    assert "not allowed with argument" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(["batch", str(wave_inputs[0]), "-o", str(tmp_path), "--jobs", "0"])


@pytest.mark.parametrize(
    ("source", "name"),
    [
        ("sample", "sample"),
        ("shots/cloth.npz", "cloth"),
        ("shots/cloth.take2.npz", "cloth.take2"),
        ("shots/run/", "run"),
        ("shots/run.v2", "run.v2"),  # a folder: no format's suffix to drop
        ("shots/run/*.obj", "run"),
        ("shots/run/f[0-9]*.obj", "run"),
        ("shots/take.abc", "take"),
        ("shots/mesh.OBJ", "mesh"),
    ],
)
def test_output_names(source, name):
    assert output_name(source) == name


def test_the_live_line_on_a_terminal(capsys):
    class Terminal(io.StringIO):
        def isatty(self) -> bool:
            return True

    terminal = Terminal()
    display = batch._Display(2, terminal)
    display.start("2 at a time")
    row = batch._Row("a.npz", Path("out/a.tkc"))
    display.failed(row, tuckercodec.InputError("broken", path="a.npz"))
    display.finished(row)
    display.close()
    text = terminal.getvalue()
    assert "\r\x1b[Kbatch: 0/2 done, 2 at a time" in text
    assert "\r\x1b[Kbatch: 1/2 done, 1 failed, 2 at a time" in text
    assert text.endswith("\r\x1b[K")  # the line is cleared for the summary
    assert capsys.readouterr() == ("", "tuckercodec: bad input: a.npz: broken\n")
