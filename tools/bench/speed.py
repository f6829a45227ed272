"""Speed now against a baseline revision of the package, side by side in one run.

Both packages run in fresh child Pythons: this checkout's, and the package as it was at
``--baseline`` (a git revision, default the last commit before the work on speed), extracted with
``git archive`` into a temporary folder first on the child's ``PYTHONPATH``. Every measure runs
as rounds of one child per package, baseline and now (A B B A A B...), so that whatever else
the machine does falls on both alike (the order turns each round: on a loaded machine a run's
place in the round was seen to matter); the first round is a warm-up (it also compiles the
extracted package's bytecode) and is thrown away, and each figure is the median of the
``--repeat`` rounds after it. A child times only the call measured, after its imports and
reading its input. A decode is timed after one untimed call in the same child (lazy imports
paid, as in ``tools.bench codec``, whose figures the speed targets were set against); an encode
and an OBJ folder are the child's first call, as from the command line.

For each sequence (default: every one of ../shared/data present):

1. **Encode** at KG 0.1 and 0.02 (``encode(sequence, target_kg=t)`` on the loaded sequence):
   seconds, the file size and its ratio now/baseline (target: at most 1.01), and the decoded KG
   error of the new file, measured here with ``kg_error``, against the target.
2. **Decode** the KG 0.1 files: ``Decoder(data)`` plus ``frame(0)``, and
   ``Decoder(data).positions()``, from bytes in memory; once with each package decoding the file
   it wrote itself, and once with both decoding the baseline's file (this isolates the
   decoder's changes from the encoder's), where the decoded positions must be bit for bit the
   same.
3. **OBJ folder** (the sequences that are folders of OBJ frames; the first sequence if none
   is): the baseline's KG 0.1 file decoded by ``decode_file(file, folder)``, what
   ``tuckercodec decode FILE.tkc FOLDER`` runs, end to end; every file hashed, and the text must
   be the same from both packages.

With ``--large``, the first frame from disk of a large segmented file: the skinned body of
``tools.generate.sequence`` (100,000 vertices, 1,000 frames, the size of the large-file target),
made once in ``--workdir`` and encoded there once by the baseline's CLI at KG 0.1 in segments of 250
frames (the encoder's default length), so that both packages read the same file. Each child opens
``Decoder(path)`` and decodes frame 0 (timed together, and with the child's ``import
tuckercodec`` added: a package that imports its modules lazily pays them inside the call, so
the target is judged on the sum), then a few later frames (the median reported); the memory
is the whole child process's peak resident set (``ru_maxrss``: the interpreter, imports and
all) after frame 0.

Printed: a table per measure with both packages' seconds and the ratio baseline/now, the
verdicts against the speed targets, the machine, the load average before and after, and the
command. The exit status is 1 if a child failed or the same file decoded to different
positions or text, 0 otherwise (targets missed are reported, not an error).

    python -m tools.bench speed
    python -m tools.bench speed ../shared/data/samba.npz --repeat 5
    python -m tools.bench speed --large --baseline 70b9332
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time
from contextlib import ExitStack
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from tools import common
from tools.bench import arguments
from tools.bench.scale import DEFAULT_WORKDIR, git_package
from tools.generate import sequence as make_sequence
from tuckercodec import Decoder, kg_error
from tuckercodec.internal import sample_path

#: Main before the work on speed.
DEFAULT_BASELINE = "70b9332"
TARGETS = (0.1, 0.02)
#: The KG target of the files decoded, written as OBJ and, with --large, read from disk.
DECODE_TARGET = 0.1
MB = 1e6

# the speed targets: a run's verdicts say whether each is met
ENCODE_SPEEDUP = 3.0
SIZE_RATIO = 1.01
OPEN_SPEEDUP = 3.0  # Decoder(bytes) + frame(0), on samba
OPEN_SEQUENCE = "samba"
POSITIONS_SPEEDUP = 3.0
OBJ_SPEEDUP = 3.0
LARGE_SPEEDUP = 5.0
LARGE_PEAK_BYTES = 160 * MB
LARGE_LATER_SECONDS = 0.020

LARGE_KIND = "body"
LARGE_VERTICES = 100_000
LARGE_FRAMES = 1_000
LARGE_SEGMENT_FRAMES = 250
LARGE_SEED = 1

MARKER = "speed.md"

#: One measure in a child: the JSON job in argv[1], the JSON result on stdout. It runs under
#: either package, so it imports nothing from this checkout but ``tuckercodec``.
_CHILD = r"""
import hashlib, json, os, resource, shutil, sys, time
job = json.loads(sys.argv[1])
start = time.perf_counter()
import tuckercodec as tc
out = {"import": time.perf_counter() - start}
def peak():
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
kind = job["kind"]
if kind == "encode":
    sequence = tc.load_sequence(job["source"], progress=False)
    encode = tc.encode  # a package that imports lazily imports the encoder here, untimed
    start = time.perf_counter()
    data = encode(sequence, target_kg=job["target"])
    out["seconds"] = time.perf_counter() - start
    out["bytes"] = len(data)
    with open(job["output"], "wb") as handle:
        handle.write(data)
elif kind == "decode":
    with open(job["file"], "rb") as handle:
        data = handle.read()
    tc.Decoder(data).frame(0)  # warm-up: lazy imports, caches
    start = time.perf_counter()
    tc.Decoder(data).frame(0)
    out["open_frame"] = time.perf_counter() - start
    start = time.perf_counter()
    positions = tc.Decoder(data).positions()
    out["positions"] = time.perf_counter() - start
    digest = hashlib.sha256(f"{positions.dtype.str}{positions.shape}".encode())
    digest.update(positions.tobytes())
    out["hash"] = digest.hexdigest()
elif kind == "obj":
    from tuckercodec.files import decode_file
    folder = job["folder"]
    shutil.rmtree(folder, ignore_errors=True)
    start = time.perf_counter()
    decode_file(job["file"], folder)
    out["seconds"] = time.perf_counter() - start
    hashes, size = {}, 0
    # the frames' text: a folder the tool writes also holds its manifest, which a baseline
    # older than it does not write
    for name in sorted(n for n in os.listdir(folder) if n.endswith(".obj")):
        with open(os.path.join(folder, name), "rb") as handle:
            text = handle.read()
        hashes[name] = hashlib.sha256(text).hexdigest()
        size += len(text)
    shutil.rmtree(folder)
    out["hashes"], out["bytes"] = hashes, size
elif kind == "large":
    start = time.perf_counter()
    decoder = tc.Decoder(job["file"])
    decoder.frame(0)
    out["first"] = time.perf_counter() - start
    # with the import: a package that imports lazily imports the decoder inside "first"
    out["first_with_import"] = out["import"] + out["first"]
    out["first_peak"] = peak()
    later = []
    for frame in job["frames"]:
        start = time.perf_counter()
        decoder.frame(frame)
        later.append(time.perf_counter() - start)
    out["later"], out["peak"] = later, peak()
else:
    raise SystemExit(f"unknown job {kind}")
print(json.dumps(out))
"""


# ------------------------------------------------------------------------------------------
# the two packages and their children


@dataclass(frozen=True)
class Package:
    """A tuckercodec a child runs: ``folder`` holds it, first on ``PYTHONPATH`` and the child's
    working folder, so nothing else shadows it."""

    label: str
    folder: Path

    def run(self, job: dict[str, Any]) -> dict[str, Any]:
        """One child for ``job``: its JSON result, or ``{"error": ...}``."""
        done = subprocess.run(
            [sys.executable, "-c", _CHILD, json.dumps(job)],
            cwd=self.folder,
            env=common.package_environment(self.folder),
            capture_output=True,
            text=True,
            check=False,
        )
        if done.returncode != 0:
            lines = [line for line in done.stderr.strip().splitlines() if line.strip()]
            return {"error": f"{self.label}: exit {done.returncode}: " + " / ".join(lines[-2:])}
        result: dict[str, Any] = json.loads(done.stdout)
        return result


@dataclass
class Measure:
    """The results of one measure, per contender (a package, or a package on a given file),
    warm-up rounds left out."""

    samples: dict[str, list[dict[str, Any]]] = field(default_factory=dict)
    errors: list[str] = field(default_factory=list)

    def median(self, contender: str, key: str) -> float | None:
        values = [float(s[key]) for s in self.samples.get(contender, [])]
        return statistics.median(values) if values else None

    def last(self, contender: str) -> dict[str, Any]:
        found = self.samples.get(contender) or [{}]
        return found[-1]


def interleaved(
    contenders: list[tuple[str, Package, dict[str, Any]]], repeat: int, warmup: int
) -> Measure:
    """``warmup + repeat`` rounds, each running every contender's job once, the order turned
    by one each round (A B, B A, A B... with two), so that neither always runs first or after
    the same one; a failing contender stops the measure."""
    measure = Measure({name: [] for name, _, _ in contenders})
    for number in range(warmup + repeat):
        turn = number % len(contenders)
        for name, package, job in contenders[turn:] + contenders[:turn]:
            result = package.run(job)
            if "error" in result:
                measure.errors.append(result["error"])
                return measure
            if number >= warmup:
                measure.samples[name].append(result)
    return measure


# ------------------------------------------------------------------------------------------
# the measures


def source_of(sequence: str) -> Path:
    """The file or folder a child loads: ``sample`` is the built-in sample's file."""
    return sample_path() if sequence == common.SAMPLE else Path(sequence).resolve()


def stem_of(sequence: str) -> str:
    return common.SAMPLE if sequence == common.SAMPLE else Path(sequence).name.removesuffix(".npz")


def is_obj_folder(sequence: str) -> bool:
    path = source_of(sequence)
    return path.is_dir() and any(path.glob("*.obj"))


@dataclass
class SequenceResult:
    """Everything measured on one sequence."""

    name: str
    encodes: dict[float, Measure] = field(default_factory=dict)
    files: dict[tuple[float, str], Path] = field(default_factory=dict)  # (target, old|new)
    kg: dict[tuple[float, str], float] = field(default_factory=dict)
    decode: Measure | None = None
    obj: Measure | None = None


def measure_sequence(
    sequence: str, old: Package, new: Package, out: Path, args: argparse.Namespace, obj: bool
) -> SequenceResult:
    """The encodes, decodes and (if ``obj``) the OBJ folder of one sequence."""
    name = stem_of(sequence)
    result = SequenceResult(name)
    source = source_of(sequence)
    for target in TARGETS:
        say(f"{name}: encode at KG {target:g}")
        for label in ("old", "new"):
            result.files[target, label] = out / f"{name}.kg{target:g}.{label}.tkc"
        contenders = [
            (
                label,
                package,
                {
                    "kind": "encode",
                    "source": str(source),
                    "target": target,
                    "output": str(result.files[target, label]),
                },
            )
            for label, package in (("old", old), ("new", new))
        ]
        result.encodes[target] = interleaved(contenders, args.repeat, args.warmup)
    if any(m.errors for m in result.encodes.values()):
        return result
    reference = common.load(source)
    for (target, label), path in result.files.items():
        result.kg[target, label] = kg_error(reference, Decoder(path).positions())
    old_file = str(result.files[DECODE_TARGET, "old"])
    new_file = str(result.files[DECODE_TARGET, "new"])
    say(f"{name}: decode")
    result.decode = interleaved(
        [
            ("old", old, {"kind": "decode", "file": old_file}),
            ("new", new, {"kind": "decode", "file": new_file}),
            ("new on old file", new, {"kind": "decode", "file": old_file}),
        ],
        args.repeat,
        args.warmup,
    )
    if obj:
        say(f"{name}: OBJ folder")
        result.obj = interleaved(
            [
                (label, package, {"kind": "obj", "file": old_file, "folder": str(folder)})
                for label, package, folder in (
                    ("old", old, out / f"{name}.obj-old"),
                    ("new", new, out / f"{name}.obj-new"),
                )
            ],
            args.repeat,
            args.warmup,
        )
    return result


@dataclass
class LargeResult:
    file: Path
    frames: list[int]
    measure: Measure
    made: str


def large_file(workdir: Path, old: Package, revision: str) -> tuple[Path, str]:
    """The large segmented file, written by the baseline's encoder (made now, or found in
    ``workdir`` from an earlier run), and how it came to be."""
    workdir.mkdir(parents=True, exist_ok=True)
    stem = f"{LARGE_KIND}-{LARGE_VERTICES}x{LARGE_FRAMES}-seed{LARGE_SEED}"
    npy = workdir / f"{stem}.npy"
    faces = make_sequence.faces_path(npy)
    path = workdir / f"{stem}.kg{DECODE_TARGET:g}.seg{LARGE_SEGMENT_FRAMES}.{revision}.tkc"
    if path.exists():
        return path, f"found in {workdir}"
    start = time.perf_counter()
    if not (npy.exists() and faces.exists()):
        say(f"making {npy} (kept for later runs)")
        made = make_sequence.make(LARGE_KIND, LARGE_VERTICES, LARGE_FRAMES, LARGE_SEED)
        make_sequence.write(npy, made, force=True)
    say(f"encoding {path.name} with the baseline's encoder (kept for later runs)")
    command = [sys.executable, "-m", "tuckercodec", "encode", str(npy), "-o", str(path)]
    command += ["--kg", f"{DECODE_TARGET:g}", "--faces", str(faces)]
    command += ["--segment-frames", str(LARGE_SEGMENT_FRAMES)]
    subprocess.run(
        command,
        cwd=old.folder,
        env=common.package_environment(old.folder),
        check=True,
        capture_output=True,
    )
    return path, f"made now in {time.perf_counter() - start:.0f} s"


def measure_large(
    args: argparse.Namespace, old: Package, new: Package, revision: str
) -> LargeResult:
    """The first frame and later frames of the large file, a fresh child per run."""
    path, made = large_file(args.workdir, old, revision)
    middle = LARGE_FRAMES // 2
    frames = [1, 2, 3, middle, middle + 1, LARGE_FRAMES - 1]
    say("large file: first frame from disk")
    job = {"kind": "large", "file": str(path), "frames": frames}
    measure = interleaved([("old", old, job), ("new", new, job)], args.repeat, args.warmup)
    return LargeResult(path, frames, measure, made)


# ------------------------------------------------------------------------------------------
# the tables


def ratio(old: float | None, new: float | None) -> float | None:
    return None if old is None or new is None or new <= 0 else old / new


def cell(value: float | None, digits: int = 3) -> str:
    return "-" if value is None else f"{value:.{digits}f}"


def verdict(met: bool) -> str:
    return "met" if met else "NOT met"


@dataclass
class Report:
    lines: list[str] = field(default_factory=list)
    verdicts: list[str] = field(default_factory=list)
    failures: list[str] = field(default_factory=list)

    def table(self, head: list[str], rows: list[list[str]]) -> None:
        self.lines += ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
        self.lines += ["| " + " | ".join(row) + " |" for row in rows]
        self.lines.append("")


def encode_table(report: Report, results: list[SequenceResult]) -> None:
    """Seconds, sizes and the decoded KG per sequence and target."""
    report.lines.append(
        "Encode from the loaded sequence (seconds, medians), sizes and the new file's decoded KG:"
    )
    report.lines.append("")
    rows, missed = [], []
    for result in results:
        for target, measure in result.encodes.items():
            if measure.errors:
                report.failures += measure.errors
                rows.append([result.name, f"{target:g}", "failed", *["-"] * 7])
                missed.append(f"{result.name} KG {target:g} (failed)")
                continue
            old, new = measure.median("old", "seconds"), measure.median("new", "seconds")
            speedup = ratio(old, new)
            old_bytes, new_bytes = measure.last("old")["bytes"], measure.last("new")["bytes"]
            size = new_bytes / old_bytes
            kg = result.kg.get((target, "new"))
            kg_ok = kg is not None and kg <= target
            rows.append(
                [
                    result.name,
                    f"{target:g}",
                    cell(old, 2),
                    cell(new, 2),
                    cell(speedup, 2),
                    str(old_bytes),
                    str(new_bytes),
                    f"{size:.4f}",
                    cell(kg, 5),
                    "ok" if kg_ok else "FAIL",
                ]
            )
            if not (speedup is not None and speedup >= ENCODE_SPEEDUP):
                missed.append(f"{result.name} KG {target:g} ({cell(speedup, 2)}x)")
            if size > SIZE_RATIO:
                missed.append(f"{result.name} KG {target:g} size {size:.4f}")
            if not kg_ok:
                missed.append(f"{result.name} KG {target:g} decoded KG {cell(kg, 5)}")
    report.table(
        [
            "sequence",
            "KG",
            "baseline s",
            "now s",
            "baseline/now",
            "baseline bytes",
            "now bytes",
            "now/baseline size",
            "decoded KG now",
            "<= target",
        ],
        rows,
    )
    report.verdicts.append(
        f"encode at least {ENCODE_SPEEDUP:g}x at KG 0.1 and 0.02 on every sequence, size at most "
        f"{SIZE_RATIO:g}x, decoded KG within the target: {verdict(not missed)}"
        + (f" (missed: {', '.join(missed)})" if missed else "")
    )


def decode_table(report: Report, results: list[SequenceResult]) -> None:
    """Open + frame 0 and all frames, own files and the baseline's file."""
    report.lines.append(
        f"Decode of the KG {DECODE_TARGET:g} files from bytes (seconds, medians): "
        "`Decoder(data)` + `frame(0)`, and `Decoder(data).positions()`; each package's own "
        "file, then both on the baseline's file:"
    )
    report.lines.append("")
    rows = []
    open_ratios: dict[str, float | None] = {}
    all_ratios: dict[str, float | None] = {}
    for result in results:
        measure = result.decode
        if measure is None:
            continue
        if measure.errors:
            report.failures += measure.errors
            rows.append([result.name, "failed", *["-"] * 7])
            continue
        for file, contender in (("own", "new"), ("baseline's", "new on old file")):
            opened = [measure.median(c, "open_frame") for c in ("old", contender)]
            whole = [measure.median(c, "positions") for c in ("old", contender)]
            same = "-"
            if file == "baseline's":
                hashes = {s["hash"] for c in ("old", contender) for s in measure.samples[c]}
                same = "yes" if len(hashes) == 1 else "NO"
                if same == "NO":
                    report.failures.append(
                        f"{result.name}: the baseline's file decodes to other positions now"
                    )
                open_ratios[f"{result.name}, baseline's file"] = ratio(*opened)
                all_ratios[f"{result.name}, baseline's file"] = ratio(*whole)
            else:
                open_ratios[result.name] = ratio(*opened)
                all_ratios[result.name] = ratio(*whole)
            rows.append(
                [
                    result.name,
                    file,
                    cell(opened[0], 4),
                    cell(opened[1], 4),
                    cell(ratio(*opened), 2),
                    cell(whole[0], 4),
                    cell(whole[1], 4),
                    cell(ratio(*whole), 2),
                    same,
                ]
            )
    report.table(
        [
            "sequence",
            "file",
            "open + frame 0: baseline s",
            "now s",
            "baseline/now",
            "all frames: baseline s",
            "now s",
            "baseline/now",
            "positions bit-identical",
        ],
        rows,
    )
    samba = {k: v for k, v in open_ratios.items() if k.startswith(OPEN_SEQUENCE)}
    if samba:
        report.verdicts.append(
            f"{OPEN_SEQUENCE}: `Decoder(bytes)` + first frame at least {OPEN_SPEEDUP:g}x: "
            + "; ".join(
                f"{verdict(v is not None and v >= OPEN_SPEEDUP)} ({k}, {cell(v, 2)}x)"
                for k, v in samba.items()
            )
        )
    else:
        report.verdicts.append(f"{OPEN_SEQUENCE} open + first frame: not measured (not given)")
    short = [
        f"{k} ({cell(v, 2)}x)" for k, v in all_ratios.items() if not (v and v >= POSITIONS_SPEEDUP)
    ]
    if all_ratios:
        report.verdicts.append(
            f"all frames at least {POSITIONS_SPEEDUP:g}x on every sequence and file: "
            f"{verdict(not short)}" + (f" (missed: {', '.join(short)})" if short else "")
        )


def obj_table(report: Report, results: list[SequenceResult]) -> None:
    """The OBJ folders: seconds and whether the text is the same."""
    measured = [r for r in results if r.obj is not None]
    if not measured:
        return
    report.lines.append(
        f"Decode of the baseline's KG {DECODE_TARGET:g} file to a folder of OBJ frames "
        "(`decode_file(file, folder)`, as `tuckercodec decode FILE.tkc FOLDER`; seconds, "
        "medians):"
    )
    report.lines.append("")
    rows, missed = [], []
    for result in measured:
        measure = result.obj
        assert measure is not None
        if measure.errors:
            report.failures += measure.errors
            rows.append([result.name, "failed", *["-"] * 5])
            missed.append(f"{result.name} (failed)")
            continue
        old, new = measure.median("old", "seconds"), measure.median("new", "seconds")
        hashes = [
            json.dumps(s["hashes"], sort_keys=True)
            for c in ("old", "new")
            for s in measure.samples[c]
        ]
        same = len(set(hashes)) == 1
        if not same:
            report.failures.append(f"{result.name}: the OBJ text differs from the baseline's")
        speedup = ratio(old, new)
        last = measure.last("new")
        rows.append(
            [
                result.name,
                str(len(last["hashes"])),
                f"{last['bytes'] / MB:.1f}",
                cell(old, 3),
                cell(new, 3),
                cell(speedup, 2),
                "yes" if same else "NO",
            ]
        )
        if not (same and speedup is not None and speedup >= OBJ_SPEEDUP):
            missed.append(f"{result.name} ({cell(speedup, 2)}x, text same: {same})")
    report.table(
        [
            "sequence",
            "files",
            "MB of text",
            "baseline s",
            "now s",
            "baseline/now",
            "text identical",
        ],
        rows,
    )
    report.verdicts.append(
        f"OBJ folder at least {OBJ_SPEEDUP:g}x, text identical: {verdict(not missed)}"
        + (f" (missed: {', '.join(missed)})" if missed else "")
    )


def large_table(report: Report, large: LargeResult) -> None:
    """The large file's first frame, memory and later frames."""
    measure = large.measure
    report.lines.append(
        f"First frame from disk of {large.file.name} ({LARGE_VERTICES} vertices requested, "
        f"{LARGE_FRAMES} frames, segments of {LARGE_SEGMENT_FRAMES}; {large.made}), a fresh "
        "process per run: `import tuckercodec` + `Decoder(path)` + `frame(0)` (the target's "
        "measure: a package that imports lazily imports the decoder in the call) and the call "
        "alone, the process's peak resident memory "
        f"after it (ru_maxrss), and the median of frames {large.frames} decoded after it:"
    )
    report.lines.append("")
    if measure.errors:
        report.failures += measure.errors
        report.lines += [f"failed: {e}" for e in measure.errors] + [""]
        report.verdicts.append("large file: NOT measured (failed)")
        return

    def later(contender: str) -> float | None:
        runs = [statistics.median(s["later"]) for s in measure.samples[contender]]
        return statistics.median(runs) if runs else None

    first = [measure.median(c, "first_with_import") for c in ("old", "new")]
    opened = [measure.median(c, "first") for c in ("old", "new")]
    peak = [measure.median(c, "first_peak") for c in ("old", "new")]
    after = [later(c) for c in ("old", "new")]
    rows = [
        [
            "import tuckercodec + open + frame 0 (s)",
            cell(first[0], 3),
            cell(first[1], 3),
            cell(ratio(*first), 2),
        ],
        ["open + frame 0 (s)", cell(opened[0], 3), cell(opened[1], 3), cell(ratio(*opened), 2)],
        [
            "peak resident memory after frame 0 (MB)",
            cell((peak[0] or 0) / MB, 0),
            cell((peak[1] or 0) / MB, 0),
            cell(ratio(*peak), 2),
        ],
        [
            "a later frame, median (ms)",
            cell((after[0] or 0) * 1000, 1),
            cell((after[1] or 0) * 1000, 1),
            cell(ratio(*after), 2),
        ],
    ]
    report.table(["measure", "baseline", "now", "baseline/now"], rows)
    speedup = ratio(*first)
    report.verdicts.append(
        f"large file: first frame at least {LARGE_SPEEDUP:g}x: "
        f"{verdict(speedup is not None and speedup >= LARGE_SPEEDUP)} ({cell(speedup, 2)}x); "
        f"at most {LARGE_PEAK_BYTES / MB:g} MB resident: "
        f"{verdict(peak[1] is not None and peak[1] <= LARGE_PEAK_BYTES)}; later frames at most "
        f"{LARGE_LATER_SECONDS * 1000:g} ms: "
        f"{verdict(after[1] is not None and after[1] <= LARGE_LATER_SECONDS)}"
    )


# ------------------------------------------------------------------------------------------
# the command line


def say(text: str) -> None:
    print(f"speed: {text}...", file=sys.stderr, flush=True)


def load_average() -> str:
    try:
        return " ".join(f"{value:.2f}" for value in os.getloadavg())
    except OSError:
        return "unknown"


def revision_of(name: str) -> str | None:
    """The commit ``name`` names, abbreviated, or None when git does not know it."""
    done = subprocess.run(
        ["git", "-C", str(common.REPO), "rev-parse", "--short=12", f"{name}^{{commit}}"],
        capture_output=True,
        text=True,
        check=False,
    )
    return done.stdout.strip() if done.returncode == 0 else None


def checkout_state() -> str:
    """This checkout's commit, and whether its package has uncommitted changes."""
    head = revision_of("HEAD") or "unknown"
    changed = subprocess.run(
        ["git", "-C", str(common.REPO), "status", "--porcelain", "--", "tuckercodec"],
        capture_output=True,
        text=True,
        check=False,
    ).stdout.strip()
    return head + (" with uncommitted changes to tuckercodec/" if changed else "")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The speed suite's options."""
    arguments.sequences(parser, "every sequence of ../shared/data")
    parser.add_argument(
        "--baseline", default=DEFAULT_BASELINE, help=f"a git revision (default {DEFAULT_BASELINE})"
    )
    arguments.repeat(parser, 3, "timed rounds of each measure, the medians reported")
    parser.add_argument(
        "--warmup",
        type=int,
        default=1,
        help="rounds run first and thrown away (default 1)",
    )
    parser.add_argument(
        "--large",
        action="store_true",
        help=f"also the first frame from disk of a {LARGE_VERTICES} x {LARGE_FRAMES} segmented "
        "file (made once in --workdir: about 1.2 GB of input and some minutes)",
    )
    parser.add_argument("--workdir", type=Path, default=DEFAULT_WORKDIR, help="for --large")
    arguments.output(
        parser,
        "output folder: the files and speed.md (default results/bench-speed)",
        "results/bench-speed",
    )


def run(args: argparse.Namespace) -> int:
    """Measure and print; the exit status."""
    if args.warmup < 0:
        raise arguments.UsageError("--warmup must be at least 0")
    revision = revision_of(args.baseline)
    if revision is None:
        raise arguments.UsageError(f"git knows no revision {args.baseline}")
    inputs = arguments.sequences_and_folder(args, MARKER)
    if inputs is None:
        return 2
    sequences, out = inputs
    args.workdir = args.workdir.expanduser().resolve()
    obj_sequences = [s for s in sequences if is_obj_folder(s)] or sequences[:1]
    load_before = load_average()
    started = time.monotonic()
    with ExitStack() as stack:
        folder = stack.enter_context(git_package(revision))
        if folder is None:
            return 1
        old, new = Package(f"baseline {revision}", folder), Package("now", common.REPO)
        results = [measure_sequence(s, old, new, out, args, s in obj_sequences) for s in sequences]
        large = measure_large(args, old, new, revision) if args.large else None
    report = Report()
    report.lines += [
        f"Speed of this checkout ({checkout_state()}) against the baseline {revision} "
        f"(`{args.baseline}`), one run, {args.repeat} rounds after {args.warmup} warm-up, "
        "baseline and now alternating in fresh processes (the order turned each round):",
        "",
    ]
    encode_table(report, results)
    decode_table(report, results)
    obj_table(report, results)
    if large is not None:
        large_table(report, large)
    report.lines += ["Verdicts against the speed targets:", ""]
    report.lines += [f"- {line}" for line in report.verdicts]
    report.lines += [""] + [f"FAILED: {line}" for line in report.failures]
    report.lines += [
        f"machine: {common.machine()}",
        f"load average (1, 5, 15 min): {load_before} before, {load_average()} after "
        f"({(time.monotonic() - started) / 60:.1f} min)",
        f"command: {args.command}",
    ]
    text = "\n".join(report.lines).rstrip() + "\n"
    print(text, end="")
    common.write_text(out / MARKER, text, force=True)
    return 1 if report.failures else 0
