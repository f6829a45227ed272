"""The JavaScript decoder (``tuckercodec/web/tkc/``) fuzzed on the Python fuzzer's inputs.

libFuzzer cannot see inside node, so the JavaScript decoder is not fuzzed with coverage of its
own: it is given the inputs the coverage-guided runs of the ``decoder`` and ``segmented``
targets kept (each one reaching a part of the Python decoder no other reaches, and so, the
format being one, most often a part of the JavaScript one), the conformance vectors, and
optionally structural mutations of them (``--js-mutations``). ``js_replay.mjs`` decodes each in
one node process (faces, names, every frame); the oracle is the Python decoder's whole
``decode`` on the same bytes:

* node must end every file in a ``TkcError`` or a decode: anything else it throws is a crash;
* the two decoders must agree on accepting or refusing each file, with one exception the spec
  documents (§6.1 step 3): libzstd, under the Python decoder, decodes some Zstandard frames
  whose entropy-coded streams do not end where RFC 8878 says, which fzstd, under the
  JavaScript one, refuses. Such a frame breaks R29; a file the Python decoder accepts and the
  JavaScript one refuses with fzstd's "corrupt" R29 is counted apart (``zstd_leniency``), not
  failed. (This is judged from fzstd's message, not proven frame by frame.)
* the rule each refusal names (spec/FORMAT.md §11) is compared and counted, not required to
  agree: both decoders check in §5's order, but a file that breaks two rules of one step may
  be refused for either.

    python -m tools.fuzz --js-replay /tmp/fuzzwork/decoder /tmp/fuzzwork/segmented
    python -m tools.fuzz --js-replay --js-mutations 5000       # the committed inputs, mutated
"""

from __future__ import annotations

import json
import random
import shutil
import subprocess
import tempfile
import time
from pathlib import Path
from typing import Any

from .container import resign, structural_mutation
from .paths import CORPUS, CRASHES, REGRESSIONS, VECTORS, saved_inputs

SCRIPT = Path(__file__).with_name("js_replay.mjs")
#: The targets whose inputs are .tkc files.
TKC_TARGETS = ("decoder", "segmented")
#: What node may take per file, on top of its start: a hang beyond that is a finding.
SECONDS_PER_FILE = 2.0


def default_inputs() -> list[Path]:
    """The committed .tkc inputs: the two decoders' corpora, regressions and crashes, and the
    conformance vectors (every version, 1.0 to 1.4)."""
    folders = [root / name for root in (CORPUS, REGRESSIONS, CRASHES) for name in TKC_TARGETS]
    return saved_inputs(*folders) + sorted(VECTORS.glob("*.tkc"))


def expand(paths: list[Path]) -> list[Path]:
    """Files as given, folders as the inputs they hold."""
    out: list[Path] = []
    for path in paths:
        out += saved_inputs(path) if path.is_dir() else [path]
    return out


def python_outcome(data: bytes) -> dict[str, Any]:
    """The Python decoder's verdict on a whole decode (faces, names, every frame)."""
    import warnings

    import tuckercodec as tc

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # a warning is the Python fuzzer's finding
            tc.decode(data)
    except tc.FormatError as error:
        return {"accepted": False, "rule": error.rule, "kind": type(error).__name__}
    except Exception as error:  # the Python fuzzer's finding; here, no verdict to compare
        return {"crashed": True, "name": type(error).__name__, "message": str(error)[:200]}
    return {"accepted": True}


def node_outcomes(paths: list[Path]) -> tuple[dict[str, dict[str, Any]], str | None]:
    """Each file's outcome in node, by path; and what went wrong with node itself (a hang, a
    crash of the process), naming the file it was on, or None."""
    executable = shutil.which("node")
    if executable is None:
        raise RuntimeError("node is not on PATH: the JavaScript decoder cannot run")
    with tempfile.NamedTemporaryFile("w", suffix=".txt", delete=False) as listing:
        listing.write("".join(f"{p.resolve()}\n" for p in paths))
    limit = 60 + SECONDS_PER_FILE * len(paths)
    try:
        done = subprocess.run(
            [executable, str(SCRIPT), listing.name],
            capture_output=True,
            text=True,
            timeout=limit,
            check=False,
        )
        stdout, problem = done.stdout, None
        if done.returncode:
            problem = f"node exited {done.returncode}: {done.stderr[-2000:]}"
    except subprocess.TimeoutExpired as expired:
        raw = expired.stdout or ""
        stdout = raw.decode(errors="replace") if isinstance(raw, bytes) else raw
        problem = f"node overran {limit:.0f} s"
    finally:
        Path(listing.name).unlink()
    outcomes = {}
    for line in stdout.splitlines():
        with_path = json.loads(line)
        outcomes[with_path.pop("path")] = with_path
    if problem and len(outcomes) < len(paths):
        problem += f" on {paths[len(outcomes)]}"
    return outcomes, problem


def mutations(paths: list[Path], count: int, seed: int, folder: Path) -> list[Path]:
    """``count`` variants of the given files: a few of the .tkc mutator's structural edits
    (re-signed) and byte edits, written to ``folder``."""
    rng = random.Random(seed)
    originals = [p.read_bytes() for p in paths]
    out = []
    for index in range(count):
        data = rng.choice(originals)
        for _ in range(rng.randint(1, 3)):
            if rng.random() < 0.7:
                data = structural_mutation(data, rng) or data
            elif data:
                edited = bytearray(data)
                edited[rng.randrange(len(edited))] = rng.randrange(256)
                data = resign(bytes(edited)) if rng.random() < 0.8 else bytes(edited)
        path = folder / f"mutation-{index:06d}.tkc"
        path.write_bytes(data)
        out.append(path)
    return out


def compare(paths: list[Path]) -> dict[str, Any]:
    """Both decoders on every file: the counts, and every crash and disagreement."""
    started = time.monotonic()
    js, problem = node_outcomes(paths)
    summary: dict[str, Any] = {"files": len(paths), "both_accept": 0, "both_refuse": 0}
    summary.update(same_rule=0, other_rule=[], disagree=[], js_crashes=[], python_crashes=[])
    summary["zstd_leniency"] = []
    for path in paths:
        mine = python_outcome(path.read_bytes())
        theirs = js.get(str(path.resolve()))
        if theirs is None:
            continue  # node stopped before it: ``problem`` names the file
        if theirs.get("crashed"):
            summary["js_crashes"].append({"path": str(path), **theirs})
        elif mine.get("crashed"):
            summary["python_crashes"].append({"path": str(path), **mine})
        elif mine["accepted"] and _zstd_leniency(theirs):
            summary["zstd_leniency"].append(str(path))
        elif mine["accepted"] != theirs["accepted"]:
            summary["disagree"].append({"path": str(path), "python": mine, "javascript": theirs})
        elif mine["accepted"]:
            summary["both_accept"] += 1
        else:
            summary["both_refuse"] += 1
            if mine["rule"] == theirs["rule"]:
                summary["same_rule"] += 1
            else:
                summary["other_rule"].append(
                    {"path": str(path), "python": mine["rule"], "javascript": theirs["rule"]}
                )
    summary["node_problem"] = problem
    summary["seconds"] = round(time.monotonic() - started, 1)
    return summary


def _zstd_leniency(outcome: dict[str, Any]) -> bool:
    """A refusal of fzstd's for a frame it finds corrupt (R29), which libzstd may decode."""
    return outcome.get("rule") == "R29-zstd-content-size" and "corrupt" in outcome.get(
        "message", ""
    )


def failures_of(summary: dict[str, Any]) -> list[str]:
    """What fails a replay: node crashing, hanging or dying, the decoders disagreeing."""
    out = [f"node threw {c['name']}: {c['message']} on {c['path']}" for c in summary["js_crashes"]]
    out += [
        f"{d['path']}: Python {_verdict(d['python'])}, JavaScript {_verdict(d['javascript'])}"
        for d in summary["disagree"]
    ]
    if summary["node_problem"]:
        out.append(summary["node_problem"])
    return out


def _verdict(outcome: dict[str, Any]) -> str:
    return "accepts" if outcome["accepted"] else f"refuses ({outcome['rule']})"


def js_replay(paths: list[Path], count: int, seed: int) -> dict[str, Any]:
    """The replay of ``paths`` (default: :func:`default_inputs`), and ``count`` mutations of
    them; the summary with its ``failures``."""
    given = expand(paths) if paths else default_inputs()
    with tempfile.TemporaryDirectory(prefix="tkc-fuzz-js-") as scratch:
        extra = mutations(given, count, seed, Path(scratch)) if count else []
        summary = compare(given + extra)
        summary["mutations"] = len(extra)
        summary["failures"] = failures_of(summary)
        for item in summary["disagree"] + summary["js_crashes"]:
            if item["path"].startswith(scratch):  # keep the input: the folder goes
                item["base64"] = _base64(Path(item["path"]).read_bytes())
    pairs: dict[str, int] = {}
    for item in summary["other_rule"]:
        pair = f"Python {item['python']}, JavaScript {item['javascript']}"
        pairs[pair] = pairs.get(pair, 0) + 1
    summary["other_rule_pairs"] = dict(sorted(pairs.items(), key=lambda kv: -kv[1]))
    summary["zstd_leniency_count"] = len(summary["zstd_leniency"])
    summary["zstd_leniency"] = summary["zstd_leniency"][:20]
    summary["other_rule_count"] = len(summary["other_rule"])
    summary["other_rule"] = summary["other_rule"][:20]
    return summary


def _base64(data: bytes) -> str:
    import base64

    return base64.b64encode(data).decode()
