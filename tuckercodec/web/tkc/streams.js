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
