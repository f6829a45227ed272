"""The exception hierarchy of tuckercodec, and the command line's exit code for each class.

Every error the library raises on purpose derives from :class:`TuckerCodecError`, so a caller can
catch one class. Misuse of the API (a wrong argument type, an impossible parameter, a frame that
does not exist) raises the plain ``TypeError``/``ValueError`` as usual. The classes that describe
a bad value (:class:`InputError`, :class:`FormatError`, :class:`UnreachableTargetError`,
:class:`FormatVersionError`) are also ``ValueError``\\ s, so that code written against generic
exceptions keeps working.
:class:`InternalError` is the one that is nobody's fault but tuckercodec's: a state the code
checks for and holds impossible (a file that does not decode to what was measured), reported
as a bug rather than as something the caller could change.

Each class carries the exit code the command line returns for it
(:attr:`TuckerCodecError.exit_code`).
"""

from __future__ import annotations

import os
from typing import Any

#: The command line's exit codes (also listed in the README).
EXIT_OK = 0
#: an output that exists (without --force; with it, a folder the tool did not write), or
#: another I/O failure
EXIT_FAILURE = 1
EXIT_USAGE = 2  # a usage error: an option out of range, a frame that does not exist
EXIT_CORRUPT = 3  # an invalid or corrupt compressed file (FormatError)
EXIT_BAD_INPUT = 4  # a mesh sequence that cannot be read or used (InputError)
EXIT_UNREACHABLE = 5  # a target no file of the format can meet (UnreachableTargetError)
EXIT_MISSING_DEPENDENCY = 6  # an optional package a feature needs is absent (DependencyError)
# 7: `batch`, some inputs failed (cli.batch.EXIT_SOME_FAILED)
EXIT_INTERNAL = 70  # a bug in tuckercodec (InternalError): sysexits.h's EX_SOFTWARE


class TuckerCodecError(Exception):
    """Base class of every error raised by tuckercodec on purpose."""

    #: What the command line exits with when this error stops it.
    exit_code: int = EXIT_FAILURE


class InputError(TuckerCodecError, ValueError):
    """A mesh sequence that cannot be read or used: names the file, frame and line at fault.

    Attributes are ``None`` where they do not apply.
    """

    exit_code = EXIT_BAD_INPUT

    def __init__(
        self,
        message: str,
        *,
        path: str | os.PathLike[str] | None = None,
        line: int | None = None,
        frame: int | None = None,
    ) -> None:
        self.reason = message
        self.path = None if path is None else os.fspath(path)
        self.line = line
        self.frame = frame
        where = []
        if self.path is not None:
            where.append(self.path + (f":{line}" if line is not None else ""))
        elif line is not None:
            where.append(f"line {line}")
        if frame is not None:
            where.append(f"frame {frame}")
        super().__init__(f"{', '.join(where)}: {message}" if where else message)

    def __reduce__(self) -> tuple[Any, ...]:
        # keyword-only arguments: pickle (process pools, Dask) must call the class with them
        return _rebuild, (type(self), self.args, self.__dict__)


class UnreachableTargetError(TuckerCodecError, ValueError):
    """A target that no file of the format can meet for this sequence: a size below what the
    coarsest file needs, or an error below what the format's 32-bit integers can resolve."""

    exit_code = EXIT_UNREACHABLE


class FormatVersionError(TuckerCodecError, ValueError):
    """An encode that needs a feature of a newer format version than the one asked for (the
    encoder's ``format_version``): lossless with format 1.2, say, or a sequence with UVs that
    a file of 1.4 cannot hold. Nothing is dropped to fit: the message names the option or the
    data at fault, the version it needs and what to change.

    Attributes:
        feature: what needs the newer version, as named to the caller (``"lossless"``,
            ``"the sequence's attributes"``).
        needs: the format version it needs (``"1.3"``).
        format_version: the version the encode is held to (``"1.2"``).
    """

    exit_code = EXIT_USAGE

    def __init__(self, message: str, *, feature: str, needs: str, format_version: str) -> None:
        self.feature = feature
        self.needs = needs
        self.format_version = format_version
        super().__init__(message)

    def __reduce__(self) -> tuple[Any, ...]:
        return _rebuild, (type(self), self.args, self.__dict__)


class InternalError(TuckerCodecError, RuntimeError):
    """A bug in tuckercodec: a state the code holds impossible, found by one of its own checks
    (say, a file that would not decode to the positions the encoder measured). Nothing the
    caller can change avoids it, so its message says so and asks for a report; no file is
    returned. A ``RuntimeError``, never a ``ValueError``: code that retries on a bad value
    (a search trying another step) must not swallow it."""

    exit_code = EXIT_INTERNAL

    def __str__(self) -> str:
        return f"{super().__str__()}. This is a bug in tuckercodec: please report it"


class DependencyError(TuckerCodecError, RuntimeError):
    """An optional dependency (such as matplotlib for plots) is not installed; the message names
    the extra to install."""

    exit_code = EXIT_MISSING_DEPENDENCY


class FormatError(TuckerCodecError, ValueError):
    """A compressed file that breaks a rule of ``spec/FORMAT.md``.

    Attributes:
        rule: the identifier of the rule the file breaks (``spec/FORMAT.md`` §11), such as
            ``"R09-trailing-bytes"``: stable, unlike the message, so test and compare this.
        field: the header field or section at fault (``None`` if none applies).
        offset: the byte offset in the file at fault (``None`` if none applies).
        path: the file, when it was read from a path (``None`` for bytes in memory).
    """

    exit_code = EXIT_CORRUPT

    def __init__(
        self,
        message: str,
        *,
        rule: str,
        field: str | None = None,
        offset: int | None = None,
        path: str | os.PathLike[str] | None = None,
    ) -> None:
        self.reason = message
        self.rule = rule
        self.field = field
        self.offset = offset
        self.path = None if path is None else os.fspath(path)
        super().__init__(message)

    def __str__(self) -> str:
        # built on demand: the file opener adds the path after the error was raised
        location = [] if self.field is None else [self.field]
        if self.offset is not None:
            location.append(f"offset {self.offset}")
        text = f"{', '.join(location)}: {self.reason}" if location else self.reason
        if self.path is not None:
            text = f"{self.path}: {text}"
        return f"{text} [{self.rule}]"

    def __reduce__(self) -> tuple[Any, ...]:
        return _rebuild, (type(self), self.args, self.__dict__)


class TruncatedFileError(FormatError):
    """The file ends before the data its preamble, header or section table promises."""


class ChecksumError(FormatError):
    """A CRC-32 in the file does not match the bytes it covers: the file was damaged."""


class UnsupportedVersionError(FormatError):
    """A format major version, critical flag, critical section or codec this decoder does not
    know. The file may be valid for a newer decoder."""


class LimitError(FormatError):
    """A declared size beyond this decoder's limits (checked before anything is allocated)."""


def _rebuild(
    cls: type[TuckerCodecError], args: tuple[Any, ...], state: dict[str, Any]
) -> TuckerCodecError:
    """Unpickle an error whose constructor takes keyword-only arguments."""
    error = cls.__new__(cls)
    Exception.__init__(error, *args)
    error.__dict__.update(state)
    return error
