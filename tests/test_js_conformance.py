"""The JavaScript decoder (tuckercodec/web/tkc/, written from spec/FORMAT.md) against the
conformance vectors of spec/vectors (§12), in node: every valid vector decodes to the digests,
header facts, names and reconstruction its JSON gives, and every invalid one fails with its rule
and error class, as the Python decoder does. The same observations in a browser are in
test_viewer_browser.py."""

from __future__ import annotations

from typing import Any

import pytest

from tests.support.js_decoder import (
    INVALID,
    VALID,
    VECTORS,
    check_every_vector_observed,
    check_invalid_observation,
    check_valid_observation,
    run_node,
)


@pytest.fixture(scope="module")
def observed() -> dict[str, Any]:
    """What the JavaScript decoder makes of every vector (tests/js/conformance_observe.mjs)."""
    return run_node("conformance.mjs", VECTORS)


def test_every_vector_observed(observed):
    check_every_vector_observed(observed)


@pytest.mark.parametrize("name", VALID)
def test_valid_vector(observed, name):
    check_valid_observation(observed, name)


@pytest.mark.parametrize("name", INVALID)
def test_invalid_vector(observed, name):
    check_invalid_observation(observed, name)
