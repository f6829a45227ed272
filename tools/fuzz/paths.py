"""Where the fuzz inputs live (without importing tuckercodec: see the package's docstring)."""

from __future__ import annotations

from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]  # tools.common.REPO, without importing tuckercodec
VECTORS = ROOT / "spec" / "vectors"
FUZZ_DIR = ROOT / "tests" / "fuzz"
CORPUS = FUZZ_DIR / "corpus"
CRASHES = FUZZ_DIR / "crashes"
REGRESSIONS = FUZZ_DIR / "regressions"
#: Files in the fuzz folders that are notes, not inputs.
NOT_INPUTS = {".md", ".txt", ".json"}


def saved_inputs(*folders: Path) -> list[Path]:
    """Every input file in the given folders (notes and tracebacks left out)."""
    out: list[Path] = []
    for folder in folders:
        if folder.is_dir():
            out += sorted(p for p in folder.iterdir() if p.is_file() and p.suffix not in NOT_INPUTS)
    return out
