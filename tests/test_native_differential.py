"""The compiled core against pure Python on whole files (tools/fuzz/differential.py): the
conformance vectors, the decoders' committed fuzz inputs and mutations of them must decode to
the same bits, or be refused with the same class, rule and message, by both. RELIABILITY.md
records the long run (100,000 mutations and more); this is its short form, on every submission."""

from __future__ import annotations

import pytest

from tools.fuzz.differential import compare, seed_inputs
from tuckercodec.system import native


@pytest.fixture(scope="module")
def summary():
    if native.core() is None:
        pytest.skip("the compiled core is not installed (python -m tools.build_native)")
    return compare(count=1500, seed=20261204)


def test_the_core_and_python_agree_on_every_input(summary):
    assert summary["failures"] == []
    assert summary["inputs"] == len(seed_inputs()) + 1500


def test_the_inputs_reach_past_the_checksums(summary):
    # a differential test that only ever compared CRC failures would prove nothing
    verdicts, rules = summary["verdicts"], summary["rules"]
    assert verdicts.get("ok", 0) >= 50
    deep = ("R39-traversal", "R33-face-index", "R40-residual", "R28-shape", "R30-planes")
    assert all(rules.get(rule, 0) > 0 for rule in deep), rules
