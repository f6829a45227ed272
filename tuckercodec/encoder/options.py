"""Everything an encode is asked to do, in one frozen, JSON-safe object.

:class:`EncodeOptions` is the encoder's whole configuration, checked once when it is made:
the mode (a target KG error, fixed ranks or a target size), how ranks are selected, the zstd
level, when and how to segment, where a segmented encode's passes run, and the newest format
version the file may be. The one-shot
functions (:func:`tuckercodec.encode`, :func:`tuckercodec.encode_file` and the others) take it
whole, as keywords named as its fields, or both, all through :func:`resolve_options`; they, the
zarr codecs, ``batch`` and the command line hand it to :class:`~tuckercodec.encoder.Encoder`.
:meth:`EncodeOptions.to_config` and :meth:`EncodeOptions.from_config` carry it as a plain dict
(JSON's types only), for a task sent to a worker or a codec's stored configuration.
"""

from __future__ import annotations

import contextlib
import math
import re
from dataclasses import asdict, dataclass, fields, replace
from typing import Any, Literal

import numpy as np

from ..decomposition.analysis import DEFAULT_SELECTION, SELECTIONS, Selection
from ..format import streams
from ..format.residual import CORRECTIONS_MINOR
from ..format.segments import BASIS_OWN, BASIS_SHARED, SEGMENTED_MINOR
from .versions import Features, parse_format_version

Mode = Literal["kg", "ranks", "bpfv", "max-error", "lossless"]

#: The KG error (percent) met when no mode is given.
DEFAULT_TARGET_KG = 0.1
#: The bases of a segmented file: one U1 shared by every segment, or one per segment.
BASES = (BASIS_SHARED, BASIS_OWN)
#: The zstd levels a section may be compressed at.
LEVELS = range(1, 23)


@dataclass(frozen=True)
class EncodeOptions:
    """What to encode for, and how.

    Attributes:
        target_kg: the largest KG error allowed for the decoded sequence, in percent (the
            default mode, :data:`DEFAULT_TARGET_KG`, when no mode is given).
        ranks: fixed ranks (i, k); quantization then adds at most about 5 % to the KG error of
            the truncation.
        target_bpfv: the largest whole-file size in bits per frame per vertex; the smallest KG
            error that fits is chosen, down to a KG error of 1e-4.
        select: ``"exact"`` chooses ranks by the exact error table, ``"bound"`` by the seed
            paper's bound alone (an encode in one piece only).
        level: zstd level of the sections (1-22).
        segment_frames: cut the frames into segments of this many, each its own decomposition
            (format 1.1). Without it, segments are made only when encoding the sequence whole
            would take more than ``max_memory``.
        max_memory: the memory the encode may use, in bytes (default: half the machine's).
        basis: with segments, ``"shared"`` (one U1 for all, the default) or ``"own"``.
        jobs: with segments, run the passes on this many worker processes (extra ``dask``).
        scheduler: with segments, run the passes on the Dask cluster of this scheduler.
        max_error: a bound on every decoded vertex's Euclidean distance from the input: a
            length in the sequence's units, or a string ``"P%"``, P percent of the bounding-box
            diagonal of the whole sequence. Alone (mode ``"max-error"``), with ``target_kg``
            (both hold) or with ``ranks``; not with ``target_bpfv``. Files that need
            corrections are format 1.3 (spec §6.9).
        lossless: decode to the input's values bit for bit (mode ``"lossless"``, format 1.3),
            alone.
        face_order: ``"auto"`` (the default) keeps the faces in the order given when the
            sequence has data per corner or per face (UVs, materials), so that they line up
            with the original topology, and lets the connectivity coder reorder them
            otherwise; ``"given"`` always keeps it, ``"walk"`` never (format 1.5, §6.10).
        field_targets: the error target of each animated field, by name: ``"rel:P"`` (a
            relative error of P percent, Karni-Gotsman's measure generalised to the field's
            components), ``"max:E"`` (no value farther than E, in the field's units) or
            ``"lossless"``; a mapping, or (name, target) pairs.
        field_target: the target of every field :attr:`field_targets` does not name (default:
            ``"lossless"`` in mode lossless, else ``"rel:P"`` with P the positions' KG target).
        attachments: keep the sequence's attributes, face sets and fields (the default); False
            writes the positions and faces alone, as format 1.4 did.
        format_version: the newest format version the file may be, ``"1.0"`` to ``"1.6"``
            (default ``None``: the newest, 1.6), for decoders that read only up to it. The
            encoder then uses no feature of a later version (:mod:`.versions`): below 1.6 no
            adaptive coding (§6.14), below 1.2 neither faces-traverse nor predictors 2 and 3.
            The file says the version of the newest feature it uses, as without the option. What
            needs a later version raises :class:`~tuckercodec.errors.FormatVersionError` naming
            it and the version it needs, never dropped: ``segment_frames`` (1.1), ``max_error``
            and ``lossless`` (1.3) here; with the sequence, a whole encode beyond
            ``max_memory`` (segments, 1.1), time codes, a unit or an up axis (1.4), attributes,
            face sets or fields unless ``attachments`` is False (1.5). ``face_order="given"``
            below 1.5 keeps the faces as given without §6.10's ORDER (faces-delta).

    At most one of ``target_kg``, ``ranks`` and ``target_bpfv``; ``jobs`` or ``scheduler``, not
    both. A bad value raises ``ValueError`` naming it. Whether ranks fit the sequence is known
    only with the sequence: the encoder checks that.
    """

    target_kg: float | None = None
    ranks: tuple[int, int] | None = None
    target_bpfv: float | None = None
    select: Selection = DEFAULT_SELECTION
    level: int = streams.DEFAULT_LEVEL
    segment_frames: int | None = None
    max_memory: int | None = None
    basis: str = BASIS_SHARED
    jobs: int | None = None
    scheduler: str | None = None
    max_error: float | str | None = None
    lossless: bool = False
    face_order: str = "auto"
    field_targets: Any = ()
    field_target: str | None = None
    attachments: bool = True
    format_version: str | None = None

    def __post_init__(self) -> None:
        _refuse_two_modes(self.target_kg, self.ranks, self.target_bpfv)
        if not isinstance(self.lossless, (bool, np.bool_)):
            raise ValueError(f"lossless must be true or false, got {self.lossless!r}")
        object.__setattr__(self, "lossless", bool(self.lossless))
        if self.max_error is not None:
            object.__setattr__(self, "max_error", parse_max_error(self.max_error))
            if self.target_bpfv is not None:
                raise ValueError(
                    "give max_error or target_bpfv, not both: a size target cannot also promise "
                    "a bound on every vertex"
                )
        if self.lossless:
            given = [
                name
                for name in ("target_kg", "ranks", "target_bpfv", "max_error")
                if getattr(self, name) is not None
            ]
            if given:
                raise ValueError(f"lossless stands alone: give it without {' and '.join(given)}")
        for name in ("target_kg", "target_bpfv"):
            value = getattr(self, name)
            if value is not None:
                object.__setattr__(self, name, _positive_number(name, value))
        if self.ranks is not None:
            object.__setattr__(self, "ranks", _two_ranks(self.ranks))
        if self.select not in SELECTIONS:
            raise ValueError(f"select must be 'exact' or 'bound', got {self.select!r}")
        if self.basis not in BASES:
            raise ValueError(f"basis must be one of {', '.join(BASES)}, got {self.basis!r}")
        if not (_is_integer(self.level) and int(self.level) in LEVELS):
            raise ValueError(f"level must be an integer from 1 to 22, got {self.level!r}")
        object.__setattr__(self, "level", int(self.level))
        for name in ("segment_frames", "max_memory", "jobs"):
            value = getattr(self, name)
            if value is not None:
                if not (_is_integer(value) and int(value) >= 1):
                    raise ValueError(f"{name} must be an integer >= 1, got {value!r}")
                object.__setattr__(self, name, int(value))
        if self.scheduler is not None and not isinstance(self.scheduler, str):
            raise ValueError(f"scheduler must be an address, got {self.scheduler!r}")
        if self.jobs is not None and self.scheduler is not None:
            raise ValueError("give jobs or scheduler, not both")
        if self.face_order not in FACE_ORDERS:
            raise ValueError(
                f"face_order must be one of {', '.join(FACE_ORDERS)}, got {self.face_order!r}"
            )
        pairs = (
            self.field_targets.items()
            if isinstance(self.field_targets, dict)
            else self.field_targets
        )
        checked = []
        for pair in pairs:
            is_pair = isinstance(pair, (tuple, list)) and len(pair) == 2
            if not (is_pair and isinstance(pair[0], str)):
                raise ValueError(f"field_targets holds (name, target) pairs, got {pair!r}")
            checked.append((pair[0], parse_field_target(pair[1], pair[0])))
        object.__setattr__(self, "field_targets", tuple(sorted(checked)))
        if self.field_target is not None:
            object.__setattr__(
                self, "field_target", parse_field_target(self.field_target, "every field")
            )
        if not isinstance(self.attachments, (bool, np.bool_)):
            raise ValueError(f"attachments must be true or false, got {self.attachments!r}")
        object.__setattr__(self, "attachments", bool(self.attachments))
        if self.format_version is not None:
            object.__setattr__(self, "format_version", parse_format_version(self.format_version))
        self._refuse_newer_options()

    def _refuse_newer_options(self) -> None:
        """Refuse an option that needs a newer format than :attr:`format_version` (those the
        sequence decides are checked by the encoder)."""
        features = self.features
        if self.segment_frames is not None:
            features.require(
                SEGMENTED_MINOR, "segment_frames", "segmented files, spec §6.7", "leave it out"
            )
        for name in ("lossless", "max_error"):
            if getattr(self, name) not in (None, False):
                features.require(
                    CORRECTIONS_MINOR, name, "corrections, spec §6.9", f"leave {name} out"
                )

    @property
    def features(self) -> Features:
        """The format features the file may use (:attr:`format_version`'s)."""
        return Features.of(self.format_version)

    def target_of_field(self, name: str) -> str:
        """The error target of the field ``name``: its own, :attr:`field_target`, or the
        default that follows the positions' mode."""
        own = dict(self.field_targets).get(name)
        if own is not None:
            return own
        if self.field_target is not None:
            return self.field_target
        return "lossless" if self.lossless else f"rel:{self.kg_target!r}"

    @property
    def mode(self) -> Mode:
        """``"lossless"``, ``"ranks"``, ``"bpfv"``, ``"max-error"`` (a bound alone) or ``"kg"``
        (the default, with or without a bound)."""
        if self.lossless:
            return "lossless"
        if self.max_error is not None and self.target_kg is None and self.ranks is None:
            return "max-error"
        if self.ranks is not None:
            return "ranks"
        return "bpfv" if self.target_bpfv is not None else "kg"

    @property
    def kg_target(self) -> float:
        """The KG target of mode ``"kg"``: the one given, or :data:`DEFAULT_TARGET_KG`."""
        return DEFAULT_TARGET_KG if self.target_kg is None else self.target_kg

    @property
    def target(self) -> float | None:
        """What the mode aims at: :attr:`kg_target` for ``"kg"``, ``target_bpfv`` for
        ``"bpfv"``, nothing for fixed ranks."""
        targets: dict[str, float | None] = {"kg": self.kg_target, "bpfv": self.target_bpfv}
        return targets.get(self.mode)

    @property
    def corrections(self) -> bool:
        """Whether the encode may add corrections (§6.9): a bound on every vertex, or lossless."""
        return self.lossless or self.max_error is not None

    def max_error_length(self, diagonal: float) -> float | None:
        """:attr:`max_error` as a length, given the sequence's bounding-box diagonal."""
        if self.max_error is None:
            return None
        if isinstance(self.max_error, str):
            return float(self.max_error[:-1]) / 100.0 * diagonal
        return float(self.max_error)

    def to_config(self) -> dict[str, Any]:
        """Every field, as JSON's types (ranks as a list)."""
        config = asdict(self)
        if self.ranks is not None:
            config["ranks"] = list(self.ranks)
        config["field_targets"] = dict(self.field_targets)
        return config

    @classmethod
    def from_config(cls, config: dict[str, Any]) -> EncodeOptions:
        """The options of a :meth:`to_config` dict (missing fields take their defaults);
        ``ValueError`` naming a field it does not know."""
        unknown = sorted(set(config) - set(FIELDS))
        if unknown:
            raise ValueError(f"unknown encode options: {', '.join(map(str, unknown))}")
        values = dict(config)
        if isinstance(values.get("ranks"), list):
            values["ranks"] = tuple(values["ranks"])
        return cls(**values)


#: How the faces are ordered in the file (:attr:`EncodeOptions.face_order`).
FACE_ORDERS = ("auto", "given", "walk")

_FIELD_TARGET = re.compile(r"(rel|max):([0-9.eE+-]+)")


def parse_field_target(value: object, name: str) -> str:
    """A field's target, ``"rel:P"``, ``"max:E"`` or ``"lossless"``, checked (P and E
    positive numbers); ValueError naming the field otherwise."""
    text = value.strip() if isinstance(value, str) else value
    if text == "lossless":
        return "lossless"
    match = _FIELD_TARGET.fullmatch(text) if isinstance(text, str) else None
    number = None
    if match is not None:
        with contextlib.suppress(ValueError):
            number = float(match.group(2))
    if match is None or number is None or not (math.isfinite(number) and number > 0):
        raise ValueError(
            f"the target of {name} must be 'rel:P' (percent), 'max:E' (in the field's units) "
            f"or 'lossless', got {value!r}"
        )
    return f"{match.group(1)}:{number!r}"


#: The names of :class:`EncodeOptions`' fields: the keywords every front door takes.
FIELDS = tuple(field.name for field in fields(EncodeOptions))


def _refuse_two_modes(target_kg: object, ranks: object, target_bpfv: object) -> None:
    given = [
        name
        for name, value in (
            ("target_kg", target_kg),
            ("ranks", ranks),
            ("target_bpfv", target_bpfv),
        )
        if value is not None
    ]
    if len(given) > 1:
        raise ValueError(f"give one of target_kg, ranks and target_bpfv, not {' and '.join(given)}")


def parse_max_error(value: object) -> float | str:
    """A bound on every vertex: a positive finite length, or ``"P%"`` of the bounding-box
    diagonal (kept as the string, normalised, so that the options stay JSON-safe)."""
    if isinstance(value, str):
        text = value.strip()
        number = text[:-1].strip() if text.endswith("%") else text
        try:
            amount = float(number)
        except ValueError:
            amount = math.nan
        if not (math.isfinite(amount) and amount > 0):
            raise ValueError(
                f"max_error must be a positive length or a percentage such as '0.1%', got {value!r}"
            )
        return f"{amount!r}%" if text.endswith("%") else amount
    return _positive_number("max_error", value)


def _positive_number(name: str, value: object) -> float:
    if not (
        isinstance(value, (int, float, np.integer, np.floating))
        and not isinstance(value, bool)
        and math.isfinite(value)
        and value > 0
    ):
        raise ValueError(f"{name} must be a positive finite number, got {value!r}")
    return float(value)


def _is_integer(value: object) -> bool:
    """An int or a float without a fraction (2.0, as JSON may carry it), never a bool."""
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        return False
    return math.isfinite(value) and float(value) == int(value)


def _two_ranks(ranks: object) -> tuple[int, int]:
    """(i, k) as ints; the range is checked against the sequence by the encoder."""
    pair: tuple[Any, ...] = tuple(ranks) if isinstance(ranks, (tuple, list, np.ndarray)) else ()
    if not (len(pair) == 2 and all(_is_integer(r) and int(r) >= 1 for r in pair)):
        raise ValueError(f"ranks must be two integers, each at least 1, got {ranks!r}")
    return int(pair[0]), int(pair[1])


def resolve_options(options: EncodeOptions | None = None, /, **fields: Any) -> EncodeOptions:
    """The options of a front door (:func:`~tuckercodec.encode`, :func:`~tuckercodec.encode_file`
    and the others): ``options`` (default: every field at its default) with ``fields``, keywords
    named as :class:`EncodeOptions`' fields, put over it as :func:`dataclasses.replace` does. The
    result is checked as a whole, so a keyword that names another mode than ``options``' is a
    ``ValueError`` naming both, as it would be in one :class:`EncodeOptions`.

    Raises:
        TypeError: ``options`` that is not an :class:`EncodeOptions`, or a keyword that is not
            one of its fields (named).
        ValueError: a value :class:`EncodeOptions` refuses.
    """
    if options is None:
        options = EncodeOptions()
    elif not isinstance(options, EncodeOptions):
        raise TypeError(f"options must be EncodeOptions, got {type(options).__name__}")
    unknown = sorted(set(fields) - set(FIELDS))
    if unknown:
        raise TypeError(
            f"unexpected keyword argument {unknown[0]!r}: an encode takes the fields of "
            f"EncodeOptions ({', '.join(FIELDS)})"
        )
    return replace(options, **fields) if fields else options
