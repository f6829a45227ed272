"""The fuzzer's findings stay fixed, and a short fuzz run on every test run (issue 5, items 2, 5).

- Every saved input (tests/fuzz/corpus, tests/fuzz/regressions, and anything a fuzz run left
  in tests/fuzz/crashes) ends in FormatError or decodes consistently, quickly, in bounded
  memory, without a warning (tools.fuzz's ``check_input`` is the oracle).
- The structural mutator of tools.fuzz, driven by a plain random generator, makes a few
  hundred re-signed variants of the seeds: this part needs no atheris, so it runs everywhere.
- A bounded atheris run (``TKC_FUZZ_SECONDS``, 30 s by default) in a subprocess with a hard
  timeout; skipped, saying why, where atheris is not installed (it has no Windows build).
"""

from __future__ import annotations

import base64
import json
import os
import random
import signal
import subprocess
import sys
import time
import tracemalloc
from pathlib import Path

import pytest

from tools import fuzz as fuzz_tool

ROOT = Path(__file__).resolve().parents[1]

SAVED = fuzz_tool.saved_inputs(fuzz_tool.CORPUS, fuzz_tool.REGRESSIONS, fuzz_tool.CRASHES)
#: What one saved input may cost. The largest, a valid strip of 2**19 vertices, takes about
#: 0.5 s and 100 MiB; the others milliseconds and kilobytes.
INPUT_SECONDS = 5.0
INPUT_PEAK_BYTES = 256 << 20
FUZZ_SECONDS = int(os.environ.get("TKC_FUZZ_SECONDS", "30"))


def _label(path: Path) -> str:
    return f"{path.parent.name}/{path.name}"


def test_the_fuzz_folders_hold_inputs():
    assert any(p.parent == fuzz_tool.CORPUS for p in SAVED), "tests/fuzz/corpus is empty"
    assert any(p.parent == fuzz_tool.REGRESSIONS for p in SAVED), "tests/fuzz/regressions is empty"
    size = sum(p.stat().st_size for p in SAVED if p.parent == fuzz_tool.CORPUS)
    assert size < 512 << 10, f"the committed corpus is {size >> 10} KiB: merge it down"


@pytest.mark.parametrize("path", SAVED, ids=_label)
def test_saved_input(path):
    """FormatError or a consistent decode; a file left in crashes/ fails here until fixed."""
    data = path.read_bytes()
    started = time.perf_counter()
    tracemalloc.start()
    try:
        fuzz_tool.check_input(data)  # raises the crash itself; warnings are errors (pyproject)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    elapsed = time.perf_counter() - started
    assert elapsed < INPUT_SECONDS, f"{_label(path)} took {elapsed:.1f} s"
    assert peak < INPUT_PEAK_BYTES, f"{_label(path)} peaked at {peak >> 20} MiB"


def test_structural_mutations_of_the_seeds():
    """Re-signed structural edits of every seed, without libFuzzer: each ends in FormatError
    or decodes consistently."""
    rng = random.Random(20261123)
    seeds = [p.read_bytes() for p in fuzz_tool.seed_inputs()]
    tried = 0
    for _ in range(400):
        data = rng.choice(seeds)
        for _ in range(rng.randint(1, 3)):  # a few edits on top of each other
            data = fuzz_tool.structural_mutation(data, rng) or data
        fuzz_tool.check_input(data)
        tried += 1
    assert tried == 400


def test_resign_makes_the_checksums_right():
    """A byte-level mutation re-signed is judged on what it changed: a flipped header byte is
    no longer a ChecksumError."""
    import tuckercodec

    data = bytearray((ROOT / "spec" / "vectors" / "v1-wave-triangles.tkc").read_bytes())
    data[40] ^= 0x01  # inside the header
    with pytest.raises(tuckercodec.ChecksumError):
        tuckercodec.decode(bytes(data))
    try:
        tuckercodec.decode(fuzz_tool.resign(bytes(data)))
    except tuckercodec.ChecksumError as error:  # pragma: no cover - the assertion says it
        pytest.fail(f"still a checksum error after resign: {error}")
    except tuckercodec.FormatError:
        pass


def test_importing_the_fuzzer_leaves_tuckercodec_to_its_worker():
    """The worker imports tuckercodec for the first time under atheris' instrumentation (else it
    fuzzes blind to the package's coverage): importing tools.fuzz must not import it."""
    check = "import sys, tools.fuzz; sys.exit('tuckercodec' in sys.modules)"
    assert subprocess.run([sys.executable, "-c", check], cwd=ROOT, check=False).returncode == 0


def test_the_seeds_decode_and_the_hand_made_one_is_as_committed(tmp_path):
    """make_seeds writes valid files (it decodes each); the one built section by section is
    byte-stable, unlike the encoder's, so it must equal the committed seed."""
    written = {path.name: path for path in fuzz_tool.make_seeds(tmp_path)}
    assert set(written) <= {path.name for path in SAVED if path.parent == fuzz_tool.CORPUS}
    name = "seed-one-vertex.tkc"
    assert written[name].read_bytes() == (fuzz_tool.CORPUS / name).read_bytes()


def test_a_short_bounded_fuzz_run(tmp_path):
    """python -m tools.fuzz for FUZZ_SECONDS from the seeds, in its own process group, killed if
    it overruns. Any crash fails the test with its traceback and the input in base64 (to keep
    it: decode it into tests/fuzz/crashes/)."""
    try:
        import atheris  # noqa: F401
    except ImportError:
        pytest.skip(
            "atheris is not installed (it has no Windows build): the bounded fuzz run is skipped; "
            "the saved inputs and structural mutations above still ran"
        )
    crashes, summary_path = tmp_path / "crashes", tmp_path / "summary.json"
    seed = int(os.environ.get("TKC_FUZZ_SEED", str(random.SystemRandom().randrange(1, 2**31))))
    command = [sys.executable, "-m", "tools.fuzz", "--seconds", str(FUZZ_SECONDS)]
    command += ["--seed", str(seed), "--work", str(tmp_path / "work"), "--crashes", str(crashes)]
    command += ["--json", str(summary_path), "--memory-mb", "1024"]
    process = subprocess.Popen(
        command,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        cwd=ROOT,
        start_new_session=True,
    )
    try:
        stdout, stderr = process.communicate(timeout=FUZZ_SECONDS + 90)
    except subprocess.TimeoutExpired:
        os.killpg(process.pid, signal.SIGKILL)  # the driver and its libFuzzer worker
        process.communicate()
        pytest.fail(
            f"python -m tools.fuzz --seconds {FUZZ_SECONDS} (seed {seed}) overran its time and "
            "was killed"
        )
    assert summary_path.exists(), (
        f"no summary (exit {process.returncode}):\n{stdout}\n{stderr[-4000:]}"
    )
    summary = json.loads(summary_path.read_text())
    found = sorted(p for p in crashes.iterdir() if p.suffix != ".txt") if crashes.exists() else []
    report = []
    for path in found:
        notes = path.with_suffix(".txt")
        why = notes.read_text() if notes.exists() else "(no traceback: a hang or out-of-memory)"
        report.append(
            f"--- {path.name} (seed {seed})\n{why}"
            f"\ninput, base64: {base64.b64encode(path.read_bytes()).decode()}"
        )
    assert not found, "the fuzzer found crashes:\n" + "\n".join(report)
    assert summary["inputs_tried"] > 100, summary
