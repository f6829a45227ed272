"""glTF animation samplers and node transforms, evaluated at given times as the spec defines.

* ``LINEAR``: linear interpolation between the two keyframes around a time, spherical linear
  (slerp, the shorter way) for rotations; ``STEP``: the value of the last keyframe at or before
  the time; ``CUBICSPLINE``: the spec's Hermite spline over (in-tangent, value, out-tangent)
  triples, the tangents scaled by the keyframe interval (rotations normalized afterwards).
* Before the first keyframe a sampler holds its first value, after the last its last value.
* At a keyframe's own time every interpolation returns that keyframe's value exactly, so
  sampling at the keyframes reads back what was written.
* A node's local transform is its ``matrix``, or translation · rotation · scale from its static
  fields overridden by the animated channels; a mesh's world transform is the product along its
  parents.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from .accessors import read_accessor
from .container import Document

INTERPOLATIONS = ("LINEAR", "STEP", "CUBICSPLINE")
PATH_WIDTHS = {"translation": 3, "rotation": 4, "scale": 3}


@dataclass
class Sampler:
    """An animation sampler read from the file: keyframe times (n,), values (n, m) or, for
    CUBICSPLINE, (n, 3, m) (in-tangent, value, out-tangent)."""

    times: np.ndarray
    values: np.ndarray
    interpolation: str
    rotation: bool = False

    def at(self, times: np.ndarray) -> np.ndarray:
        """The sampler's value at each of ``times``: (len(times), m)."""
        keys = self.times
        if len(keys) == 1:
            value = self.values[0, 1] if self.interpolation == "CUBICSPLINE" else self.values[0]
            return np.repeat(value[None], len(times), axis=0)
        after = np.searchsorted(keys, times, side="right") - 1
        if self.interpolation == "STEP":
            return self.values[np.clip(after, 0, len(keys) - 1)]
        index = np.clip(after, 0, len(keys) - 2)
        span = keys[index + 1] - keys[index]
        s = np.clip((times - keys[index]) / span, 0.0, 1.0)[:, None]
        if self.interpolation == "LINEAR":
            a, b = self.values[index], self.values[index + 1]
            if self.rotation:
                return _slerp(a, b, s)
            return (1.0 - s) * a + s * b
        s2, s3 = s * s, s * s * s
        v0, out0 = self.values[index, 1], self.values[index, 2]
        v1, in1 = self.values[index + 1, 1], self.values[index + 1, 0]
        span = span[:, None]
        result = (
            (2 * s3 - 3 * s2 + 1) * v0
            + span * (s3 - 2 * s2 + s) * out0
            + (-2 * s3 + 3 * s2) * v1
            + span * (s3 - s2) * in1
        )
        return _normalized(result) if self.rotation else result


def _normalized(q: np.ndarray) -> np.ndarray:
    norm = np.linalg.norm(q, axis=1, keepdims=True)
    return q / np.where(norm > 0, norm, 1.0)


def _slerp(a: np.ndarray, b: np.ndarray, s: np.ndarray) -> np.ndarray:
    """Spherical linear interpolation of unit quaternions (x, y, z, w), the shorter way."""
    a, b = _normalized(a), _normalized(b)
    dot = np.sum(a * b, axis=1, keepdims=True)
    b = np.where(dot < 0, -b, b)
    dot = np.abs(dot)
    close = dot > 0.9995  # nearly equal: linear interpolation is exact enough and stable
    angle = np.arccos(np.clip(dot, -1.0, 1.0))
    sine = np.where(close, 1.0, np.sin(angle))
    wa = np.where(close, 1.0 - s, np.sin((1.0 - s) * angle) / sine)
    wb = np.where(close, s, np.sin(s * angle) / sine)
    result = wa * a + wb * b
    return np.where(s == 0, a, np.where(s == 1, b, _normalized(result)))


def read_sampler(
    doc: Document, animation: int, index: Any, width: int, what: str, *, rotation: bool = False
) -> Sampler:
    """Sampler ``index`` of animation ``animation``, its outputs ``width`` numbers per key."""
    where = f"animations[{animation}].samplers[{index}]"
    samplers = doc.item("animations", animation, what).get("samplers")
    if (
        not isinstance(samplers, list)
        or not isinstance(index, int)
        or not (0 <= index < len(samplers) and isinstance(samplers[index], dict))
    ):
        raise doc.fail(f"{what} refers to a sampler {index!r} that animations[{animation}] lacks")
    sampler = samplers[index]
    interpolation = sampler.get("interpolation", "LINEAR")
    if interpolation not in INTERPOLATIONS:
        raise doc.fail(f"{where}: interpolation {interpolation!r} is not glTF's")
    times = read_accessor(doc, sampler.get("input"), f"{where} input", width=1)[:, 0]
    if (np.diff(times) <= 0).any() or times[0] < 0:
        raise doc.fail(f"{where}: keyframe times must be >= 0 and increase strictly")
    # float32, as viewers keep animation values (three.js de-normalizes integers into a
    # Float32Array): a normalized weight is then exactly what they interpolate from
    flat = read_accessor(doc, sampler.get("output"), f"{where} output").astype(np.float32)
    flat = flat.astype(np.float64)
    per_key = 3 if interpolation == "CUBICSPLINE" else 1
    total = flat.size
    if total != len(times) * per_key * width:
        raise doc.fail(
            f"{where}: {total} output numbers for {len(times)} keyframes of {width} "
            f"({interpolation}{', with tangents' if per_key == 3 else ''})"
        )
    values = flat.reshape(len(times), per_key, width) if per_key == 3 else flat.reshape(-1, width)
    return Sampler(times, values, interpolation, rotation=rotation)


def node_matrix(
    doc: Document, node_index: int, times: np.ndarray, channels: dict[str, Sampler]
) -> np.ndarray:
    """Node ``node_index``'s local transform at each time, (n, 4, 4); ``channels`` maps
    "translation"/"rotation"/"scale" to the samplers that animate them."""
    node = doc.item("nodes", node_index, "a node's parent")
    where = f"nodes[{node_index}]"
    count = len(times)
    if "matrix" in node:
        if channels:
            raise doc.fail(f"{where} has a matrix and animated {', '.join(channels)}: not allowed")
        matrix = numbers(doc, node["matrix"], 16, f"{where}.matrix")
        return np.repeat(matrix.reshape(4, 4).T[None], count, axis=0)  # column-major in JSON
    defaults = {
        "translation": [0.0, 0.0, 0.0],
        "rotation": [0.0, 0.0, 0.0, 1.0],
        "scale": [1.0] * 3,
    }
    parts = {}
    for path, default in defaults.items():
        if path in channels:
            parts[path] = channels[path].at(times)
        else:
            value = numbers(doc, node.get(path, default), len(default), f"{where}.{path}")
            parts[path] = np.repeat(value[None], count, axis=0)
    matrices = np.zeros((count, 4, 4))
    matrices[:, :3, :3] = (
        _rotation_matrices(_normalized(parts["rotation"])) * parts["scale"][:, None, :]
    )
    matrices[:, :3, 3] = parts["translation"]
    matrices[:, 3, 3] = 1.0
    return matrices


def numbers(doc: Document, value: Any, count: int, where: str) -> np.ndarray:
    if (
        not isinstance(value, list)
        or len(value) != count
        or not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value)
    ):
        raise doc.fail(f"{where} must be {count} numbers")
    array = np.array(value, dtype=np.float64)
    if not np.isfinite(array).all():
        raise doc.fail(f"{where} is not finite")
    return array


def _rotation_matrices(q: np.ndarray) -> np.ndarray:
    """Rotation matrices (n, 3, 3) of unit quaternions (x, y, z, w)."""
    x, y, z, w = q.T
    return np.stack(
        [
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)], -1),
            np.stack([2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)], -1),
            np.stack([2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)], -1),
        ],
        axis=1,
    )
