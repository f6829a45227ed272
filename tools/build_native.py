"""Build the compiled core in place, for development: ``python -m tools.build_native``.

``pip install .`` builds it as a user gets it; an editable checkout needs this after each change
to ``tuckercodec/native/``: cargo builds the release library, and it is copied into the
package as ``_native`` with this Python's extension suffix (git ignores it), where
``import tuckercodec._native`` finds it. ``--debug`` builds without optimisation (faster to
build, slower to run).
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import sysconfig
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
CRATES = ROOT / "tuckercodec" / "native"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--debug", action="store_true", help="an unoptimised build")
    args = parser.parse_args(argv)
    profile = "debug" if args.debug else "release"
    command = ["cargo", "build", "--locked", "-p", "tuckercodec-python"]
    if not args.debug:
        command.append("--release")
    environment = {"PYO3_PYTHON": sys.executable}
    subprocess.run(command, cwd=CRATES, check=True, env={**os.environ, **environment})
    built = CRATES / "target" / profile / "lib_native.so"
    target = ROOT / "tuckercodec" / f"_native{sysconfig.get_config_var('EXT_SUFFIX')}"
    shutil.copyfile(built, target.with_suffix(".tmp"))
    target.with_suffix(".tmp").replace(target)
    print(f"built {target.relative_to(ROOT)} ({profile})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
