"""The fuzzers' findings stay fixed, and a short fuzz run on every test run: a crafted input
ends in a clear error, never a crash, a hang or a flood of memory.

- Every saved input of every door (tests/fuzz/corpus/<target>, tests/fuzz/regressions/<target>,
  and anything a fuzz run left in tests/fuzz/crashes/<target>) ends in the door's documented
  error or reads consistently, quickly, in bounded memory, without a warning (the target's
  ``check`` in tools.fuzz.targets is the oracle); a seed (``seed-*``) reads without error.
  USD and Alembic inputs go through their isolated child, half a second each.
- Every finding not fixed yet (tests/data/fuzz/<target>/) still reproduces: once fixed, it is
  to move to the regressions.
- The structure-aware mutators, driven by a plain random generator, make variants of the
  seeds: this part needs no atheris, so it runs everywhere.
- A bounded atheris run (``TKC_FUZZ_SECONDS``, 30 s by default) of target ``all`` (every
  in-process door in one process, the first byte of an input choosing) in a subprocess with a
  hard timeout; skipped, saying why, where atheris is not installed (it has no Windows build).
  It must see coverage and reach beyond its seeds: a harness that instruments nothing the doors
  run fails here, not silently.
- The JavaScript decoder on the decoders' inputs and mutations of them, against the Python one.
"""

from __future__ import annotations

import base64
import importlib.util
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
from tools.fuzz.container import decoder_seeds
from tools.fuzz.targets import TARGETS

ROOT = Path(__file__).resolve().parents[1]

SAVED = [
    (name, path)
    for name in TARGETS
    for path in fuzz_tool.saved_inputs(
        *(root / name for root in (fuzz_tool.CORPUS, fuzz_tool.REGRESSIONS, fuzz_tool.CRASHES))
    )
]
#: What one saved input may cost in process. The largest, a valid strip of 2**19 vertices,
#: takes about 0.5 s and 100 MiB (6 s under tracemalloc on a loaded 2-core machine); the others
#: milliseconds and kilobytes. An input read through the isolated child costs a process (about
#: 0.5 s). The time limits only stop a hang: no test may assume how fast a machine runs.
INPUT_SECONDS = 60.0
ISOLATED_SECONDS = 180.0
INPUT_PEAK_BYTES = 256 << 20
FUZZ_SECONDS = int(os.environ.get("TKC_FUZZ_SECONDS", "30"))
WARM: set[str] = set()
#: Variants of its seeds each in-process door's own mutator makes, without libFuzzer.
MUTATIONS = 40
#: Mutations of the decoders' inputs the JavaScript decoder is given besides them.
JS_MUTATIONS = 300


def _label(item: tuple[str, Path]) -> str:
    name, path = item
    return f"{name}/{path.parent.parent.name}/{path.name}"


def _needs(name: str) -> None:
    for module in TARGETS[name].needs:
        if importlib.util.find_spec(module) is None:
            pytest.skip(f"{module} is not installed: the {name} reader cannot run")


def test_the_fuzz_folders_hold_inputs():
    for name in TARGETS:
        assert any(n == name and p.parent.parent == fuzz_tool.CORPUS for n, p in SAVED), (
            f"tests/fuzz/corpus/{name} is empty"
        )
    assert any(p.parent.parent == fuzz_tool.REGRESSIONS for _, p in SAVED), "no regressions"
    size = sum(p.stat().st_size for _, p in SAVED if p.parent.parent == fuzz_tool.CORPUS)
    assert size < 512 << 10, f"the committed corpora are {size >> 10} KiB: merge them down"


@pytest.mark.parametrize("item", SAVED, ids=[_label(item) for item in SAVED])
def test_saved_input(item):
    """The documented error or a consistent read; a file left in crashes/ fails here until
    fixed. A seed is a valid input."""
    name, path = item
    _needs(name)
    target = TARGETS[name]
    data = path.read_bytes()
    if name not in WARM:  # the lazy imports of a door's first input, under tracemalloc, take
        WARM.add(name)  # seconds and megabytes that are not the input's doing
        seeds = [p for n, p in SAVED if n == name and p.name.startswith("seed")]
        target.check(seeds[0].read_bytes())
    started = time.perf_counter()
    tracemalloc.start()
    try:
        outcome = target.check(data)  # raises the crash itself; warnings are errors (pyproject)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    elapsed = time.perf_counter() - started
    limit = ISOLATED_SECONDS if target.isolated else INPUT_SECONDS
    assert elapsed < limit, f"{_label(item)} took {elapsed:.1f} s"
    assert peak < INPUT_PEAK_BYTES, f"{_label(item)} peaked at {peak >> 20} MiB"
    if path.name.startswith("seed-"):
        assert outcome.split("/")[0] == "ok", f"the seed {_label(item)} is refused: {outcome}"


#: Findings not fixed yet (tests/data/fuzz/README.md), by target.
OPEN_FINDINGS = [
    (folder.name, path)
    for folder in sorted((ROOT / "tests" / "data" / "fuzz").glob("*/"))
    if folder.name in TARGETS  # javascript/: a disagreement kept for the record, not a crash
    for path in fuzz_tool.saved_inputs(folder)
]


@pytest.mark.parametrize("item", OPEN_FINDINGS, ids=[f"{n}/{p.name}" for n, p in OPEN_FINDINGS])
def test_an_open_finding_still_reproduces(item):
    """An input the fuzzer found that breaks a door outside the fuzzer, kept until the door is
    fixed: it still fails the door's oracle. Once fixed, this fails, asking for the input to
    become a regression."""
    name, path = item
    _needs(name)
    try:
        outcome = TARGETS[name].check(path.read_bytes())
    except Exception:  # the finding, as recorded
        return
    pytest.fail(
        f"{path.relative_to(ROOT)} now ends in {outcome!r}: fixed. Move it to "
        f"tests/fuzz/regressions/{name}/ and drop its line in tests/data/fuzz/README.md"
    )


def _open_signatures() -> set[str]:
    """The crash names (``crash-<type>-<module>-<line>``) the open findings make today."""
    names = set()
    for name, path in OPEN_FINDINGS:
        if all(importlib.util.find_spec(module) for module in TARGETS[name].needs):
            try:
                TARGETS[name].check(path.read_bytes())
            except Exception as error:
                names.add(f"crash-{fuzz_tool.signature_of(error)}")
    return names


def test_structural_mutations_of_the_seeds():
    """Re-signed structural edits of every decoder seed, without libFuzzer: each ends in
    FormatError or decodes consistently."""
    rng = random.Random(20261123)
    target = TARGETS["decoder"]
    seeds = [p.read_bytes() for n, p in SAVED if n == "decoder" and p.name.startswith("seed")]
    seeds += [p.read_bytes() for p in sorted((ROOT / "spec" / "vectors").glob("*.tkc"))]
    for _ in range(400):
        data = rng.choice(seeds)
        for _ in range(rng.randint(1, 3)):  # a few edits on top of each other
            data = fuzz_tool.structural_mutation(data, rng) or data
        target.check(data)


def _flip(data: bytes, max_size: int) -> bytes:
    """A stand-in for libFuzzer's byte mutation: one byte changed, cut or repeated."""
    rng = random.Random(data)
    out = bytearray(data or b"\0")
    at = rng.randrange(len(out))
    what = rng.randrange(3)
    if what == 0:
        out[at] = rng.randrange(256)
    elif what == 1:
        del out[at:]
    else:
        out[at:at] = out[at : at + 8]
    return bytes(out[:max_size])


@pytest.mark.parametrize("name", [n for n, t in TARGETS.items() if not t.isolated])
def test_structure_aware_mutations(name, monkeypatch):
    """Each in-process door's own mutator (the readers' bundle, zip, GLB, JSON, XML and number
    edits; FACE's params and streams; the .tkc edits), MUTATIONS variants of its seeds:
    each ends in the documented error or a consistent read."""
    _needs(name)
    from tools.fuzz import targets

    monkeypatch.setattr(targets, "_atheris_mutate", _flip)
    target = TARGETS[name]
    seeds = [p.read_bytes() for n, p in SAVED if n == name and p.name.startswith("seed")]
    rng = random.Random(f"{name}-20261127")
    for _ in range(MUTATIONS):
        data = rng.choice(seeds)
        for _ in range(rng.randint(1, 3)):
            if name in ("decoder", "segmented"):  # the .tkc mutator without libFuzzer's part
                data = fuzz_tool.structural_mutation(data, rng) or data
            elif name == "zarr-chunk":
                data = data[:1] + (fuzz_tool.structural_mutation(data[1:], rng) or data[1:])
            else:
                data = target.mutate(data, 1 << 16, rng.randrange(2**31))
        target.check(data)


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
    check = "import sys, tools.fuzz.driver, tools.fuzz.javascript, tools.fuzz.worker; "
    check += "sys.exit('tuckercodec' in sys.modules)"
    assert subprocess.run([sys.executable, "-c", check], cwd=ROOT, check=False).returncode == 0


def test_the_hand_made_decoder_seed_is_as_committed():
    """The seed built section by section is byte-stable, unlike the encoder's, so it must equal
    the committed one."""
    name = "seed-one-vertex.tkc"
    assert decoder_seeds()[name] == (fuzz_tool.CORPUS / "decoder" / name).read_bytes()


def test_a_short_bounded_fuzz_run(tmp_path):
    """python -m tools.fuzz --target all for FUZZ_SECONDS from every in-process door's seeds, in
    its own process group, killed if it overruns. Any crash fails the test with its traceback
    and the input in base64 (to keep it: decode it into tests/fuzz/crashes/<target>/, without
    the first byte, which chose the door)."""
    try:
        import atheris  # noqa: F401
    except ImportError:
        pytest.skip(
            "atheris is not installed (it has no Windows build): the bounded fuzz run is skipped; "
            "the saved inputs and mutations above still ran"
        )
    for name in TARGETS["decoder"].needs + fuzz_tool.target_named("all").needs:
        if importlib.util.find_spec(name) is None:
            pytest.skip(f"{name} is not installed: the bounded run needs every in-process door")
    crashes, summary_path = tmp_path / "crashes", tmp_path / "summary.json"
    seed = int(os.environ.get("TKC_FUZZ_SEED", str(random.SystemRandom().randrange(1, 2**31))))
    command = [sys.executable, "-m", "tools.fuzz", "--target", "all"]
    command += ["--seconds", str(FUZZ_SECONDS), "--seed", str(seed)]
    command += ["--work", str(tmp_path / "work"), "--crashes", str(crashes)]
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
        stdout, stderr = process.communicate(timeout=FUZZ_SECONDS + 180)
    except subprocess.TimeoutExpired:
        os.killpg(process.pid, signal.SIGKILL)  # the driver and its libFuzzer worker
        process.communicate()
        pytest.fail(
            f"python -m tools.fuzz --target all --seconds {FUZZ_SECONDS} (seed {seed}) overran "
            "its time and was killed"
        )
    assert summary_path.exists(), (
        f"no summary (exit {process.returncode}):\n{stdout}\n{stderr[-4000:]}"
    )
    summary = json.loads(summary_path.read_text())
    folder = crashes / "all"
    found = sorted(p for p in folder.iterdir() if p.suffix != ".txt") if folder.exists() else []
    known = _open_signatures()  # recorded, another's to fix: not this run's failure
    found = [p for p in found if p.name.rsplit("-", 1)[0] not in known]
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
    # not blind: libFuzzer saw the seeds' coverage, and the run reached beyond it
    coverage = summary["coverage"]
    assert coverage["start"] and coverage["start"]["cov"] > 1000, coverage
    assert coverage["end"]["ft"] > coverage["start"]["ft"], coverage
    assert coverage["new_units_added"] > 0, coverage
    assert not summary["failures"], summary["failures"]
    # the driver exits 1 on any crash, a known one too
    assert process.returncode == 0 or summary["new_crashes"], stderr[-4000:]


#: libFuzzer's output when the worker instrumented nothing the target runs (as it did once the
#: package imported lazily): no "cov:" at all, a corpus of one input.
BLIND = """INFO: seed corpus: files: 118 min: 1b max: 20188b total: 227831b rss: 69Mb
#119\tINITED exec/s: 0 rss: 86Mb
#32768\tpulse  corp: 1/1b lim: 8192 exec/s: 16384 rss: 86Mb
#274764\tDONE   corp: 1/1b lim: 8192 exec/s: 18317 rss: 86Mb
Done 274764 runs in 15 second(s)
stat::number_of_executed_units: 274764
stat::new_units_added:          0
"""
SEEING = """#119\tINITED cov: 1010 ft: 1728 corp: 96/106Kb exec/s: 0 rss: 88Mb
#4096\tpulse  cov: 1012 ft: 1801 corp: 123/136Kb lim: 8192 exec/s: 1365 rss: 92Mb
#31222\tDONE   cov: 1024 ft: 1866 corp: 150/189Kb lim: 8192 exec/s: 1040 rss: 117Mb
stat::new_units_added:          414
"""
STUCK = """#119\tINITED cov: 1010 ft: 1728 corp: 96/106Kb exec/s: 0 rss: 88Mb
#31222\tDONE   cov: 1010 ft: 1728 corp: 96/106Kb lim: 8192 exec/s: 1040 rss: 117Mb
stat::new_units_added:          0
"""


def test_a_blind_or_stuck_run_fails():
    """The driver's judgement of libFuzzer's output: a run without coverage (the harness
    instruments nothing), a run whose corpus never grows past its seeds, and one where a module
    was imported after the instrumentation each fail, saying so; a growing run passes, its
    coverage read from the first INITED and the last line."""
    from tools.fuzz.driver import judge_coverage

    coverage, failures = judge_coverage([SEEING], [], expect_growth=True)
    assert not failures
    assert coverage["start"] == {"cov": 1010, "ft": 1728, "corpus": 96}
    assert coverage["end"] == {"cov": 1024, "ft": 1866, "corpus": 150}
    assert coverage["new_units_added"] == 414
    _, failures = judge_coverage([BLIND], [], expect_growth=True)
    assert len(failures) == 1 and "blind" in failures[0]
    _, failures = judge_coverage([STUCK], [], expect_growth=True)
    assert len(failures) == 1 and "did not grow" in failures[0]
    assert not judge_coverage([STUCK], [], expect_growth=False)[1]
    _, failures = judge_coverage([SEEING], ["tuckercodec.io.obj"], expect_growth=True)
    assert len(failures) == 1 and "tuckercodec.io.obj" in failures[0]


@pytest.mark.parametrize("name", [*TARGETS, "all"])
def test_every_target_names_modules_that_exist(name):
    """The modules a target's worker instruments import (modules move: a name that no longer
    imports would leave its code out of the coverage), and they hold the code its door runs."""
    import importlib

    target = fuzz_tool.target_named(name)
    assert target.modules, f"{name} instruments no module"
    for module in target.modules:
        importlib.import_module(module)
    door = (
        "tuckercodec.io"
        if name not in ("decoder", "segmented", "face", "zarr-chunk", "all")
        else "tuckercodec.decoder"
    )
    assert door in target.modules


def test_the_javascript_decoder_on_the_fuzz_inputs():
    """The JavaScript decoder on the decoders' committed fuzz inputs, the vectors and a few
    hundred mutations of them (tools.fuzz.javascript): it never throws anything but a
    TkcError, never hangs, and accepts exactly the files the Python decoder accepts."""
    from tests.support.js_decoder import node
    from tools.fuzz.javascript import js_replay

    node()  # skips, saying why, without node 18 or newer
    summary = js_replay([], JS_MUTATIONS, 20261204)
    assert not summary["failures"], summary["failures"]
    assert summary["both_accept"] > 10 and summary["both_refuse"] > 100, summary
