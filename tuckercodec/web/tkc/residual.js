// Codec `residual` (spec/FORMAT.md §6.9, version 1.3): one 64-bit integer e per decoded
// coordinate, which moves the exact reconstruction P of §8.1 onto a grid ("grid") or onto
// chosen binary32 or binary64 bits ("float32", "float64").
//
// readResidual checks the section's parameters in the order of §5 step 18 (R40-residual, then
// R21-header-limit for each chunk's decompressed size); the caller checks the CRC after it.
// decodeChunk decodes one chunk (R29 for its zstd frame) and restores its integers; correct
// applies one frame's integers to P (R41-residual-value).
//
// The 64-bit integers are held as interleaved 32-bit halves in an Int32Array, low half first:
// e[j] = pairs[2j+1]·2^32 + (pairs[2j] >>> 0). On a little-endian engine (every one this
// decoder targets, checked below) that is the memory of a BigInt64Array of the same values, so
// no BigInt is made per value: zigzag, the wrapping prefix sum and the 64-bit additions of the
// float64 domain are all done on the halves with exact 32-bit operations, and the grid and
// float32 domains read e as a Number, which is exact within the ranges they allow (±2^53, ±2^32).

import { formatError, limitError } from './errors.js';
import { MsgFloat, describe, isInt } from './msgpack.js';
import { decompressExact } from './zstd.js';

const PARAMETER = 'R40-residual';
const VALUE = 'R41-residual-value';
const TWO_32 = 4294967296;
// float32 domain: the ordered integers of the finite binary32 values (§6.9)
const F32_LOWEST = -2139095040;
const F32_HIGHEST = 2139095039;
// float64 domain: the high halves of the ordered integers of the finite binary64 values,
// −0x7FF0000000000000 (that of −max) .. 0x7FEFFFFFFFFFFFFF (that of +max); every low half goes
const F64_LOWEST_HIGH = -2146435072; // 0x80100000 as int32: −0x7FF0000000000000 is 0x8010000000000000
const F64_HIGHEST_HIGH = 0x7fefffff;
// grid domain: e in −2^53 .. 2^53, high halves −2^21 .. 2^21 − 1, or 2^53 itself
const GRID_HIGH = 2 ** 21;

/** True where typed arrays are little-endian (the halves above, and the bit views below). */
export const LITTLE_ENDIAN = new Uint8Array(new Uint16Array([1]).buffer)[0] === 1;

/**
 * One chunk of a RESD section: its frames (counted from the section's first) and bytes.
 * @typedef {{planes: number, offset: number, length: number, start: number, frames: number}} Chunk
 */

/**
 * A RESD (or RESD.s) section's parameters, checked; chunk c holds the section's frames
 * c·chunkFrames .. (its start and frames).
 * @typedef {{section: import('./container.js').Section, domain: 'grid' | 'float32' | 'float64',
 *   step: number, predict: number, chunkFrames: number, chunks: Chunk[], frames: number}} Residual
 */

/**
 * §5 step 18 up to the CRC: the parameters of a RESD section covering `frames` frames of K
 * vertices, in the order §6.9 lists them (R40-residual), then each chunk's decompressed size
 * against max_section_bytes (R21-header-limit).
 * @param {import('./container.js').Section} section
 * @param {number} frames F' (F for RESD, F_s for RESD.s)
 * @param {number} K
 * @param {import('./limits.js').Limits} limits
 * @returns {Residual}
 */
export function readResidual(section, frames, K, limits) {
  const where = `section '${section.id}'`;
  const entry = section.entry;
  /** @type {(message: string) => Error} */
  const fail = (message) => formatError(PARAMETER, `${where}: ${message}`);
  /** @param {string} key */
  const shown = (key) => (entry.has(key) ? describe(entry.get(key)) : 'missing');
  const domain = entry.get('domain');
  if (domain !== 'grid' && domain !== 'float32' && domain !== 'float64') {
    throw fail(`"domain" is ${shown('domain')}, not "grid", "float32" or "float64"`);
  }
  let step = 0;
  if (domain === 'grid') {
    const value = entry.get('step');
    if (!(value instanceof MsgFloat) || !Number.isFinite(value.value) || !(value.value > 0)) {
      throw fail(`"step" is ${shown('step')}; in domain "grid" it is a finite float > 0`);
    }
    step = value.value;
  }
  const predict = entry.get('predict');
  if (predict !== 0 && predict !== 1) throw fail(`"predict" is ${shown('predict')}, not 0 or 1`);
  const chunkFrames = entry.get('chunk_frames');
  if (!isInt(chunkFrames) || chunkFrames < 1) throw fail(`"chunk_frames" is ${shown('chunk_frames')}, not an int >= 1`);
  // a BigInt chunk_frames is above 2^53, so above F': one chunk
  const L = typeof chunkFrames === 'bigint' || chunkFrames >= frames ? frames : chunkFrames;
  const count = Math.ceil(frames / L);
  const table = entry.get('chunks');
  if (!Array.isArray(table) || table.length !== count) {
    const what = Array.isArray(table) ? `an array of ${table.length} entries` : shown('chunks');
    throw fail(`"chunks" is ${what}; ${frames} frames in chunks of ${L} need ${count}`);
  }
  /** @type {Chunk[]} */
  const chunks = [];
  let offset = 0;
  table.forEach((item, c) => {
    if (!Array.isArray(item) || item.length !== 2 || !item.every((v) => isInt(v))) {
      throw fail(`chunk ${c} is ${describe(item)}, not an array of two ints [planes, length]`);
    }
    const [planes, length] = /** @type {(number | bigint)[]} */ (item);
    if (!(planes >= 1 && planes <= 8)) throw fail(`chunk ${c} has planes ${planes}, not in 1..8`);
    if (!(length >= 0)) throw fail(`chunk ${c} has length ${length}, below 0`);
    const start = c * L;
    // a BigInt length cannot add up to a payload's length: Infinity makes the sum say so
    const bytes = typeof length === 'bigint' ? Infinity : length;
    chunks.push({ planes: Number(planes), offset, length: bytes, start, frames: Math.min(L, frames - start) });
    offset += bytes;
  });
  if (offset !== section.length) {
    throw fail(`the chunks' lengths add up to ${offset} bytes, the payload has ${section.length}`);
  }
  chunks.forEach((chunk, c) => {
    const size = chunk.frames * K * 3 * chunk.planes;
    if (size > limits.max_section_bytes) {
      throw limitError('R21-header-limit', `${where}: chunk ${c} decodes to ${size} bytes, max_section_bytes = ${limits.max_section_bytes}`);
    }
  });
  // chunkFrames as the file gives it (a BigInt one made a Number: still above F', one chunk)
  return { section, domain, step, predict, chunkFrames: Number(chunkFrames), chunks, frames };
}

/**
 * Chunk c's restored integers e (§6.9), as interleaved halves (see the top of this file):
 * N_c = n_c·K·3 values in frame-major order, j = (t·K + v)·3 + x.
 * @param {Residual} residual
 * @param {number} c
 * @param {Uint8Array} payload the whole section's payload, its CRC checked
 * @param {number} K
 * @returns {Int32Array} 2·N_c halves
 */
export function decodeChunk(residual, c, payload, K) {
  const chunk = residual.chunks[c];
  const N = chunk.frames * K * 3;
  const P = chunk.planes;
  const where = `section '${residual.section.id}' chunk ${c}`;
  const raw = decompressExact(payload.subarray(chunk.offset, chunk.offset + chunk.length), N * P, where);
  const pairs = new Int32Array(2 * N);
  // u[j] = Σ_p raw[p·N + j] << 8p: planes 0-3 make the low half, 4-7 the high half
  for (let p = 0; p < P; p++) {
    const plane = raw.subarray(p * N, (p + 1) * N);
    const half = p < 4 ? 0 : 1;
    const shift = 8 * (p & 3);
    for (let j = 0; j < N; j++) pairs[2 * j + half] |= plane[j] << shift;
  }
  // zigzag on 64 bits: s = (u >> 1) XOR −(u AND 1), the shift carrying bit 32 into the low half
  for (let j = 0; j < 2 * N; j += 2) {
    const lo = pairs[j];
    const hi = pairs[j + 1];
    const sign = -(lo & 1);
    pairs[j] = ((lo >>> 1) | (hi << 31)) ^ sign;
    pairs[j + 1] = (hi >>> 1) ^ sign;
  }
  if (residual.predict === 1) {
    // e[t] = s[t] + e[t − 1], wrapped to 64 bits: a carry from the low halves into the high
    for (let j = 2 * K * 3; j < 2 * N; j += 2) {
      const before = j - 2 * K * 3;
      const lo = (pairs[j] >>> 0) + (pairs[before] >>> 0);
      pairs[j] = lo | 0;
      pairs[j + 1] = (pairs[j + 1] + pairs[before + 1] + (lo >= TWO_32 ? 1 : 0)) | 0;
    }
  }
  return pairs;
}

/** Scratch views shared by correct(): one frame's binary32 values and their bits. */
let scratch32 = new Float32Array(0);
let bits32 = new Int32Array(0);
let scratch64 = new Float64Array(0);
let bits64 = new Int32Array(0);

/**
 * One frame's decoded positions (§6.9): P (the exact reconstruction of §8.1) corrected by the
 * frame's integers, into `out` (a Float32Array receives the binary64 result rounded once, which
 * in domain float32 is the corrected binary32 value itself).
 * @param {Residual} residual
 * @param {Float64Array} P K·3 values
 * @param {Int32Array} pairs the chunk's integers (decodeChunk)
 * @param {number} first the index in the chunk of the frame's first integer, t·K·3
 * @param {Float64Array | Float32Array} out K·3 values
 * @param {number} frameNumber the frame within the file, for messages
 */
export function correct(residual, P, pairs, first, out, frameNumber) {
  if (!LITTLE_ENDIAN) throw new Error('corrections (§6.9) are decoded on little-endian engines only');
  const n = P.length;
  const at = 2 * first;
  /** @type {(j: number, message: string) => Error} */
  const fail = (j, message) => formatError(VALUE, `section '${residual.section.id}', frame ${frameNumber}, vertex ${Math.floor(j / 3)}, axis ${'xyz'[j % 3]}: ${message}`);
  /** @param {number} j */
  const integer = (j) => BigInt.asIntN(64, (BigInt(pairs[at + 2 * j + 1]) << 32n) | BigInt(pairs[at + 2 * j] >>> 0));
  if (residual.domain === 'grid') {
    const step = residual.step;
    for (let j = 0; j < n; j++) {
      const hi = pairs[at + 2 * j + 1];
      const lo = pairs[at + 2 * j] >>> 0;
      if ((hi < -GRID_HIGH || hi >= GRID_HIGH) && !(hi === GRID_HIGH && lo === 0)) {
        throw fail(j, `e = ${integer(j)} is outside −2^53..2^53`);
      }
      const e = hi * TWO_32 + lo; // exact: |e| <= 2^53
      const value = P[j] + step * e; // one multiplication, then one addition (never fused in JS)
      if (value - value !== 0) throw fail(j, `P + step·e = ${P[j]} + ${step}·${e} is ${value}, not finite`);
      out[j] = value;
    }
    return out;
  }
  if (residual.domain === 'float32') {
    if (scratch32.length < n) {
      scratch32 = new Float32Array(n);
      bits32 = new Int32Array(scratch32.buffer);
    }
    scratch32.set(P.subarray(0, n)); // the binary32 nearest each P (ties to even, beyond: ±∞)
    for (let j = 0; j < n; j++) {
      // NaN has no binary32 "nearest" it, and its bits are the engine's: no correction is defined
      if (P[j] !== P[j]) throw fail(j, 'P is NaN: no binary32 value is nearest it');
      const bits = bits32[j];
      const b = bits < 0 ? bits ^ 0x7fffffff : bits; // the ordered integer
      const hi = pairs[at + 2 * j + 1];
      const lo = pairs[at + 2 * j] >>> 0;
      if (hi !== 0 && hi !== -1 && !(hi === 1 && lo === 0)) throw fail(j, `e = ${integer(j)} is outside −2^32..2^32`);
      const o = b + (hi * TWO_32 + lo); // exact
      if (o < F32_LOWEST || o > F32_HIGHEST) {
        throw fail(j, `b + e = ${b} + ${hi * TWO_32 + lo} = ${o} is not the ordered integer of a finite binary32 (P = ${P[j]})`);
      }
      bits32[j] = o < 0 ? o ^ 0x7fffffff : o;
    }
    out.set(scratch32.subarray(0, n));
    return out;
  }
  // float64: o = b + e on 64 bits, on the halves of P's bits (written over them, in `out`
  // itself when it is a Float64Array)
  let target;
  let bits;
  if (out instanceof Float64Array) {
    target = out;
    bits = new Int32Array(out.buffer, out.byteOffset, 2 * n);
  } else {
    if (scratch64.length < n) {
      scratch64 = new Float64Array(n);
      bits64 = new Int32Array(scratch64.buffer);
    }
    target = scratch64;
    bits = bits64;
  }
  if (target !== P) target.set(P.subarray(0, n));
  for (let j = 0; j < n; j++) {
    let pLo = bits[2 * j];
    let pHi = bits[2 * j + 1];
    if (pHi < 0) {
      pHi ^= 0x7fffffff;
      pLo = ~pLo;
    }
    const sum = (pLo >>> 0) + (pairs[at + 2 * j] >>> 0);
    const oHi = (pHi + pairs[at + 2 * j + 1] + (sum >= TWO_32 ? 1 : 0)) | 0;
    if (oHi < F64_LOWEST_HIGH || oHi > F64_HIGHEST_HIGH) {
      const o = BigInt.asIntN(64, (BigInt(oHi) << 32n) | BigInt(sum >>> 0));
      throw fail(j, `b + e = ${o} is not the ordered integer of a finite binary64 (P = ${P[j]}, e = ${integer(j)})`);
    }
    if (oHi < 0) {
      bits[2 * j] = ~sum;
      bits[2 * j + 1] = oHi ^ 0x7fffffff;
    } else {
      bits[2 * j] = sum | 0;
      bits[2 * j + 1] = oHi;
    }
  }
  if (target !== out) out.set(target.subarray(0, n));
  return out;
}
