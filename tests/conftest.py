"""The fixtures the test modules share. Helpers they import live in :mod:`tests.support`."""

from __future__ import annotations

import os

import pytest

import tuckercodec
from tuckercodec import MeshSequence
from tuckercodec.io.samples import sample_path

#: The environment of each pytest-xdist worker (pyproject.toml's addopts run one per core): one
#: BLAS thread each, as tuckercodec.system.parallel gives its own workers. Two workers of two BLAS
#: threads each on two cores oversubscribe them, and OpenBLAS's waiting threads then make a
#: large factorisation several times slower (chicken's U1 at rank 1200: 3.7 s on one thread,
#: 23 s on two with the other core busy). A value already set is kept.
WORKER_ENVIRONMENT = {"OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}


def pytest_configure(config: pytest.Config) -> None:
    # The controller sets it before it starts the workers, which inherit it (numpy reads it when
    # first imported, and a worker may import it before this file, through a plugin).
    # (-n auto may not be resolved to a number yet; -n 0 runs in this process.)
    distributed = getattr(config.option, "numprocesses", None) not in (None, 0)
    if distributed and not hasattr(config, "workerinput"):
        for name, value in WORKER_ENVIRONMENT.items():
            os.environ.setdefault(name, value)


@pytest.fixture(scope="module")
def cloth() -> MeshSequence:
    """The cloth that ships with the package (60 frames of 3101 vertices)."""
    return tuckercodec.load_sequence(sample_path(), progress=False)
