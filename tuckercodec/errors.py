"""The exception hierarchy of tuckercodec.

Every error the library raises on purpose derives from :class:`TuckerCodecError`, so a caller can
catch one class. Misuse of the API (a wrong argument type or an impossible parameter) raises the
plain ``TypeError``/``ValueError`` as usual; :class:`InputError` is also a ``ValueError`` so that
code written against generic exceptions keeps working.
"""

from __future__ import annotations

from pathlib import Path


class TuckerCodecError(Exception):
    """Base class of every error raised by tuckercodec."""


class InputError(TuckerCodecError, ValueError):
    """A mesh sequence that cannot be read or used: names the file, frame and line at fault.

    Attributes are ``None`` where they do not apply.
    """

    def __init__(
        self,
        message: str,
        *,
        path: str | Path | None = None,
        line: int | None = None,
        frame: int | None = None,
    ) -> None:
        self.reason = message
        self.path = None if path is None else str(path)
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


class DependencyError(TuckerCodecError, RuntimeError):
    """An optional dependency (such as matplotlib for plots) is not installed."""


class FormatError(TuckerCodecError, ValueError):
    """A compressed file that breaks a rule of ``spec/FORMAT.md``: names the field or offset.

    Attributes:
        field: the header field or section at fault (``None`` if none applies).
        offset: the byte offset in the file at fault (``None`` if none applies).
    """

    def __init__(self, message: str, *, field: str | None = None, offset: int | None = None) -> None:
        self.reason = message
        self.field = field
        self.offset = offset
        where = []
        if field is not None:
            where.append(field)
        if offset is not None:
            where.append(f"offset {offset}")
        super().__init__(f"{', '.join(where)}: {message}" if where else message)


class TruncatedFileError(FormatError):
    """The file ends before the data its preamble, header or section table promises."""


class ChecksumError(FormatError):
    """A CRC-32 in the file does not match the bytes it covers: the file was damaged."""


class UnsupportedVersionError(FormatError):
    """A format major version, critical flag, critical section or codec this decoder does not
    know. The file may be valid for a newer decoder."""


class LimitError(FormatError):
    """A declared size beyond this decoder's limits (checked before anything is allocated)."""
