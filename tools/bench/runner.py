"""The one command of the benchmarks: ``python -m tools.bench SUITE [options]``.

Each suite is a module of :mod:`tools.bench` with ``add_arguments(parser)``, which declares its
options (the shared ones through :mod:`tools.bench.arguments`), and ``run(args)``, which measures
and prints, returning the exit status. ``args.command`` holds the command line that ran it, as
the suites print it beside their results.
"""

from __future__ import annotations

import argparse
import importlib
from types import ModuleType

from tools import common
from tools.bench.arguments import UsageError

#: The suites, by the name given on the command line, and their modules.
SUITES = {
    "peers": "tools.bench.peers",
    "codec": "tools.bench.codec",
    "analysis": "tools.bench.analysis",
    "bpfv": "tools.bench.bpfv",
    "size": "tools.bench.size",
    "rate": "tools.bench.rate",
    "entropy": "tools.bench.entropy",
    "scale": "tools.bench.scale",
    "read": "tools.bench.read",
    "streaming": "tools.bench.streaming",
    "gltf": "tools.bench.gltf",
    "zarr": "tools.bench.zarr",
    "viewer": "tools.bench.viewer",
    "faces": "tools.bench.faces",
    "bounds": "tools.bench.bounds",
    "lossless": "tools.bench.lossless",
    "speed": "tools.bench.speed",
    "fields": "tools.bench.fields",
    "attributes": "tools.bench.attributes",
}


def suite(name: str) -> ModuleType:
    """The module of the suite ``name``."""
    return importlib.import_module(SUITES[name])


def parser() -> tuple[argparse.ArgumentParser, dict[str, argparse.ArgumentParser]]:
    """The command's parser, and each suite's."""
    main_parser = argparse.ArgumentParser(
        prog="python -m tools.bench",
        description="Run one benchmark suite; every suite prints what it measured, the machine "
        "and the command.",
    )
    commands = main_parser.add_subparsers(dest="suite", metavar="SUITE", required=True)
    parsers = {}
    for name in SUITES:
        module = suite(name)
        summary = " ".join((module.__doc__ or "").strip().split("\n\n")[0].split())
        parsers[name] = commands.add_parser(name, help=summary, description=summary)
        module.add_arguments(parsers[name])
    return main_parser, parsers


def main(argv: list[str] | None = None) -> int:
    """Run the suite ``argv`` names (None: this process's arguments); its exit status."""
    main_parser, parsers = parser()
    args = main_parser.parse_args(argv)
    args.command = common.command("tools.bench", argv)
    try:
        status: int = suite(args.suite).run(args)
    except UsageError as error:
        parsers[args.suite].error(str(error))
    return status
