"""What the command line says about an expected failure: one line and an exit code, the same
for a verb that stops (:mod:`.main`) and for one input of a batch that goes on (:mod:`.batch`)."""

from __future__ import annotations

from ..errors import (
    EXIT_FAILURE,
    EXIT_USAGE,
    DependencyError,
    FormatError,
    InputError,
    InternalError,
    TuckerCodecError,
    UnreachableTargetError,
)

#: What the one-line message calls each kind of error, after "tuckercodec: ".
KINDS: tuple[tuple[type[TuckerCodecError], str], ...] = (
    (InputError, "bad input: "),
    (FormatError, "invalid or corrupt file: "),
    (UnreachableTargetError, "target cannot be met: "),
    (InternalError, "internal error: "),  # its message asks for a report
    (DependencyError, ""),  # its message names the package and the extra to install
    (TuckerCodecError, "error: "),
)


def describe_failure(error: BaseException) -> tuple[str, str, int] | None:
    """``(kind, message, exit code)`` of an expected failure, the line being
    ``f"tuckercodec: {kind}{message}"``; None for anything else (a bug, an interrupt).

    Expected: the package's errors, an output that exists (FileExistsError), a usage error
    (ValueError: a rank out of range, a frame that does not exist) and I/O failures (OSError).
    """
    if isinstance(error, TuckerCodecError):
        kind = next(label for cls, label in KINDS if isinstance(error, cls))
        return kind, str(error), error.exit_code
    if isinstance(error, FileExistsError):
        return "", str(error), EXIT_FAILURE
    if isinstance(error, ValueError):
        return "", str(error), EXIT_USAGE
    if isinstance(error, OSError):
        return "", f"{error.filename or ''}: {error.strerror or error}", EXIT_FAILURE
    return None
