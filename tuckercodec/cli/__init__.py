"""The ``tuckercodec`` command line: :mod:`.arguments` parses, :mod:`.commands` holds the verbs,
:mod:`.main` runs one and turns failures into exit codes."""

from .main import main

__all__ = ["main"]
