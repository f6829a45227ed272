"""The installable zip of the Blender add-on: a Blender 4.2+ extension that bundles its wheels.

An artist installs one file (Edit > Preferences > Get Extensions > Install from Disk). The zip
holds::

    blender_manifest.toml        id "tuckercodec_blender", its platforms and wheels
    __init__.py                  imports register/unregister from tuckercodec.blender.addon
    wheels/tuckercodec-V-py3-none-any.whl   this package, built here from its installed files:
                                 its modules and package data, no hidden file, no link
    wheels/scipy-..., msgpack-..., zstandard-...   fetched by ``pip download`` for each platform

Blender installs the wheels into the extensions' own site-packages, ahead of its bundled
modules. Blender brings numpy (1.26 in 4.2 to 4.5), which is why it is not bundled; scipy is,
because the encoder (export) needs scipy.linalg and the decoder's mesh-mean restore a sparse
product. The wheels are for Blender's Python, 3.11 (Blender 4.2 to 4.5), so the zip declares the
platforms it has wheels for, and Blender refuses it on any other.
"""

from __future__ import annotations

import base64
import fnmatch
import hashlib
import os
import platform
import subprocess
import sys
import tempfile
import zipfile
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from .._version import __version__
from ..errors import DependencyError
from ..system.atomic import atomic_output

#: The add-on's module and extension id.
ADDON_ID = "tuckercodec_blender"
#: Blender's Python: the bundled wheels are built for it (Blender 4.2 to 4.5 run 3.11).
BLENDER_PYTHON = "3.11"
BLENDER_MIN = "4.2.0"
#: The wheels bundled beside tuckercodec's, as pip requirements. scipy below 1.17: 1.17 needs
#: numpy 1.26.4 or newer at least, and the wheels must run on the numpy Blender brings.
BUNDLED_REQUIREMENTS = ("scipy>=1.11,<1.17", "msgpack>=1.0", "zstandard>=0.22")
#: Blender's platform names and the wheel platform tags pip may choose for each.
PLATFORM_TAGS: dict[str, tuple[str, ...]] = {
    "linux-x64": ("manylinux_2_28_x86_64", "manylinux_2_17_x86_64", "manylinux2014_x86_64"),
    "windows-x64": ("win_amd64",),
    "macos-arm64": ("macosx_14_0_arm64", "macosx_12_0_arm64", "macosx_11_0_arm64"),
    "macos-x64": ("macosx_14_0_x86_64", "macosx_10_14_x86_64", "macosx_10_9_x86_64"),
}
#: A fixed time for every member, so that the same inputs make the same zip.
_ZIP_TIME = (1980, 1, 1, 0, 0, 0)

_INIT = f'''"""{ADDON_ID}: open and export tuckercodec .tkc files (animated meshes) in Blender.

Written by `tuckercodec blender-addon` (tuckercodec {__version__}); the add-on's code is
tuckercodec.blender.addon, in the tuckercodec wheel this extension bundles.
"""

from tuckercodec.blender.addon import register, unregister

__all__ = ["register", "unregister"]
'''


@dataclass(frozen=True)
class AddonZip:
    """What :func:`write_addon_zip` wrote: the zip's path, its platforms and its wheels."""

    path: Path
    platforms: tuple[str, ...]
    wheels: tuple[str, ...]
    size: int


def current_platform() -> str:
    """This machine's platform in Blender's naming (``linux-x64``...); ``ValueError`` if Blender
    has no such platform for which wheels are bundled."""
    machine = platform.machine().lower()
    arch = {"x86_64": "x64", "amd64": "x64", "arm64": "arm64", "aarch64": "arm64"}.get(machine)
    system = {"linux": "linux", "darwin": "macos", "win32": "windows"}.get(sys.platform)
    name = f"{system}-{arch}"
    if name not in PLATFORM_TAGS:
        raise ValueError(
            f"no bundled wheels for this machine ({sys.platform}, {machine}): "
            f"name a platform with --platform ({', '.join(PLATFORM_TAGS)})"
        )
    return name


def manifest(platforms: Sequence[str], wheels: Sequence[str]) -> str:
    """The ``blender_manifest.toml`` of the extension (schema 1.0.0)."""
    listed = ", ".join(f'"{name}"' for name in platforms)
    wheel_lines = "".join(f'  "./wheels/{name}",\n' for name in wheels)
    return (
        'schema_version = "1.0.0"\n'
        f'id = "{ADDON_ID}"\n'
        f'version = "{__version__}"\n'
        'name = "tuckercodec (.tkc)"\n'
        'tagline = "Open and export compressed animated meshes (.tkc files)"\n'
        'maintainer = "tuckercodec"\n'
        'type = "add-on"\n'
        'tags = ["Import-Export", "Animation"]\n'
        f'blender_version_min = "{BLENDER_MIN}"\n'
        'license = ["SPDX:MIT"]\n'
        f"platforms = [{listed}]\n"
        f"wheels = [\n{wheel_lines}]\n"
        "\n[permissions]\n"
        'files = "Read .tkc files and write .tkc files and point caches"\n'
    )


def _record_hash(data: bytes) -> str:
    digest = base64.urlsafe_b64encode(hashlib.sha256(data).digest()).rstrip(b"=")
    return f"sha256={digest.decode()}"


def _zip_member(archive: zipfile.ZipFile, name: str, data: bytes, *, deflate: bool) -> None:
    info = zipfile.ZipInfo(name, date_time=_ZIP_TIME)
    info.external_attr = 0o644 << 16
    info.compress_type = zipfile.ZIP_DEFLATED if deflate else zipfile.ZIP_STORED
    archive.writestr(info, data)


#: pyproject's package data of ``tuckercodec`` (``[tool.setuptools.package-data]``), which the
#: wheel takes beside the Python modules; tests/test_blender_addon.py checks the two agree. The
#: package is read from where it is installed, where pyproject.toml is not.
PACKAGE_DATA = (
    "data/*.npz",
    "data/*.txt",
    "py.typed",
    "web/viewer/*.html",
    "web/viewer/*.js",
    "web/viewer/*.css",
    "web/tkc/*.js",
    "web/tkc/*.md",
    "web/three/*.js",
    "web/vendor/*/*",
)


def _declared(relative: tuple[str, ...]) -> bool:
    """Whether a file (its path's parts inside the package) is one setuptools puts in the
    wheel: a Python module, or a match of a :data:`PACKAGE_DATA` pattern (``*`` within one
    part, as glob matches, and not a hidden name)."""
    if relative[-1].endswith(".py"):
        return True
    return any(
        len(parts) == len(relative) and all(map(fnmatch.fnmatchcase, relative, parts))
        for parts in (pattern.split("/") for pattern in PACKAGE_DATA)
    )


def package_files(root: Path | None = None) -> list[tuple[str, Path]]:
    """(name in the wheel, file) of every file the package declares: its Python modules and
    :data:`PACKAGE_DATA`, as setuptools builds its wheel. Never a hidden file or folder (a
    developer's ``.env``, an editor's settings), nor a folder with a dot in its name (setuptools
    takes no package there), nor ``__pycache__``; a symbolic link is not followed, whether to a
    file or a folder, so nothing outside the package ships."""
    root = Path(__file__).resolve().parents[1] if root is None else root
    files: list[tuple[str, Path]] = []
    pending: list[tuple[Path, tuple[str, ...]]] = [(root, ())]
    while pending:
        folder, parts = pending.pop()
        with os.scandir(folder) as entries:
            for entry in entries:
                if entry.name.startswith(".") or entry.is_symlink():
                    continue
                relative = (*parts, entry.name)
                if entry.is_dir(follow_symlinks=False):
                    if "." not in entry.name and entry.name != "__pycache__":
                        pending.append((Path(entry.path), relative))
                elif entry.is_file(follow_symlinks=False) and _declared(relative):
                    files.append(("/".join((root.name, *relative)), Path(entry.path)))
    return sorted(files)


def build_own_wheel(folder: Path, root: Path | None = None) -> Path:
    """This package as a pure-Python wheel in ``folder``, built from its installed files (no
    build tools, no network): the package, then METADATA, WHEEL and RECORD in its dist-info.
    Its dependencies are not declared: Blender does not resolve them, the zip bundles them."""
    name = f"tuckercodec-{__version__}-py3-none-any.whl"
    info = f"tuckercodec-{__version__}.dist-info"
    members = [(arcname, path.read_bytes()) for arcname, path in package_files(root)]
    members.append(
        (
            f"{info}/METADATA",
            (
                "Metadata-Version: 2.1\nName: tuckercodec\n"
                f"Version: {__version__}\nRequires-Python: >=3.11\n"
            ).encode(),
        )
    )
    members.append(
        (
            f"{info}/WHEEL",
            b"Wheel-Version: 1.0\nGenerator: tuckercodec blender-addon\n"
            b"Root-Is-Purelib: true\nTag: py3-none-any\n",
        )
    )
    record = "".join(f"{arc},{_record_hash(data)},{len(data)}\n" for arc, data in members)
    members.append((f"{info}/RECORD", (record + f"{info}/RECORD,,\n").encode()))
    with zipfile.ZipFile(folder / name, "w") as wheel:
        for arcname, data in members:
            _zip_member(wheel, arcname, data, deflate=True)
    return folder / name


def download_wheels(platform_name: str, folder: Path) -> list[Path]:
    """The bundled requirements' wheels for Blender's Python on ``platform_name``, fetched into
    ``folder`` by ``pip download`` (from the index pip is configured with). Raises
    :class:`~tuckercodec.errors.DependencyError` with pip's last lines when it cannot."""
    target = folder / platform_name
    target.mkdir()
    command = [
        *(sys.executable, "-m", "pip", "download", "--quiet", "--disable-pip-version-check"),
        *("--no-deps", "--only-binary=:all:", "--dest", str(target)),
        *("--python-version", BLENDER_PYTHON, "--implementation", "cp"),
        *(arg for tag in PLATFORM_TAGS[platform_name] for arg in ("--platform", tag)),
        *BUNDLED_REQUIREMENTS,
    ]
    done = subprocess.run(command, capture_output=True, text=True, check=False)
    wheels = sorted(target.glob("*.whl"))
    if done.returncode != 0 or len(wheels) != len(BUNDLED_REQUIREMENTS):
        said = "\n".join((done.stderr or done.stdout).strip().splitlines()[-3:])
        raise DependencyError(
            f"the add-on's wheels for {platform_name} (Python {BLENDER_PYTHON}: "
            f"{', '.join(BUNDLED_REQUIREMENTS)}) could not be fetched with pip download "
            f"(exit {done.returncode}, {len(wheels)} wheels): {said or 'no message'}"
        )
    return wheels


def write_addon_zip(
    path: str | os.PathLike[str], platforms: Sequence[str] = (), *, overwrite: bool = False
) -> AddonZip:
    """Write the add-on's installable zip to ``path``, atomically.

    Args:
        path: the zip to write; an existing file is refused (``FileExistsError``) unless
            ``overwrite``, before any wheel is fetched.
        platforms: Blender platform names (:data:`PLATFORM_TAGS`) to bundle wheels for;
            default this machine's.
    """
    target = Path(path)
    chosen = tuple(dict.fromkeys(platforms)) or (current_platform(),)
    unknown = [name for name in chosen if name not in PLATFORM_TAGS]
    if unknown:
        raise ValueError(f"unknown platform {unknown[0]!r}: one of {', '.join(PLATFORM_TAGS)}")
    with atomic_output(target, overwrite=overwrite) as handle, tempfile.TemporaryDirectory() as tmp:
        wheels = [build_own_wheel(Path(tmp))]
        for name in chosen:
            wheels += download_wheels(name, Path(tmp))
        names = tuple(dict.fromkeys(wheel.name for wheel in wheels))
        with zipfile.ZipFile(handle, "w") as archive:
            _zip_member(
                archive, "blender_manifest.toml", manifest(chosen, names).encode(), deflate=True
            )
            _zip_member(archive, "__init__.py", _INIT.encode(), deflate=True)
            written = set()
            for wheel in wheels:
                if wheel.name not in written:  # a wheel for two platforms is bundled once
                    written.add(wheel.name)
                    _zip_member(archive, f"wheels/{wheel.name}", wheel.read_bytes(), deflate=False)
        handle.flush()
        size = handle.tell()
    return AddonZip(target, chosen, names, size)
