// Integer streams (spec/FORMAT.md §6.1): one Zstandard frame of N·P bytes in P byte planes,
// each value zigzag-coded. Every value of a stream fits 32 bits (P <= 4), so the decoded
// stream is an Int32Array.

import { decompressExact } from './zstd.js';

/**
 * Decodes a stream of `count` signed integers stored in `planes` byte planes.
 * The caller has checked that `planes` is an int in 1..4 (R30-planes).
 * @param {Uint8Array} payload one Zstandard frame
 * @param {number} count N
 * @param {number} planes P
 * @param {string} where the section (and stream), for messages
 * @returns {Int32Array}
 */
export function decodeIntStream(payload, count, planes, where) {
  const raw = decompressExact(payload, count * planes, where);
  const out = new Int32Array(count);
  const n = count;
  // u[j] = Σ_p raw[p·N + j] << 8p, then s = (u >>> 1) XOR −(u AND 1)
  if (planes === 1) {
    for (let j = 0; j < n; j++) {
      const u = raw[j];
      out[j] = (u >>> 1) ^ -(u & 1);
    }
  } else if (planes === 2) {
    for (let j = 0; j < n; j++) {
      const u = raw[j] | (raw[n + j] << 8);
      out[j] = (u >>> 1) ^ -(u & 1);
    }
  } else if (planes === 3) {
    for (let j = 0; j < n; j++) {
      const u = raw[j] | (raw[n + j] << 8) | (raw[2 * n + j] << 16);
      out[j] = (u >>> 1) ^ -(u & 1);
    }
  } else {
    for (let j = 0; j < n; j++) {
      const u = (raw[j] | (raw[n + j] << 8) | (raw[2 * n + j] << 16) | (raw[3 * n + j] << 24)) >>> 0;
      out[j] = (u >>> 1) ^ -(u & 1);
    }
  }
  return out;
}

/**
 * Decodes a stream of `count` signed 64-bit integers stored in `planes` byte planes (1..8: the
 * streams of format 1.5's attributes, whose float64 values' ordered integers take 64 bits). The
 * caller has checked `planes`. The values are held as interleaved 32-bit halves, low half first:
 * v[j] = out[2j+1]·2^32 + (out[2j] >>> 0), so no BigInt is made per value.
 * @param {Uint8Array} payload one Zstandard frame
 * @param {number} count N
 * @param {number} planes P
 * @param {string} where the section (and stream), for messages
 * @returns {Int32Array} 2·N halves
 */
export function decodeWideStream(payload, count, planes, where) {
  const raw = decompressExact(payload, count * planes, where);
  const out = new Int32Array(2 * count);
  const n = count;
  // u[j] = Σ_p raw[p·N + j] << 8p (planes 0-3 the low half, 4-7 the high), then zigzag on 64
  // bits: s = (u >> 1) XOR −(u AND 1), the shift carrying bit 32 into the low half
  /** @param {number} j @param {number} first */
  const half = (j, first) => {
    let u = 0;
    for (let p = Math.min(planes, first + 4) - 1; p >= first; p--) u = (u << 8) | raw[p * n + j];
    return u;
  };
  for (let j = 0; j < n; j++) {
    const lo = half(j, 0);
    const hi = planes > 4 ? half(j, 4) : 0;
    const sign = -(lo & 1);
    out[2 * j] = ((lo >>> 1) | (hi << 31)) ^ sign;
    out[2 * j + 1] = (hi >>> 1) ^ sign;
  }
  return out;
}
