"""Files with corrections (spec/FORMAT.md §6.9, format 1.3) made by hand, from the spec alone:
the exact reconstruction P of §8.1 written literally (B and W one binary64 operation at a time,
in its order, the weights rounded to integers in units of 2^e and S an exact integer product),
the correction integers e that move P onto chosen targets in each domain, and a RESD
section coding them (64-bit zigzag, byte planes, zstd, chunks, predict 1's differences). Tests
hold the JavaScript decoder to these files without needing the reference encoder, and edit them
to break one rule of §6.9 at a time."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
import zstandard

from tests.support.compressed import Parts
from tuckercodec import Decoder
from tuckercodec.format.container import pack_container

FLAG_CORRECTIONS = 1 << 2
MINOR = 3
MASK64 = (1 << 64) - 1


def _u1_integers(decoder: Decoder, number: int) -> tuple[np.ndarray, np.ndarray]:
    """Segment ``number``'s U1 integers q1 (K x i, int64) and steps (i, float64): §8.1 multiplies
    them. (Read through the decoder's own U1 reader: a file without corrections keeps none.)"""
    segment = decoder.segments[number]
    i = segment.ranks[0]
    section_id = "U1" if segment.basis == "shared" or not decoder.segmented else f"U1.{number}"
    quantized = decoder._decode_u1(section_id)
    return quantized.q[:, :i].astype(np.int64), quantized.steps[:i].astype(np.float64)


def _weights(decoder: Decoder, number: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """y[t, a, x] = step1[a]·W[a, x] of §8.1 for every frame t of a segment (B and W summed in
    §8.1's order, one binary64 operation at a time), with q1 and CENT."""
    factors = decoder.segment_factors(number)
    u3, core, cent, u2 = factors.u3, factors.core, factors.centroids, factors.u2
    q1, steps1 = _u1_integers(decoder, number)
    i, k = core.shape[0], core.shape[2]
    with np.errstate(over="ignore", invalid="ignore"):
        B = np.empty((i, 3, k))
        for x in range(3):
            B[:, x, :] = (core[:, 0, :] * u2[x, 0] + core[:, 1, :] * u2[x, 1]) + core[:, 2, :] * u2[
                x, 2
            ]
        y = np.empty((u3.shape[0], i, 3))
        for t in range(u3.shape[0]):
            W = B[:, :, 0] * u3[t, 0]
            for b in range(1, k):
                W = W + B[:, :, b] * u3[t, b]
            y[t] = steps1[:, None] * W
    return y, q1, cent


def exponents_of(data: bytes, extra: int = 0) -> list[int]:
    """Each segment's e of §8.1: the smallest with R·max|w| <= 2^53 (R = max_v Σ_a |q1[v, a]|),
    found by trying (the rounding of w can need one more), plus ``extra``."""
    decoder = Decoder(data)
    out = []
    for number in range(len(decoder.segments)):
        y, q1, _ = _weights(decoder, number)
        R = int(np.abs(q1).sum(axis=1).max())
        e = -1022
        largest = float(np.abs(y).max())
        if largest > 0 and R > 0:
            e = max(-1022, int(np.floor(np.log2(R * largest))) - 54)
        while R * int(np.abs(np.rint(y * 2.0**-e)).max()) > 2**53:
            e += 1
        out.append(e + extra)
    return out


def exact_reconstruction(data: bytes, exponents: list[int] | None = None) -> list[np.ndarray]:
    """P of §8.1 for every segment (each F_s x K x 3) with the exponents given (by default
    exponents_of's), literally: w = round(y·2^-e) (ties to even), S = q1·w in exact integers
    (Python's), P = S·2^e + CENT, one multiplication and one addition."""
    decoder = Decoder(data)
    exponents = exponents_of(data) if exponents is None else exponents
    out = []
    for number, e in enumerate(exponents):
        y, q1, cent = _weights(decoder, number)
        w = np.rint(y * 2.0**-e)
        frames = np.empty((y.shape[0], q1.shape[0], 3))
        q = q1.astype(object)
        for t in range(y.shape[0]):
            S = np.array(q @ w[t].astype(np.int64).astype(object), dtype=np.float64)  # exact
            frames[t] = S * 2.0**e + cent[t]
        out.append(frames)
    return out


def ordered(values: np.ndarray, bits: int) -> np.ndarray:
    """The ordered integers (§6.9) of binary32 (bits 32) or binary64 values, flattened, as
    int64: w for a bit pattern w >= 0, else -2^(n-1) - w - 1, which is w XOR (2^(n-1) - 1)."""
    signed = np.ascontiguousarray(values, dtype=np.float32 if bits == 32 else np.float64).view(
        np.int32 if bits == 32 else np.int64
    )
    flat: np.ndarray = signed.reshape(-1).astype(np.int64)
    return np.where(flat >= 0, flat, flat ^ ((1 << (bits - 1)) - 1))


def from_ordered(integers: np.ndarray, bits: int) -> np.ndarray:
    """The binary32 or binary64 values of ordered integers (the map is its own inverse)."""
    o = np.asarray(integers, dtype=np.int64)
    signed = np.where(o >= 0, o, o ^ ((1 << (bits - 1)) - 1))
    return signed.astype(np.int32 if bits == 32 else np.int64).view(
        np.float32 if bits == 32 else np.float64
    )


def wrap(value: int) -> int:
    """A Python int as a signed 64-bit value (mod 2^64)."""
    value &= MASK64
    return value - (1 << 64) if value >= 1 << 63 else value


@dataclass
class Corrections:
    """One segment's corrections: its integers e (F_s x K x 3, int64) and how to store them."""

    e: np.ndarray
    domain: str
    step: float = 0.0
    scale: int = 0  # the places or digits of a decimal domain
    predict: int = 0
    chunk_frames: int = 1 << 30
    extra_planes: int = 0  # more planes than needed (a decoder accepts them)
    exponent: int | None = None  # §8.1's e; by default exponents_of's

    def section(self, section_id: str, frames: int) -> tuple[dict[str, Any], bytes]:
        """The RESD section's entry and payload (§6.9). numpy's int64 arithmetic wraps mod
        2^64, as predict 1's differences do."""
        L = self.chunk_frames
        flat = self.e.reshape(frames, -1).astype(np.int64)
        chunks, payload = [], b""
        for start in range(0, frames, L):
            block = flat[start : start + L].copy()
            if self.predict == 1:
                with np.errstate(over="ignore"):
                    block[1:] = block[1:] - flat[start : start + L][:-1]
            s = block.reshape(-1)
            u = (s.view(np.uint64) << np.uint64(1)) ^ (s >> 63).view(np.uint64)  # zigzag
            needed = (int(u.max()).bit_length() + 7) // 8 if u.size else 1
            planes = min(max(1, needed) + self.extra_planes, 8)
            raw = b"".join(
                ((u >> np.uint64(8 * p)) & np.uint64(0xFF)).astype(np.uint8).tobytes()
                for p in range(planes)
            )
            frame = zstandard.ZstdCompressor(level=3, write_content_size=True).compress(raw)
            chunks.append([planes, len(frame)])
            payload += frame
        entry: dict[str, Any] = {
            "id": section_id,
            "critical": True,
            "codec": "residual",
            "domain": self.domain,
            "exponent": self.exponent,
            "predict": self.predict,
            "chunk_frames": L,
            "chunks": chunks,
        }
        if self.domain == "grid":
            entry["step"] = self.step
        elif self.domain == "decimal-places":
            entry["places"] = self.scale
        elif self.domain in ("decimal-digits", "decimal-digits-float32"):
            entry["digits"] = self.scale
        return entry, payload


def with_corrections(
    data: bytes,
    corrections: list[Corrections],
    *,
    error: dict[str, Any] | None = None,
    edit: Callable[[Parts], object] | None = None,
) -> bytes:
    """``data`` (a file of 1.0 to 1.2) with a RESD section (RESD.s per segment) appended, flag
    bit 2 and minor version 3; ``edit(parts)``, if given, changes the parts before they are
    packed (to break a rule)."""
    parts = Parts(data)
    segments = parts.header.get("segments")
    if segments is None:
        sizes = [int(parts.header["frames"])]
        ids = ["RESD"]
    else:
        sizes = [int(s["frames"]) for s in segments]
        ids = [f"RESD.{s}" for s in range(len(segments))]
    exponents = exponents_of(data)
    for section_id, frames, item, e in zip(ids, sizes, corrections, exponents, strict=False):
        if item.exponent is None:
            item.exponent = e
        parts.sections.append(item.section(section_id, frames))
    if error is not None:
        parts.header["error"] = {**parts.header.get("error", {}), **error}
    parts.flags |= FLAG_CORRECTIONS
    if edit is not None:
        edit(parts)
    return pack_container(parts.header, parts.sections, flags=parts.flags, minor=MINOR)


def grid_targets(P: np.ndarray, step: float, rng: np.random.Generator) -> tuple[np.ndarray, Any]:
    """Integers e moving P onto a grid near P + noise, and the decoded positions they give
    (P + step·e, one multiplication and one addition)."""
    noise = rng.normal(scale=20 * step, size=P.shape)
    e = np.rint(noise / step).astype(np.int64)
    e.reshape(-1)[:3] = [0, 2**53, -(2**53)]  # the ends of the range §6.9 allows
    decoded = P + step * e.astype(np.float64)
    return e, decoded


def float_targets(
    P: np.ndarray, bits: int, rng: np.random.Generator | None
) -> tuple[np.ndarray, np.ndarray]:
    """Integers e moving P onto chosen binary32 or binary64 targets: with ``rng``, values near
    P and some far off (signs crossed, zeros of both signs, the largest finite values), so that
    e needs many planes and, in binary64, wraps; without, ``P`` itself holds the targets (an
    original, for a lossless file). Returns (e, targets as float64)."""
    dtype = np.float32 if bits == 32 else np.float64
    if rng is None:
        raise ValueError("use lossless_targets for an original")
    targets = (P + rng.normal(scale=1e-3, size=P.shape)).astype(dtype)
    flat: np.ndarray = targets.reshape(-1)
    special = [-flat[0], 0.0, -0.0, np.finfo(dtype).max, -np.finfo(dtype).max, np.finfo(dtype).tiny]
    flat[: len(special)] = np.array(special, dtype=dtype)[: flat.size]
    flat[len(special) :: 17] *= np.asarray(-1, dtype=dtype)
    return lossless_targets(P, targets), targets.astype(np.float64)


def lossless_targets(P: np.ndarray, original: np.ndarray) -> np.ndarray:
    """Integers e that make P decode to ``original``'s bits: domain float32 for a float32
    original, float64 for a float64 one."""
    bits = 32 if original.dtype == np.float32 else 64
    with np.errstate(over="ignore"):
        base = ordered(P.astype(original.dtype), bits)  # the binary32 nearest P, or P itself
    with np.errstate(over="ignore"):
        return (ordered(original, bits).reshape(-1) - base.reshape(-1)).reshape(P.shape)


def spec_decode(P: np.ndarray, c: Corrections) -> np.ndarray:
    """The decoded positions of §6.9 for P and c (valid values only)."""
    if c.domain == "grid":
        return P + c.step * c.e.astype(np.float64)
    bits = 32 if c.domain == "float32" else 64
    with np.errstate(over="ignore"):
        base = ordered(P.astype(np.float32 if bits == 32 else np.float64), bits).reshape(-1)
        o = base + c.e.reshape(-1).astype(np.int64)  # int64: wraps mod 2^64
    return from_ordered(o, bits).astype(np.float64).reshape(P.shape)
