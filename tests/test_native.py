"""Which implementation runs: the compiled core or pure Python (tuckercodec.system.native), and
what the command line says of it. The two implementations' agreement is tested area by area in
the tests named test_native_*.py."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

from tuckercodec.system import native


def _version(setting: str | None) -> subprocess.CompletedProcess[str]:
    environment = {k: v for k, v in os.environ.items() if k != native.ENVIRONMENT_VARIABLE}
    if setting is not None:
        environment[native.ENVIRONMENT_VARIABLE] = setting
    command = [sys.executable, "-m", "tuckercodec", "--version"]
    return subprocess.run(command, capture_output=True, text=True, env=environment, check=False)


def test_zero_chooses_pure_python():
    done = _version("0")
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip().endswith("pure Python (TUCKERCODEC_NATIVE=0)")


def test_a_misspelt_setting_is_a_one_line_error():
    done = _version("yes")
    assert done.returncode == 6
    assert done.stdout == ""
    assert done.stderr.strip().splitlines() == [
        "tuckercodec: error: TUCKERCODEC_NATIVE='yes': expected 0 (pure Python), 1 (the "
        "compiled core) or auto"
    ]


def test_auto_and_one_say_which_runs():
    installed = native.core() is not None
    auto = _version(None)
    assert auto.returncode == 0, auto.stderr
    assert ("compiled core" in auto.stdout) == installed
    required = _version("1")
    if installed:
        assert required.returncode == 0 and "compiled core" in required.stdout
    else:  # a core that must run and is missing: an error, not a slow run unnoticed
        assert required.returncode == 6
        assert "TUCKERCODEC_NATIVE=1 but the compiled core is not installed" in required.stderr


def test_pure_python_switches_the_core_off_for_a_block():
    before = native.core()
    with native.pure_python():
        assert native.core() is None
        assert native.describe().startswith("pure Python")
        with native.pure_python():
            assert native.core() is None
        assert native.core() is None
    assert native.core() is before


def test_the_core_reports_its_version():
    core = native.core()
    if core is None:
        pytest.skip("the compiled core is not installed (python -m tools.build_native)")
    assert core.core_version().count(".") == 2
    assert native.describe() == f"compiled core {core.core_version()} (Rust)"
