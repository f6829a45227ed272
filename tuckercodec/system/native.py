"""The compiled core (``tuckercodec._native``, built from ``tuckercodec/native/``), or none.

The core runs the loops that Python cannot run fast; for each, the pure-Python code stays as the
reference and the fallback, and the two give the same bytes and the same bits. Which runs:

- ``TUCKERCODEC_NATIVE`` unset, empty or ``auto``: the core where it is installed, else Python;
- ``TUCKERCODEC_NATIVE=0``: pure Python, even where the core is installed;
- ``TUCKERCODEC_NATIVE=1``: the core, and an error (:class:`DependencyError`) where it is
  missing, for a deployment that must not run slowly unnoticed.

The choice is read once, at the first call of :func:`core`. :func:`pure_python` switches the
core off for a block of code, as the tests that compare the two do.
"""

from __future__ import annotations

import importlib
import os
from collections.abc import Iterator
from contextlib import contextmanager
from types import ModuleType

from ..errors import DependencyError

ENVIRONMENT_VARIABLE = "TUCKERCODEC_NATIVE"
_CHOICES = {"": "auto", "auto": "auto", "0": "off", "1": "on"}

_loaded: ModuleType | None = None
_why_not: str | None = None  # why there is no core, once looked for
_looked = False
_switched_off = 0  # depth of pure_python() blocks


def _look() -> None:
    global _loaded, _why_not, _looked
    _looked = True
    setting = os.environ.get(ENVIRONMENT_VARIABLE, "").strip().lower()
    choice = _CHOICES.get(setting)
    if choice is None:
        raise DependencyError(
            f"{ENVIRONMENT_VARIABLE}={setting!r}: expected 0 (pure Python), 1 (the compiled "
            "core) or auto"
        )
    if choice == "off":
        _why_not = f"{ENVIRONMENT_VARIABLE}=0"
        return
    try:
        _loaded = importlib.import_module("tuckercodec._native")
    except ImportError as error:
        _why_not = f"the compiled core is not installed ({error})"
        if choice == "on":
            raise DependencyError(
                f"{ENVIRONMENT_VARIABLE}=1 but {_why_not}: install tuckercodec where cargo "
                "(Rust) is on the PATH"
            ) from error


def core() -> ModuleType | None:
    """The compiled core's module, or ``None`` where pure Python runs."""
    if not _looked:
        _look()
    return None if _switched_off else _loaded


def describe() -> str:
    """Which implementation runs, for ``tuckercodec --version`` and ``info``: the compiled core
    and its version, or pure Python and why."""
    module = core()
    if module is not None:
        return f"compiled core {module.core_version()} (Rust)"
    if _switched_off:
        return "pure Python (switched off in this block)"
    return f"pure Python ({_why_not})"


@contextmanager
def pure_python() -> Iterator[None]:
    """Run the block in pure Python, the reference, whether or not the core is installed."""
    global _switched_off
    _switched_off += 1
    try:
        yield
    finally:
        _switched_off -= 1
