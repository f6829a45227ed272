"""Optional dependencies: the libraries of one feature, installed by an extra named after it."""

from __future__ import annotations

import importlib
import importlib.util
from types import ModuleType

from ..errors import DependencyError

#: The module that tells whether each extra of pyproject.toml is installed.
EXTRA_MODULES = {
    "plot": "matplotlib",
    "usd": "pxr",
    "alembic": "alembic3d",
    "gltf": "meshoptimizer",
    "xdmf": "h5py",
    "dask": "distributed",
    "zarr": "zarr",
}


def extra_installed(extra: str) -> bool:
    """Whether the package that the extra ``extra`` installs can be imported (not importing
    it: some are slow to import)."""
    return importlib.util.find_spec(EXTRA_MODULES[extra]) is not None


def import_optional(module: str, extra: str, purpose: str) -> ModuleType:
    """Import ``module``, or raise a :class:`DependencyError` whose one-line message names the
    extra that installs it (``pip install 'tuckercodec[extra]'``).

    Args:
        module: the module to import, such as ``"pxr.Usd"``.
        extra: the extra of ``pyproject.toml`` that installs it, such as ``"usd"``.
        purpose: what needs it, for the message, such as ``"reading USD files"``.
    """
    try:
        return importlib.import_module(module)
    except ImportError as error:
        raise DependencyError(
            f"{purpose} needs the package that provides {module.split('.')[0]!r}: "
            f"pip install 'tuckercodec[{extra}]'"
        ) from error
