"""The exception classes: every one exported, each with its exit code, and each surviving a
pickle round trip (process pools and Dask workers send errors back pickled)."""

from __future__ import annotations

import inspect
import pickle

import pytest

import tuckercodec
from tuckercodec import errors


def _error_classes() -> list[type[tuckercodec.TuckerCodecError]]:
    return [
        cls
        for _, cls in inspect.getmembers(errors, inspect.isclass)
        if issubclass(cls, tuckercodec.TuckerCodecError) and cls.__module__ == errors.__name__
    ]


def test_every_error_class_is_exported():
    classes = _error_classes()
    assert len(classes) == 11
    for cls in classes:
        assert cls.__name__ in tuckercodec.__all__
        assert getattr(tuckercodec, cls.__name__) is cls


@pytest.mark.parametrize(
    ("cls", "code"),
    [
        (tuckercodec.TuckerCodecError, 1),
        (tuckercodec.InputError, 4),
        (tuckercodec.FormatError, 3),
        (tuckercodec.ChecksumError, 3),
        (tuckercodec.UnreachableTargetError, 5),
        (tuckercodec.FormatVersionError, 2),
        (tuckercodec.DependencyError, 6),
        (tuckercodec.InternalError, 70),
    ],
)
def test_each_class_carries_its_exit_code(cls, code):
    assert cls.exit_code == code


def test_a_format_error_names_path_field_offset_and_rule():
    error = tuckercodec.TruncatedFileError(
        "it was cut short", rule="R10-file-truncated", field="header", offset=40
    )
    assert str(error) == "header, offset 40: it was cut short [R10-file-truncated]"
    error.path = "cut.tkc"  # set by the file opener after the error was raised
    assert str(error) == "cut.tkc: header, offset 40: it was cut short [R10-file-truncated]"
    assert (error.rule, error.field, error.offset, error.reason) == (
        "R10-file-truncated",
        "header",
        40,
        "it was cut short",
    )


@pytest.mark.parametrize(
    "error",
    [
        tuckercodec.LimitError("too big", rule="R21-header-limit", field="header.vertices"),
        tuckercodec.FormatError("bad", rule="R12-header-not-map", path="x.tkc", offset=3),
        tuckercodec.InputError("not a number", path="a.obj", line=7, frame=2),
        tuckercodec.UnreachableTargetError("no file fits 0.1 bpfv"),
        tuckercodec.InternalError("the corrections read back differently"),
        tuckercodec.FormatVersionError(
            "lossless needs format 1.3", feature="lossless", needs="1.3", format_version="1.2"
        ),
    ],
    ids=lambda error: type(error).__name__,
)
def test_errors_survive_a_pickle_round_trip(error):
    copy = pickle.loads(pickle.dumps(error))
    assert type(copy) is type(error)
    assert str(copy) == str(error)
    assert vars(copy) == vars(error)
