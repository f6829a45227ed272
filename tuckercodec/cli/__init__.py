"""The ``tuckercodec`` command line: :mod:`.arguments` parses, :mod:`.main` runs one verb and
turns failures into exit codes (:mod:`.failures` says which), :mod:`.inputs` reads what the verbs
read.

The twelve verbs live by concern (``main._VERBS`` maps each to its function): encode, decode and
info in :mod:`.codec`; rd, eval, render and demo in :mod:`.commands`; convert and formats in
:mod:`.convert`; batch in :mod:`.batch`; view in :mod:`.view`; blender-addon in :mod:`.addon`.
"""

from .main import main

__all__ = ["main"]
