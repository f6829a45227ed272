"""The ``blender-addon`` verb: write the Blender add-on's installable zip
(:mod:`tuckercodec.blender.package`)."""

from __future__ import annotations

import argparse

from ..blender.package import write_addon_zip
from ..errors import EXIT_OK
from ..system.atomic import refuse_existing


def run_blender_addon(args: argparse.Namespace) -> int:
    refuse_existing([args.output], args.force)  # before the wheels are fetched
    written = write_addon_zip(args.output, args.platform or (), overwrite=args.force)
    print(
        f"wrote {written.path}: the Blender extension tuckercodec_blender (Blender 4.2+), "
        f"{written.size} bytes, for {', '.join(written.platforms)}, with the wheels "
        f"{', '.join(written.wheels)}"
    )
    print("install it in Blender: Edit > Preferences > Get Extensions > Install from Disk")
    return EXIT_OK
