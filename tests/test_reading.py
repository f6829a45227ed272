"""Opening inputs (tuckercodec/system/reading.py): only regular files are read, so a named pipe
given by mistake is an InputError at once, not a wait for a writer that never comes; the same for a
compressed file, whichever way it is opened."""

from __future__ import annotations

import os
import threading
from collections.abc import Callable
from pathlib import Path

import pytest

import tuckercodec
from tuckercodec import InputError
from tuckercodec.cli import main
from tuckercodec.io import load_sequence
from tuckercodec.io.obj import read_obj


def refused_without_waiting(call: Callable[[], object], pipe: Path) -> BaseException | None:
    """Run ``call``, which reads the named pipe ``pipe``, in a thread: what it raised (None if
    nothing), or fail the test if it is still waiting for a writer after 5 s."""
    outcome: list[BaseException | None] = []

    def run() -> None:
        try:
            call()
            outcome.append(None)
        except BaseException as error:  # handed to the test thread
            outcome.append(error)

    worker = threading.Thread(target=run, daemon=True)
    worker.start()
    worker.join(5)
    if worker.is_alive():  # be the writer it waits for, so that the thread ends, then fail
        with open(pipe, "wb"):
            pass
        pytest.fail(f"reading {pipe.name} waited for a writer")
    return outcome[0]


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="named pipes are POSIX")
@pytest.mark.parametrize("name", ["pipe.obj", "pipe.npz"])
def test_a_named_pipe_is_refused_not_waited_on(tmp_path: Path, name: str) -> None:
    pipe = tmp_path / name
    os.mkfifo(pipe)
    raised = refused_without_waiting(lambda: load_sequence(pipe, progress=False), pipe)
    assert isinstance(raised, InputError) and "regular file" in str(raised), raised
    assert raised.path == str(pipe)
    if name.endswith(".obj"):
        raised = refused_without_waiting(lambda: read_obj(pipe), pipe)
        assert isinstance(raised, InputError) and "regular file" in str(raised), raised


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="named pipes are POSIX")
@pytest.mark.parametrize(
    "open_file",
    [tuckercodec.info, tuckercodec.Decoder, tuckercodec.decode, tuckercodec.read_compressed],
    ids=lambda call: call.__name__,
)
def test_a_compressed_file_that_is_a_pipe_or_a_folder_is_refused(
    tmp_path: Path, open_file: Callable[[Path], object]
) -> None:
    pipe = tmp_path / "pipe.tkc"
    os.mkfifo(pipe)
    raised = refused_without_waiting(lambda: open_file(pipe), pipe)
    assert isinstance(raised, InputError) and "regular file" in str(raised), raised
    assert raised.path == str(pipe)
    with pytest.raises(InputError, match="is a folder, not a tuckercodec file") as folder:
        open_file(tmp_path)
    assert folder.value.path == str(tmp_path)


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="named pipes are POSIX")
def test_the_cli_refuses_a_pipe_as_a_compressed_file_with_exit_4(tmp_path: Path, capsys) -> None:
    pipe = tmp_path / "pipe.tkc"
    os.mkfifo(pipe)
    code = refused_without_waiting(lambda: _exit_code(["info", str(pipe)]), pipe)
    assert isinstance(code, SystemExit) and code.code == 4
    err = capsys.readouterr().err
    assert "bad input" in err and str(pipe) in err and len(err.splitlines()) == 1


def _exit_code(argv: list[str]) -> None:
    """Run the CLI and hand its exit code back as the SystemExit it would end with."""
    raise SystemExit(main(argv))


def test_open_input_names_a_file_that_cannot_be_opened(tmp_path):
    from tuckercodec.system.reading import open_input

    with pytest.raises(InputError, match=r"missing\.pc2: cannot read: No such file"):
        open_input(tmp_path / "missing.pc2", "a PC2 point cache")
    with pytest.raises(InputError, match="is a folder, not a PC2 point cache"):
        open_input(tmp_path, "a PC2 point cache")
