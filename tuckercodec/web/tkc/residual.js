// Codec `residual` (spec/FORMAT.md §6.9, version 1.3): one 64-bit integer e per decoded
// coordinate, which moves the exact reconstruction P of §8.1 onto a grid ("grid"), onto
// chosen binary32 or binary64 bits ("float32", "float64"), or onto decimals of d places or p
// significant digits ("decimal-places", "decimal-digits", and "decimal-digits-float32" for the
// binary32 values such decimals give).
//
// readResidual checks the section's parameters in the order of §5 step 18 (R40-residual, and
// (1.7) R46-adaptive-stream for `coder`, (1.8) `codebooks`, then R21-header-limit for each
// codebook's and chunk's decompressed size); the caller checks the CRC after it. decodeCodebooks
// decodes a section's codebooks (format 1.8: R29 for each zstd frame, R47-codebook for its
// entries); decodeChunk decodes one chunk (R29 for its zstd frame, or with `coder` 1 R46 for its
// adaptive stream, §6.14) and restores its integers; correct applies one frame's integers to P
// (R41-residual-value), through the codebooks on the axes that have one.
//
// The 64-bit integers are held as interleaved 32-bit halves in an Int32Array, low half first:
// e[j] = pairs[2j+1]·2^32 + (pairs[2j] >>> 0). On a little-endian engine (every one this
// decoder targets, checked below) that is the memory of a BigInt64Array of the same values, so
// no BigInt is made per value: zigzag, the wrapping prefix sum and the 64-bit additions of the
// float64 domain are all done on the halves with exact 32-bit operations, and the grid and
// float32 domains read e as a Number, which is exact within the ranges they allow (±2^53, ±2^32).

import { adaptiveError, decodeAdaptive, decodeAdaptiveWide } from './adaptive.js';
import { formatError, limitError } from './errors.js';
import { MsgFloat, describe, isInt } from './msgpack.js';
import { decompressExact } from './zstd.js';

const PARAMETER = 'R40-residual';
const VALUE = 'R41-residual-value';
const CODEBOOK = 'R47-codebook';
const TWO_32 = 4294967296;
const ZSTD = 0; // `coder` (1.7): each chunk §6.1's zstd frame of byte planes ...
const ADAPTIVE = 1; // ... or one adaptive stream of §6.14
// float32 domain: the ordered integers of the finite binary32 values (§6.9)
const F32_LOWEST = -2139095040;
const F32_HIGHEST = 2139095039;
// float64 domain: the range §6.9 gives, −9218868437227405312 .. 9218868437227405311 (−max to
// +max), as high halves: 0x80100000 .. 0x7FEFFFFF (every low half with each)
const F64_LOWEST_HIGH = -2146435072; // 0x80100000 as int32
const F64_HIGHEST_HIGH = 0x7fefffff;
// grid domain: e in −2^53 .. 2^53, high halves −2^21 .. 2^21 − 1, or 2^53 itself
const GRID_HIGH = 2 ** 21;
// decimal-places: e in −2^54 .. 2^54 (high halves −2^22 .. 2^22 − 1, or 2^54 itself), and
// k = b + e in −2^53 .. 2^53 as in the grid domain
const PLACES_E_HIGH = 2 ** 22;
const TWO_53 = 2 ** 53;
/** 10^n for n = 0..22, each exact in binary64 (read from text, which rounds correctly). */
const TEN = Array.from({ length: 23 }, (_, n) => Number(`1e${n}`));
/** The domains and the parameter each decimal one takes, with its range (§6.9). */
const DOMAINS = ['grid', 'float32', 'float64', 'decimal-places', 'decimal-digits', 'decimal-digits-float32'];
/** @type {{[domain: string]: [string, number, number]}} */
const SCALES = {
  'decimal-places': ['places', 0, 22],
  'decimal-digits': ['digits', 1, 15],
  'decimal-digits-float32': ['digits', 1, 15],
};

/** True where typed arrays are little-endian (the halves above, and the bit views below). */
export const LITTLE_ENDIAN = new Uint8Array(new Uint16Array([1]).buffer)[0] === 1;

/**
 * One chunk of a RESD section: its frames (counted from the section's first) and bytes.
 * @typedef {{planes: number, offset: number, length: number, start: number, frames: number}} Chunk
 */

/**
 * One axis's codebook of a RESD section (format 1.8): its `count` integers (0: the axis has
 * none), their planes and its bytes in the payload.
 * @typedef {{count: number, planes: number, offset: number, length: number}} Codebook
 */

/**
 * A RESD (or RESD.s) section's parameters, checked; chunk c holds the section's frames
 * c·chunkFrames .. (its start and frames). `coder` is 1 where each chunk is an adaptive stream
 * (format 1.7), else 0 (zstd planes; in a file without flag bit 4 whatever the entry says).
 * `codebooks` (format 1.8) has an entry per axis, or none where the section has no `codebooks`
 * (or the file does not set flag bit 5).
 * @typedef {{section: import('./container.js').Section, domain: string, step: number,
 *   scale: number | null, exponent: number, predict: number, coder: number, chunkFrames: number,
 *   chunks: Chunk[], frames: number, codebooks: Codebook[]}} Residual
 */

/**
 * A section's decoded codebooks (format 1.8), one per axis: its entries C as interleaved halves
 * (as a chunk's integers are), or null for an axis without one.
 * @typedef {(Int32Array | null)[]} Codebooks
 */

/**
 * §5 step 18 up to the CRC: the parameters of a RESD section covering `frames` frames of K
 * vertices, in the order §6.9 lists them (R40-residual; (1.7) `coder`, R46-adaptive-stream,
 * read only in a file with flag bit 4; (1.8) `codebooks`, read only in a file with flag bit 5),
 * then each codebook's decompressed size against max_section_bytes and its entries against
 * max_chunk_values, then each chunk's size against max_section_bytes and, for a chunk of
 * several frames, its integers against max_chunk_values (R21-header-limit).
 * @param {import('./container.js').Section} section
 * @param {number} frames F' (F for RESD, F_s for RESD.s)
 * @param {number} K
 * @param {import('./limits.js').Limits} limits
 * @param {boolean} [adaptive] the file sets flag bit 4 (format 1.7): `coder` is read, and may be 1
 * @param {boolean} [codebooks] the file sets flag bit 5 (format 1.8): `codebooks` is read
 * @returns {Residual}
 */
export function readResidual(section, frames, K, limits, adaptive = false, codebooks = false) {
  const where = `section '${section.id}'`;
  const entry = section.entry;
  /** @type {(message: string) => Error} */
  const fail = (message) => formatError(PARAMETER, `${where}: ${message}`);
  /** @param {string} key */
  const shown = (key) => (entry.has(key) ? describe(entry.get(key)) : 'missing');
  const domain = entry.get('domain');
  if (typeof domain !== 'string' || !DOMAINS.includes(domain)) {
    throw fail(`"domain" is ${shown('domain')}, not one of ${DOMAINS.map((d) => `"${d}"`).join(', ')}`);
  }
  let step = 0;
  if (domain === 'grid') {
    const value = entry.get('step');
    if (!(value instanceof MsgFloat) || !Number.isFinite(value.value) || !(value.value > 0)) {
      throw fail(`"step" is ${shown('step')}; in domain "grid" it is a finite float > 0`);
    }
    step = value.value;
  }
  let scale = null;
  if (domain in SCALES) {
    const [key, least, most] = SCALES[domain];
    const value = entry.get(key);
    if (!isInt(value) || !(value >= least && value <= most)) {
      throw fail(`"${key}" is ${shown(key)}; in domain "${domain}" it is an int in ${least}..${most}`);
    }
    scale = Number(value);
  }
  // §8.1's e: the unit of the integer weights is 2^e
  const exponent = entry.get('exponent');
  if (!isInt(exponent) || !(exponent >= -1022 && exponent <= 1022)) {
    throw fail(`"exponent" is ${shown('exponent')}, not an int in -1022..1022`);
  }
  const predict = entry.get('predict');
  if (predict !== 0 && predict !== 1) throw fail(`"predict" is ${shown('predict')}, not 0 or 1`);
  // without flag bit 4, `coder` is an unknown parameter (§3): ignored, as before 1.7
  const coder = entry.get('coder');
  if (adaptive && coder !== undefined && coder !== ZSTD && coder !== ADAPTIVE) {
    throw adaptiveError(where, `"coder" is ${describe(coder)}; this section allows 0 or 1`);
  }
  // without flag bit 5, `codebooks` is an unknown parameter (§3): ignored, as before 1.8
  const books = codebooks && entry.has('codebooks') ? readCodebooks(entry.get('codebooks'), domain, K * frames, fail) : [];
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
  const chunks = readChunks(table, L, frames, section.length, books, fail);
  checkSizes(books, chunks, K, limits, where);
  const stored = adaptive && coder === ADAPTIVE ? ADAPTIVE : ZSTD;
  // chunkFrames as the file gives it (a BigInt one made a Number: still above F', one chunk)
  return { section, domain, step, scale, exponent: Number(exponent), predict, coder: stored, chunkFrames: Number(chunkFrames), chunks, frames, codebooks: books };
}

/**
 * §5 step 18's limits (R21-header-limit): each codebook's decompressed size n·P against
 * max_section_bytes and its entries n against max_chunk_values (format 1.8: every frame needs
 * the whole codebook), in axis order; then each chunk's N_c·P against max_section_bytes and,
 * for a chunk of several frames (a frame is decoded with its whole chunk), N_c against
 * max_chunk_values.
 * @param {Codebook[]} books
 * @param {Chunk[]} chunks
 * @param {number} K
 * @param {import('./limits.js').Limits} limits
 * @param {string} where
 */
function checkSizes(books, chunks, K, limits, where) {
  books.forEach((book, x) => {
    const size = book.count * book.planes;
    if (size > limits.max_section_bytes) {
      throw limitError('R21-header-limit', `${where}: axis ${x}'s codebook decodes to ${size} bytes, max_section_bytes = ${limits.max_section_bytes}`);
    }
    // every frame needs the whole codebook: held, like a chunk, to a size that does not grow
    if (book.count > limits.max_chunk_values) {
      throw limitError('R21-header-limit', `${where}: axis ${x}'s codebook holds ${book.count} entries, max_chunk_values = ${limits.max_chunk_values}`);
    }
  });
  chunks.forEach((chunk, c) => {
    const size = chunk.frames * K * 3 * chunk.planes;
    if (size > limits.max_section_bytes) {
      throw limitError('R21-header-limit', `${where}: chunk ${c} decodes to ${size} bytes, max_section_bytes = ${limits.max_section_bytes}`);
    }
    // a frame is decoded with its whole chunk: one of several frames is held to a bounded size
    const count = chunk.frames * K * 3;
    if (chunk.frames > 1 && count > limits.max_chunk_values) {
      throw limitError('R21-header-limit', `${where}: chunk ${c} holds ${count} integers (${chunk.frames} frames of ${K} vertices), max_chunk_values = ${limits.max_chunk_values}`);
    }
  });
}

/**
 * `codebooks` (format 1.8, R40-residual): exactly three `[count, planes, length]`, each
 * `[0, 0, 0]` or `count` in 1..K·F', `planes` in 1..8 and `length` ≥ 0, a count above 0 only
 * outside domain "grid"; each axis's form, then its values, in axis order. Placed in the payload
 * (their bytes come first) by readChunks.
 * @param {import('./msgpack.js').MsgValue | undefined} table
 * @param {string} domain
 * @param {number} values K·F', the most integers a codebook may hold
 * @param {(message: string) => Error} fail
 * @returns {Codebook[]}
 */
function readCodebooks(table, domain, values, fail) {
  if (!Array.isArray(table) || table.length !== 3) {
    const what = Array.isArray(table) ? `an array of ${table.length} entries` : describe(table);
    throw fail(`"codebooks" is ${what}, not an array of 3 [count, planes, length] entries`);
  }
  return table.map((item, x) => {
    if (!Array.isArray(item) || item.length !== 3 || !item.every((v) => isInt(v))) {
      throw fail(`axis ${x}'s codebook is ${describe(item)}, not an array of three ints [count, planes, length]`);
    }
    const [count, planes, length] = /** @type {(number | bigint)[]} */ (item);
    const none = Number(count) === 0 && Number(planes) === 0 && Number(length) === 0;
    if (!none && !(count >= 1 && count <= values && planes >= 1 && planes <= 8 && length >= 0)) {
      throw fail(`axis ${x}'s codebook is [${count}, ${planes}, ${length}]; it is [0, 0, 0] or [count 1..${values}, planes 1..8, length >= 0]`);
    }
    if (!none && domain === 'grid') throw fail(`axis ${x} has a codebook; domain "grid" has none`);
    // a BigInt length cannot add up to a payload's length: Infinity makes the sum say so
    return { count: Number(count), planes: Number(planes), offset: 0, length: typeof length === 'bigint' ? Infinity : length };
  });
}

/**
 * The `chunks` table, each entry's form and `planes` in order, then their lengths and the
 * codebooks' against the payload's (R40-residual): chunk c holds the frames c·L .. of F'. The
 * codebooks' bytes come first (format 1.8): each is given its offset here.
 * @param {import('./msgpack.js').MsgValue[]} table its C entries
 * @param {number} L the frames of a chunk
 * @param {number} frames F'
 * @param {number} payload the payload's length
 * @param {Codebook[]} books the section's codebooks, none without `codebooks`
 * @param {(message: string) => Error} fail
 * @returns {Chunk[]}
 */
function readChunks(table, L, frames, payload, books, fail) {
  /** @type {Chunk[]} */
  const chunks = [];
  let offset = 0;
  for (const book of books) {
    book.offset = offset;
    offset += book.length;
  }
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
  if (offset !== payload) {
    const what = books.length > 0 ? "the codebooks' and the chunks'" : "the chunks'";
    throw fail(`${what} lengths add up to ${offset} bytes, the payload has ${payload}`);
  }
  return chunks;
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
  const where = `section '${residual.section.id}' chunk ${c}`;
  const bytes = payload.subarray(chunk.offset, chunk.offset + chunk.length);
  const pairs = residual.coder === ADAPTIVE ? adaptivePairs(bytes, chunk, K, where) : zstdPairs(bytes, chunk.frames * K * 3, chunk.planes, where);
  if (residual.predict === 1) {
    // e[t] = s[t] + e[t − 1], wrapped to 64 bits: a carry from the low halves into the high
    for (let j = 2 * K * 3; j < pairs.length; j += 2) {
      const before = j - 2 * K * 3;
      const lo = (pairs[j] >>> 0) + (pairs[before] >>> 0);
      pairs[j] = lo | 0;
      pairs[j + 1] = (pairs[j + 1] + pairs[before + 1] + (lo >= TWO_32 ? 1 : 0)) | 0;
    }
  }
  return pairs;
}

/**
 * A zstd chunk's stored integers s (§6.9), or a codebook's differences d (1.8): the frame
 * decompressed to N·P bytes (R29), planes made integers and zigzag undone, as interleaved halves
 * in the stream's order.
 * @param {Uint8Array} bytes the chunk's or codebook's payload
 * @param {number} N its integers
 * @param {number} P its planes
 * @param {string} where
 */
function zstdPairs(bytes, N, P, where) {
  const raw = decompressExact(bytes, N * P, where);
  const pairs = new Int32Array(2 * N);
  // u[j] = Σ_p raw[p·N + j] << 8p: planes 0-3 make the low half, 4-7 the high half (a plane
  // the chunk does not have reads as zeros); then zigzag on 64 bits, s = (u >> 1) XOR
  // −(u AND 1), the shift carrying bit 32 into the low half. One pass, one loop per case.
  const zeros = P < 8 ? new Uint8Array(N) : raw;
  /** @param {number} p */
  const plane = (p) => (p < P ? raw.subarray(p * N, (p + 1) * N) : zeros);
  const [p0, p1, p2, p3] = [plane(0), plane(1), plane(2), plane(3)];
  if (P <= 4) {
    for (let j = 0; j < N; j++) {
      const lo = p0[j] | (p1[j] << 8) | (p2[j] << 16) | (p3[j] << 24);
      const sign = -(lo & 1);
      pairs[2 * j] = (lo >>> 1) ^ sign;
      pairs[2 * j + 1] = sign;
    }
  } else {
    const [p4, p5, p6, p7] = [plane(4), plane(5), plane(6), plane(7)];
    for (let j = 0; j < N; j++) {
      const lo = p0[j] | (p1[j] << 8) | (p2[j] << 16) | (p3[j] << 24);
      const hi = p4[j] | (p5[j] << 8) | (p6[j] << 16) | (p7[j] << 24);
      const sign = -(lo & 1);
      pairs[2 * j] = ((lo >>> 1) | (hi << 31)) ^ sign;
      pairs[2 * j + 1] = (hi >>> 1) ^ sign;
    }
  }
  return pairs;
}

/**
 * An adaptive chunk's stored integers s (§6.9, version 1.7): its stream (§6.14, R46) holds
 * them as K rows and n_c·3 columns, column 3t + x holding s[t, v, x] for v = 0..K − 1; put back
 * in the chunk's order j = (t·K + v)·3 + x as interleaved halves. Within 4 planes (integers of
 * 32 bits) through decodeAdaptive, the faster path, else decodeAdaptiveWide.
 * @param {Uint8Array} bytes the chunk's payload
 * @param {Chunk} chunk
 * @param {number} K
 * @param {string} where
 */
function adaptivePairs(bytes, chunk, K, where) {
  const cols = chunk.frames * 3;
  if (chunk.planes <= 4) {
    const values = decodeAdaptive(bytes, K, cols, null, chunk.planes, where);
    const pairs = new Int32Array(2 * cols * K);
    for (let c = 0; c < cols; c++) {
      // column c = 3t + x starts at j = 3tK + x, its rows 3 apart
      for (let v = 0, i = c * K, j = 2 * (K * (c - (c % 3)) + (c % 3)); v < K; v++, i++, j += 6) {
        pairs[j] = values[i];
        pairs[j + 1] = values[i] >> 31;
      }
    }
    return pairs;
  }
  const halves = decodeAdaptiveWide(bytes, K, cols, chunk.planes, where);
  const pairs = new Int32Array(halves.length);
  for (let c = 0; c < cols; c++) {
    for (let v = 0, i = 2 * c * K, j = 2 * (K * (c - (c % 3)) + (c % 3)); v < K; v++, i += 2, j += 6) {
      pairs[j] = halves[i];
      pairs[j + 1] = halves[i + 1];
    }
  }
  return pairs;
}

// ---------------------------------------------------------------------------------------------
// codebooks (format 1.8, §6.9): on an axis with one, e moves b's nearest entry along the sorted
// list C of the ordered integers the axis takes; o = C[j + e] replaces b + e

/**
 * A 64-bit value from its halves, for messages.
 * @param {number} hi
 * @param {number} lo
 */
function int64(hi, lo) {
  return BigInt.asIntN(64, (BigInt(hi) << 32n) | BigInt(lo >>> 0));
}

/**
 * A 64-bit value as [high half (signed), low half (unsigned)], the form `within` compares.
 * @param {bigint} v
 */
function halvesOf(v) {
  return [Number(BigInt.asIntN(64, v) >> 32n), Number(BigInt.asUintN(32, v))];
}

/**
 * The ordered integers a codebook's entries may be in its section's domain (R47), as halves.
 * @param {Residual} residual not of domain grid, which has no codebooks
 * @returns {number[][]} [least, largest]
 */
function codebookRange(residual) {
  if (residual.domain === 'float32') return [halvesOf(BigInt(F32_LOWEST)), halvesOf(BigInt(F32_HIGHEST))];
  if (residual.domain === 'float64') return [halvesOf(-9218868437227405312n), halvesOf(9218868437227405311n)];
  if (residual.domain === 'decimal-places') return [halvesOf(-(2n ** 53n)), halvesOf(2n ** 53n)];
  const c = digitConstants(/** @type {number} */ (residual.scale));
  return [c.oLow, c.oHigh];
}

/**
 * A section's codebooks (format 1.8), in axis order: each one's zstd frame of n·P bytes (R29),
 * then its entries C[0] = d[0], C[m] = C[m − 1] + d[m] wrapped to 64 bits, each above the one
 * before and all within the domain's ordered integers (R47-codebook).
 * @param {Residual} residual
 * @param {Uint8Array} payload the whole section's payload, its CRC checked
 * @returns {Codebooks}
 */
export function decodeCodebooks(residual, payload) {
  return residual.codebooks.map((book, x) => {
    if (book.count === 0) return null;
    const where = `section '${residual.section.id}' codebook of axis ${x}`;
    const C = zstdPairs(payload.subarray(book.offset, book.offset + book.length), book.count, book.planes, where);
    for (let m = 2; m < C.length; m += 2) {
      const lo = (C[m] >>> 0) + (C[m - 2] >>> 0);
      const hi = (C[m + 1] + C[m - 1] + (lo >= TWO_32 ? 1 : 0)) | 0;
      C[m] = lo | 0;
      C[m + 1] = hi;
      if (hi < C[m - 1] || (hi === C[m - 1] && C[m] >>> 0 <= C[m - 2] >>> 0)) {
        const [after, before] = [int64(hi, lo), int64(C[m - 1], C[m - 2])];
        throw formatError(CODEBOOK, `${where}: entry ${m / 2}, ${after}, is not above entry ${m / 2 - 1}, ${before}`);
      }
    }
    const [low, high] = codebookRange(residual);
    const last = C.length - 2;
    if (!within(C[1], C[0] >>> 0, low, high) || !within(C[last + 1], C[last] >>> 0, low, high)) {
      const range = `${int64(low[0], low[1])}..${int64(high[0], high[1])}`;
      throw formatError(CODEBOOK, `${where}: its entries ${int64(C[1], C[0])}..${int64(C[last + 1], C[last])} are not all within ${range}, the ordered integers of domain "${residual.domain}"`);
    }
    return C;
  });
}

/** b of one value (baseOf), as halves: low, then high. */
const BASE = new Int32Array(2);
const BASE32 = new Float32Array(1);
const BASE32_BITS = new Int32Array(BASE32.buffer);
const BASE64 = new Float64Array(1);
const BASE64_BITS = new Int32Array(BASE64.buffer);

/**
 * The function that puts into BASE the b of §6.9 of a value P in the section's domain (the
 * ordered integer that e would move), and returns false where P has none (NaN in float32; not
 * finite elsewhere): the domain's own loop then refuses it as it would without codebooks.
 * @param {Residual} residual not of domain grid
 * @returns {(p: number) => boolean}
 */
function baseOf(residual) {
  const domain = residual.domain;
  if (domain === 'float32') {
    return (p) => {
      if (p !== p) return false;
      BASE32[0] = p; // the binary32 nearest P, ties to even (beyond the range, ±∞)
      const w = BASE32_BITS[0];
      const b = w < 0 ? w ^ 0x7fffffff : w;
      BASE[0] = b;
      BASE[1] = b < 0 ? -1 : 0;
      return true;
    };
  }
  if (domain === 'float64') {
    return (p) => {
      if (p - p !== 0) return false;
      BASE64[0] = p;
      const lo = BASE64_BITS[0];
      const hi = BASE64_BITS[1];
      BASE[0] = hi < 0 ? ~lo : lo;
      BASE[1] = hi < 0 ? hi ^ 0x7fffffff : hi;
      return true;
    };
  }
  if (domain === 'decimal-places') {
    const ten = TEN[/** @type {number} */ (residual.scale)];
    return (p) => {
      if (p - p !== 0) return false;
      const b = Math.min(Math.max(roundHalfEven(p * ten), -TWO_53), TWO_53);
      const hi = Math.floor(b / TWO_32);
      BASE[0] = b - hi * TWO_32;
      BASE[1] = hi;
      return true;
    };
  }
  const c = digitConstants(/** @type {number} */ (residual.scale));
  return (p) => {
    if (p - p !== 0) return false;
    digitsBase(p, c);
    return true;
  };
}

/**
 * j of §6.9 by value. b is nearer C[m + 1] than C[m] (a tie keeping C[m]) exactly when
 * 2b > C[m] + C[m + 1], that is when b is above the midpoint floor((C[m] + C[m + 1]) / 2), so j
 * is how many midpoints lie below b. The range from the first midpoint to the last is cut into
 * about as many equal parts as there are midpoints (each a power of two wide), with how many
 * midpoints lie before each part: a value's count is one lookup and a search among the few
 * midpoints of its part, wherever the value was in the frames before. (A search outwards from
 * each vertex's entry in the frames before missed the cache at almost every step where vertices
 * move far between frames, as in a gallop.) The compiled core's `MiddleIndex` (codebooks.rs)
 * cuts the same parts; here the 64-bit integers are 32-bit halves, and the midpoints are not kept
 * but compared from C itself, whose entries near j the caller reads next.
 */
export class MiddleIndex {
  /** @param {Int32Array} C the codebook's n ≥ 1 entries, increasing, as interleaved halves */
  constructor(C) {
    /** The entries, whose sums of neighbours the search within a part compares. */
    this.C = C;
    /** How many midpoints: n − 1. */
    this.count = C.length / 2 - 1;
    const middles = midpoints(C);
    const last = 2 * this.count - 2;
    // without midpoints, the largest integer, so that every value counts none
    /** The first midpoint's high half: none lies below a value at or below it. */
    this.lowHi = this.count > 0 ? middles[1] : 0x7fffffff;
    /** The first midpoint's low half (unsigned). */
    this.lowLo = this.count > 0 ? middles[0] >>> 0 : 0xffffffff;
    const [spanHi, spanLo] = this.count > 0 ? this.distance(middles[last + 1], middles[last] >>> 0) : [0, 0];
    /** The last midpoint's distance from the first, high half (unsigned): all lie below a value further. */
    this.spanHi = spanHi;
    /** Its low half (unsigned). */
    this.spanLo = spanLo;
    const wanted = 32 - Math.clz32(this.count);
    const bits = spanHi > 0 ? 64 - Math.clz32(spanHi) : 32 - Math.clz32(spanLo);
    /** A distance's part is the distance shifted right by this: about 2^wanted parts. */
    this.shift = Math.max(bits - wanted, 0);
    /** starts[k]: how many midpoints lie in the parts before part k (one more entry than parts) */
    this.starts = new Int32Array(this.part(spanHi, spanLo) + 2);
    for (let m = 0; m < 2 * this.count; m += 2) {
      const [hi, lo] = this.distance(middles[m + 1], middles[m] >>> 0);
      this.starts[this.part(hi, lo) + 1]++;
    }
    for (let k = 1; k < this.starts.length; k++) this.starts[k] += this.starts[k - 1];
  }

  /**
   * The distance of a value at or above the first midpoint from it, as unsigned halves.
   * @param {number} hi
   * @param {number} lo unsigned
   * @returns {[number, number]}
   */
  distance(hi, lo) {
    const d = lo - this.lowLo;
    return [(hi - this.lowHi - (d < 0 ? 1 : 0)) >>> 0, d < 0 ? d + TWO_32 : d];
  }

  /**
   * The part of a distance within the span: below 2^wanted, a 32-bit integer. (With shift 0,
   * `hi << 32` is `hi << 0` in JavaScript, which shifts by the count mod 32; it is still 0, as
   * shift 0 comes only with a span below 2^32.)
   * @param {number} hi unsigned
   * @param {number} lo unsigned
   */
  part(hi, lo) {
    const s = this.shift;
    return s >= 32 ? hi >>> (s - 32) : (hi << (32 - s)) | (lo >>> s);
  }

  /**
   * How many midpoints lie below b: j of §6.9. Those of the parts before b's are all below it
   * and those of the parts after it all above, as (a >> s) < (c >> s) implies a < c.
   * @param {number} bHi
   * @param {number} bLo unsigned
   */
  countBelow(bHi, bLo) {
    if (bHi < this.lowHi || (bHi === this.lowHi && bLo <= this.lowLo)) return 0;
    let dLo = bLo - this.lowLo;
    const dHi = (bHi - this.lowHi - (dLo < 0 ? 1 : 0)) >>> 0;
    if (dLo < 0) dLo += TWO_32;
    if (dHi > this.spanHi || (dHi === this.spanHi && dLo > this.spanLo)) return this.count;
    const k = this.part(dHi, dLo);
    // midpoint m is below b when C[m] + C[m + 1] < 2b: (the sum's high half − 2b's)·2^32 < 2b's
    // low half − the sum's, each side exact in binary64 (a multiple of 2^32 below 2^66, and an
    // integer below 2^34 in magnitude)
    const C = this.C;
    const twiceHi = 2 * bHi;
    const twiceLo = 2 * bLo;
    let first = this.starts[k];
    let end = this.starts[k + 1];
    while (first < end) {
      const m = (first + end) >>> 1;
      if ((C[2 * m + 1] + C[2 * m + 3] - twiceHi) * TWO_32 < twiceLo - (C[2 * m] >>> 0) - (C[2 * m + 2] >>> 0)) first = m + 1;
      else end = m;
    }
    return first;
  }
}

/**
 * A codebook's midpoints floor((C[m] + C[m + 1]) / 2), as interleaved halves: C[m] + floor(gap
 * / 2), the gap C[m + 1] − C[m] in 1 .. 2^64 − 1 taken as unsigned halves.
 * @param {Int32Array} C n ≥ 1 entries, increasing, as interleaved halves
 */
function midpoints(C) {
  const middles = new Int32Array(C.length - 2);
  for (let m = 0; m < middles.length; m += 2) {
    let gapLo = (C[m + 2] >>> 0) - (C[m] >>> 0);
    const gapHi = (C[m + 3] - C[m + 1] - (gapLo < 0 ? 1 : 0)) >>> 0;
    if (gapLo < 0) gapLo += TWO_32;
    const lo = (C[m] >>> 0) + (gapLo >>> 1) + (gapHi & 1) * 2 ** 31;
    middles[m] = lo | 0;
    middles[m + 1] = (C[m + 1] + (gapHi >>> 1) + (lo >= TWO_32 ? 1 : 0)) | 0;
  }
  return middles;
}

/** Each codebook's MiddleIndex, made on the first frame that needs it. */
const INDEXES = new WeakMap();

/** Scratch of throughCodebooks: one frame's integers. */
let bookPairs = new Int32Array(0);

/**
 * One frame's integers as correct's loops take them: on each axis with a codebook, e replaced by
 * C[t] − b (wrapped to 64 bits), t = j + e of §6.9 (R41 outside 0..n − 1), so that the loop's
 * b + e is o = C[t]. That difference is always within the domain's range of e (b and C[t] are
 * both within its ordered integers, C[t] by R47), whose check then holds, as §6.9 says it does
 * not apply. A value without b (baseOf) keeps its e, for the loop to refuse.
 * @param {Residual} residual
 * @param {Codebooks} books
 * @param {Float64Array} P
 * @param {Int32Array} pairs
 * @param {number} at the index of the frame's first low half
 * @param {number} frameNumber for messages
 * @returns {Int32Array} the frame's 2·P.length halves, from index 0
 */
function throughCodebooks(residual, books, P, pairs, at, frameNumber) {
  const n = P.length;
  if (bookPairs.length < 2 * n) bookPairs = new Int32Array(2 * n);
  const out = bookPairs;
  out.set(pairs.subarray(at, at + 2 * n));
  const base = baseOf(residual);
  books.forEach((C, x) => {
    if (C === null) return;
    const count = C.length / 2;
    /** @type {MiddleIndex | undefined} */
    let index = INDEXES.get(C);
    if (index === undefined) INDEXES.set(C, (index = new MiddleIndex(C)));
    for (let v = x; v < n; v += 3) {
      if (!base(P[v])) continue;
      const bHi = BASE[1];
      const bLo = BASE[0] >>> 0;
      const j = index.countBelow(bHi, bLo);
      // exact within ±2^53; an e beyond rounds to a Number beyond every t all the same
      const t = j + (out[2 * v + 1] * TWO_32 + (out[2 * v] >>> 0));
      if (!(t >= 0 && t < count)) {
        const e = int64(out[2 * v + 1], out[2 * v]);
        throw formatError(VALUE, `section '${residual.section.id}', frame ${frameNumber}, vertex ${Math.floor(v / 3)}, axis ${'xyz'[x]}: t = j + e = ${j} + ${e} is outside 0..${count - 1}, the axis's codebook`);
      }
      const lo = (C[2 * t] >>> 0) - bLo;
      out[2 * v] = lo | 0;
      out[2 * v + 1] = (C[2 * t + 1] - bHi - (lo < 0 ? 1 : 0)) | 0;
    }
  });
  return out;
}

/** Scratch shared by correct(): one frame's binary32 values, and binary64 ones, with their bits. */
let scratch32 = new Float32Array(0);
let bits32 = new Int32Array(0);
let scratch64 = new Float64Array(0);
let bits64 = new Int32Array(0);

/**
 * One frame's decoded positions (§6.9): P (the exact reconstruction of §8.1) corrected by the
 * frame's integers, into `out` (a Float32Array receives the binary64 result rounded once, which
 * in domain float32 is the corrected binary32 value itself). In the domains grid and float64 a
 * P that is not finite is left so, unchecked: the caller reports it (R36) after every value
 * whose P is finite has been checked (R41), as the Python decoder does.
 * @returns {number} the first value whose decoded position is not finite (R36), or −1 The loops below work on one array
 * type each and return the first value that breaks R41 (or −1); the message is made here.
 * @param {Residual} residual
 * @param {Float64Array} P K·3 values
 * @param {Int32Array} pairs the chunk's integers (decodeChunk)
 * @param {number} first the index in the chunk of the frame's first integer, t·K·3
 * @param {Float64Array | Float32Array} out K·3 values
 * @param {number} frameNumber the frame within the file, for messages
 * @param {Codebooks | null} [books] the section's codebooks (decodeCodebooks), if it has any
 */
export function correct(residual, P, pairs, first, out, frameNumber, books = null) {
  if (!LITTLE_ENDIAN) throw new Error('corrections (§6.9) are decoded on little-endian engines only');
  const n = P.length;
  let at = 2 * first;
  if (books !== null && books.some((C) => C !== null)) {
    pairs = throughCodebooks(residual, books, P, pairs, at, frameNumber);
    at = 0;
  }
  let bad;
  if (residual.domain === 'float32') {
    if (scratch32.length < n) {
      scratch32 = new Float32Array(n);
      bits32 = new Int32Array(scratch32.buffer);
    }
    scratch32.set(P); // the binary32 nearest each P (ties to even; beyond the range, ±∞)
    bad = correctFloat32(P, bits32, pairs, at, n);
    if (bad < 0) {
      out.set(scratch32.subarray(0, n));
      return -1; // every binary32 value o stands for is finite
    }
  } else {
    // the result is made in binary64: in `out` itself when it is a Float64Array
    /** @type {Float64Array<ArrayBufferLike>} */
    let target = scratch64;
    /** @type {Int32Array<ArrayBufferLike>} */
    let bits = bits64;
    if (out instanceof Float64Array) {
      target = out;
      bits = new Int32Array(out.buffer, out.byteOffset, 2 * n);
    } else if (scratch64.length < n) {
      target = scratch64 = new Float64Array(n);
      bits = bits64 = new Int32Array(scratch64.buffer);
    }
    if (residual.domain === 'grid') {
      bad = correctGrid(P, residual.step, pairs, at, target, n);
    } else if (residual.domain === 'decimal-places') {
      bad = correctPlaces(P, /** @type {number} */ (residual.scale), pairs, at, target, n);
    } else if (residual.domain === 'decimal-digits' || residual.domain === 'decimal-digits-float32') {
      const float32 = residual.domain === 'decimal-digits-float32';
      bad = correctDigits(P, digitConstants(/** @type {number} */ (residual.scale)), pairs, at, target, n, float32);
    } else {
      if (target !== P) target.set(P);
      bad = correctFloat64(bits, pairs, at, n);
    }
    if (bad < 0) {
      if (target !== out) out.set(target.subarray(0, n));
      return -2 - bad;
    }
  }
  throw formatError(VALUE, `section '${residual.section.id}', frame ${frameNumber}, vertex ${Math.floor(bad / 3)}, axis ${'xyz'[bad % 3]}: ${why(residual, P[bad], pairs, at + 2 * bad)}`);
}

/**
 * Domain grid: P + step·e, one multiplication then one addition (JavaScript never fuses them).
 * Returns the first value that breaks R41, or −2 − j for the first value j not finite (from a
 * P that is not finite), or −1.
 * @param {Float64Array} P
 * @param {number} step
 * @param {Int32Array} pairs
 * @param {number} at
 * @param {Float64Array} out
 * @param {number} n
 */
function correctGrid(P, step, pairs, at, out, n) {
  let notFinite = -1;
  for (let j = 0; j < n; j++) {
    const hi = pairs[at + 2 * j + 1];
    const lo = pairs[at + 2 * j] >>> 0;
    // e in −2^53..2^53: a high half in −2^21..2^21 − 1, or e = 2^53 itself
    if ((hi < -GRID_HIGH || hi >= GRID_HIGH) && !(hi === GRID_HIGH && lo === 0)) return j;
    const value = P[j] + step * (hi * TWO_32 + lo); // e exact: |e| <= 2^53
    if (value - value !== 0) {
      // not finite from a finite P: R41; from a P that is not: R36, which the caller reports
      if (P[j] - P[j] === 0) return j;
      if (notFinite < 0) notFinite = j;
    }
    out[j] = value;
  }
  return -2 - notFinite;
}

/**
 * Domain float32: o = b + e, b the ordered integer of the binary32 nearest P (its bits given);
 * the bits of o's value are written over them.
 * @param {Float64Array} P
 * @param {Int32Array} bits
 * @param {Int32Array} pairs
 * @param {number} at
 * @param {number} n
 */
function correctFloat32(P, bits, pairs, at, n) {
  for (let j = 0; j < n; j++) {
    // NaN has no binary32 nearest it, and its bits are the engine's: no correction is defined
    if (P[j] !== P[j]) return j;
    const w = bits[j];
    const b = w < 0 ? w ^ 0x7fffffff : w; // the ordered integer
    const hi = pairs[at + 2 * j + 1];
    const lo = pairs[at + 2 * j] >>> 0;
    if (hi !== 0 && hi !== -1 && !(hi === 1 && lo === 0)) return j; // e outside −2^32..2^32
    const o = b + (hi * TWO_32 + lo); // exact
    if (o < F32_LOWEST || o > F32_HIGHEST) return j;
    bits[j] = o < 0 ? o ^ 0x7fffffff : o;
  }
  return -1;
}

/**
 * Domain float64: o = b + e wrapped to 64 bits, on the halves of P's bits (written over them).
 * Returns as correctGrid does.
 * @param {Int32Array} bits P's bits, interleaved halves
 * @param {Int32Array} pairs
 * @param {number} at
 * @param {number} n
 */
function correctFloat64(bits, pairs, at, n) {
  let notFinite = -1;
  for (let j = 0; j < n; j++) {
    let lo = bits[2 * j];
    let hi = bits[2 * j + 1];
    // a P that is not finite (all exponent bits set) stays so: R36, which the caller reports
    if ((hi & 0x7ff00000) === 0x7ff00000) {
      if (notFinite < 0) notFinite = j;
      continue;
    }
    if (hi < 0) {
      // the ordered integer of a negative pattern w is w XOR 0x7FFFFFFFFFFFFFFF
      hi ^= 0x7fffffff;
      lo = ~lo;
    }
    const sum = (lo >>> 0) + (pairs[at + 2 * j] >>> 0);
    const oHi = (hi + pairs[at + 2 * j + 1] + (sum >= TWO_32 ? 1 : 0)) | 0;
    if (oHi < F64_LOWEST_HIGH || oHi > F64_HIGHEST_HIGH) return j;
    if (oHi < 0) {
      bits[2 * j] = ~sum;
      bits[2 * j + 1] = oHi ^ 0x7fffffff;
    } else {
      bits[2 * j] = sum | 0;
      bits[2 * j + 1] = oHi;
    }
  }
  return -2 - notFinite;
}

/**
 * Why value j breaks R41, for the message (the slow path: BigInt is fine here).
 * @param {Residual} residual
 * @param {number} p P of the value
 * @param {Int32Array} pairs
 * @param {number} at the index of its low half
 */
function why(residual, p, pairs, at) {
  const e = BigInt.asIntN(64, (BigInt(pairs[at + 1]) << 32n) | BigInt(pairs[at] >>> 0));
  if (residual.domain === 'grid') {
    if (e > 2n ** 53n || e < -(2n ** 53n)) return `e = ${e} is outside −2^53..2^53`;
    return `P + step·e = ${p} + ${residual.step}·${e} is not finite`;
  }
  if (residual.domain === 'decimal-places') {
    if (e > 2n ** 54n || e < -(2n ** 54n)) return `e = ${e} is outside −2^54..2^54`;
    return `k = b + e (b the integer nearest P·10^${residual.scale}, P = ${p}; e = ${e}) is outside −2^53..2^53`;
  }
  if (residual.domain === 'decimal-digits' || residual.domain === 'decimal-digits-float32') {
    const { bound } = digitConstants(/** @type {number} */ (residual.scale));
    if (e > 2n * bound + 1n || e < -(2n * bound + 1n)) return `e = ${e} is outside ±(2L+1), L = ${bound}`;
    return `o = b + e (b the ordered decimal integer of P = ${p}; e = ${e}) is outside −1−L..L, L = ${bound}`;
  }
  const scratch = new DataView(new ArrayBuffer(8));
  if (residual.domain === 'float32') {
    if (p !== p) return 'P is NaN: no binary32 value is nearest it, so no correction is defined';
    if (e > 2n ** 32n || e < -(2n ** 32n)) return `e = ${e} is outside −2^32..2^32`;
    scratch.setFloat32(0, p);
    const w = scratch.getInt32(0);
    const o = BigInt(w < 0 ? w ^ 0x7fffffff : w) + e;
    return `b + e = ${o} is not the ordered integer of a finite binary32 (P = ${p}, e = ${e})`;
  }
  scratch.setFloat64(0, p);
  const w = scratch.getBigInt64(0);
  const b = w < 0n ? w ^ 0x7fffffffffffffffn : w;
  return `b + e = ${BigInt.asIntN(64, b + e)} is not the ordered integer of a finite binary64 (P = ${p}, e = ${e})`;
}

// ---------------------------------------------------------------------------------------------
// the decimal domains (§6.9): each map one correctly rounded binary64 operation against an exact
// power of ten, so that every decoder agrees

/**
 * Rounded to the nearest integer, ties to even (Math.round sends ties toward +∞).
 * @param {number} x
 */
function roundHalfEven(x) {
  const r = Math.round(x);
  return r - x === 0.5 && r % 2 !== 0 ? r - 1 : r;
}

/**
 * Domain decimal-places (d places): b = round(P·10^d) clamped to ±2^53, k = b + e, the position
 * k / 10^d. Returns as correctGrid does.
 * @param {Float64Array} P
 * @param {number} d
 * @param {Int32Array} pairs
 * @param {number} at
 * @param {Float64Array} out
 * @param {number} n
 */
function correctPlaces(P, d, pairs, at, out, n) {
  const ten = TEN[d];
  let notFinite = -1;
  for (let j = 0; j < n; j++) {
    const eHi = pairs[at + 2 * j + 1];
    const eLo = pairs[at + 2 * j] >>> 0;
    if ((eHi < -PLACES_E_HIGH || eHi >= PLACES_E_HIGH) && !(eHi === PLACES_E_HIGH && eLo === 0)) return j;
    const p = P[j];
    if (p - p !== 0) {
      // a P that is not finite stays so: R36, which the caller reports
      if (notFinite < 0) notFinite = j;
      out[j] = p;
      continue;
    }
    let b = roundHalfEven(p * ten); // ±∞ when the product overflows: clamped below
    if (b > TWO_53) b = TWO_53;
    else if (b < -TWO_53) b = -TWO_53;
    // k = b + e exactly, on halves (|b| <= 2^53 and |e| <= 2^54: no 64-bit overflow)
    const bHi = Math.floor(b / TWO_32);
    let kLo = b - bHi * TWO_32 + eLo;
    let kHi = bHi + eHi;
    if (kLo >= TWO_32) {
      kLo -= TWO_32;
      kHi += 1;
    }
    if ((kHi < -GRID_HIGH || kHi >= GRID_HIGH) && !(kHi === GRID_HIGH && kLo === 0)) return j;
    out[j] = (kHi * TWO_32 + kLo) / ten; // k exact: |k| <= 2^53
  }
  return -2 - notFinite;
}

/**
 * The constants of decimal-digits with p digits: E_min = p − 23, the significands' least
 * 10^(p−1), the decimals of a decade B = 9·10^(p−1), Q[j] the binary64 nearest 10^(E_min + j)
 * (j = 0..44, read from text as §6.9 says), L = 45·B, and the halves of the bounds on e
 * (±(2L + 1)) and on o (−1 − L .. L), which need more than 53 bits when p = 15.
 * @typedef {{digits: number, least: number, decade: number, powers: number[], bound: bigint,
 *   eHigh: number[], eLow: number[], oHigh: number[], oLow: number[]}} Digits
 */

/** @type {Map<number, Digits>} */
const DIGITS = new Map();

/** @param {number} p */
function digitConstants(p) {
  let found = DIGITS.get(p);
  if (found === undefined) {
    const least = TEN[p - 1];
    const lowest = p - 23;
    const bound = 45n * 9n * 10n ** BigInt(p - 1);
    found = {
      digits: p,
      least,
      decade: 9 * least,
      powers: Array.from({ length: 45 }, (_, j) => Number(`1e${lowest + j}`)),
      bound,
      eHigh: halvesOf(2n * bound + 1n),
      eLow: halvesOf(-(2n * bound + 1n)),
      oHigh: halvesOf(bound),
      oLow: halvesOf(-1n - bound),
    };
    DIGITS.set(p, found);
  }
  return found;
}

const INVERSE_32 = 2 ** -32;

/**
 * correctDigits for p <= 14, where L < 2^52: e (when in range), b and o (when in range) are
 * integers below 2^53, so plain binary64 arithmetic is exact, and an o out of range is seen
 * as such though its sum rounds (rounding is monotone and the bounds are exact).
 * @param {Float64Array} P
 * @param {Digits} c
 * @param {Int32Array} pairs
 * @param {number} at
 * @param {Float64Array} out
 * @param {number} n
 * @param {boolean} float32
 */
function correctDigitsNumber(P, c, pairs, at, out, n, float32) {
  const { least, decade: B, powers } = c;
  const L = Number(c.bound);
  const most = 10 * least - 1;
  const inverseB = 1 / B;
  const lowest = 23 - c.digits; // −E_min
  const bits = new Int32Array(P.buffer, P.byteOffset, 2 * P.length); // P's high halves: its exponent
  let notFinite = -1;
  for (let j = 0; j < n; j++) {
    const e = pairs[at + 2 * j + 1] * TWO_32 + (pairs[at + 2 * j] >>> 0); // exact when in range
    if (e > 2 * L + 1 || e < -2 * L - 1) return j;
    const x = P[j];
    if (x - x !== 0) {
      if (notFinite < 0) notFinite = j; // R36, which the caller reports
      out[j] = x;
      continue;
    }
    // b, the ordered decimal integer of x
    let b = 0;
    if (x !== 0) {
      const a = x < 0 ? -x : x;
      // the largest index with powers[index] <= a (or 0): guessed from a's binary exponent
      // (log10 2 ≈ 0.30103, within one decade), then stepped to the right one
      const binary = ((bits[2 * j + 1] >>> 20) & 0x7ff) - 1023;
      let lo = Math.floor(binary * 0.30103) + lowest;
      if (lo < 0) lo = 0;
      else if (lo > 44) lo = 44;
      while (lo < 44 && powers[lo + 1] <= a) lo++;
      while (lo > 0 && powers[lo] > a) lo--;
      const s = 22 - lo;
      let m = roundHalfEven(s >= 0 ? a * TEN[s] : a / TEN[-s]);
      if (m < least) m = least;
      else if (m > most) m = most;
      b = lo * B + (1 + m - least);
    }
    if (x < 0 || (x === 0 && 1 / x < 0)) b = -1 - b;
    const o = b + e;
    if (o > L || o < -1 - L) return j;
    const negative = o < 0;
    const magnitude = negative ? -1 - o : o;
    if (magnitude === 0) {
      out[j] = negative ? -0 : 0;
      continue;
    }
    const q = magnitude - 1;
    let decade = Math.floor(q * inverseB); // within one of the quotient: corrected below
    let offset = q - decade * B; // exact
    if (offset < 0) {
      decade -= 1;
      offset += B;
    } else if (offset >= B) {
      decade += 1;
      offset -= B;
    }
    const significand = least + offset;
    const s = 22 - decade;
    const value = s > 0 ? significand / TEN[s] : significand * TEN[-s];
    const signed = negative ? -value : value;
    out[j] = float32 ? Math.fround(signed) : signed;
  }
  return -2 - notFinite;
}

/**
 * Whether hi·2^32 + lo (lo in 0..2^32 − 1) is within [low, high], each given as halves.
 * @param {number} hi
 * @param {number} lo
 * @param {number[]} low
 * @param {number[]} high
 */
function within(hi, lo, low, high) {
  if (hi < low[0] || (hi === low[0] && lo < low[1])) return false;
  return !(hi > high[0] || (hi === high[0] && lo > high[1]));
}

/**
 * The ordered decimal integer b of a finite x (§6.9) into BASE, as halves: exact for every p,
 * though it reaches 2^57 when p = 15.
 * @param {number} x
 * @param {Digits} c
 */
function digitsBase(x, c) {
  const { least, decade: B, powers } = c;
  let bHi = 0;
  let bLo = 0;
  if (x !== 0) {
    const a = Math.abs(x);
    // the largest index with powers[index] <= a, or 0 if there is none
    let lo = 0;
    let hi = 44;
    if (powers[0] > a) hi = 0;
    while (lo < hi) {
      const mid = (lo + hi + 1) >> 1;
      if (powers[mid] <= a) lo = mid;
      else hi = mid - 1;
    }
    const s = 22 - lo; // p − 1 − (E_min + index)
    let m = roundHalfEven(s >= 0 ? a * TEN[s] : a / TEN[-s]);
    if (m < least) m = least;
    else if (m > 10 * least - 1) m = 10 * least - 1;
    // o = index·B + (1 + m − 10^(p−1)): both terms exact, their sum on halves
    const X = lo * B;
    const Y = 1 + m - least;
    const xh = Math.floor(X * INVERSE_32);
    const yh = Math.floor(Y * INVERSE_32);
    bLo = X - xh * TWO_32 + (Y - yh * TWO_32);
    bHi = xh + yh;
    if (bLo >= TWO_32) {
      bLo -= TWO_32;
      bHi += 1;
    }
  }
  if (x < 0 || Object.is(x, -0)) {
    // −1 − o
    bHi = -bHi - 1;
    bLo = TWO_32 - 1 - bLo;
  }
  BASE[0] = bLo;
  BASE[1] = bHi;
}

/**
 * Domain decimal-digits (p digits): b the ordered decimal integer of P, o = b + e, the position
 * the value of o (§6.9); in decimal-digits-float32 (`float32`) that value rounded to binary32.
 * The integers reach 2^57 when p = 15, so they are added on halves, and o's decade is found
 * with a division corrected by its exact remainder. Returns as correctGrid.
 * @param {Float64Array} P
 * @param {Digits} c
 * @param {Int32Array} pairs
 * @param {number} at
 * @param {Float64Array} out
 * @param {number} n
 * @param {boolean} float32
 */
function correctDigits(P, c, pairs, at, out, n, float32) {
  if (c.bound < 2n ** 52n) return correctDigitsNumber(P, c, pairs, at, out, n, float32);
  const { least, decade: B } = c;
  let notFinite = -1;
  for (let j = 0; j < n; j++) {
    const eHi = pairs[at + 2 * j + 1];
    const eLo = pairs[at + 2 * j] >>> 0;
    if (!within(eHi, eLo, c.eLow, c.eHigh)) return j;
    const x = P[j];
    if (x - x !== 0) {
      if (notFinite < 0) notFinite = j; // R36, which the caller reports
      out[j] = x;
      continue;
    }
    digitsBase(x, c);
    const bHi = BASE[1];
    const bLo = BASE[0] >>> 0;
    let oLo = bLo + eLo;
    let oHi = bHi + eHi;
    if (oLo >= TWO_32) {
      oLo -= TWO_32;
      oHi += 1;
    }
    if (!within(oHi, oLo, c.oLow, c.oHigh)) return j;
    // the value of o: its magnitude's decade and significand, then one operation
    const negative = oHi < 0;
    let mh = oHi;
    let ml = oLo;
    if (negative) {
      mh = -oHi - 1;
      ml = TWO_32 - 1 - oLo;
    }
    if (mh === 0 && ml === 0) {
      out[j] = negative ? -0 : 0;
      continue;
    }
    // q = magnitude − 1 = decade·B + offset
    let ql = ml - 1;
    let qh = mh;
    if (ql < 0) {
      ql += TWO_32;
      qh -= 1;
    }
    let decade = Math.floor((qh * TWO_32 + ql) / B); // off by at most one where q passes 2^53
    // exact: qh·2^32 and decade·B are exact, their difference a multiple of 2^(p−1) below
    // 2^57 (so of at most 43 significant bits), and the offset a small integer
    let offset = qh * TWO_32 - decade * B + ql;
    if (offset < 0) {
      decade -= 1;
      offset += B;
    } else if (offset >= B) {
      decade += 1;
      offset -= B;
    }
    const significand = least + offset;
    const s = 22 - decade;
    const value = s > 0 ? significand / TEN[s] : significand * TEN[-s];
    const signed = negative ? -value : value;
    out[j] = float32 ? Math.fround(signed) : signed; // ties to even, like any binary32 rounding
  }
  return -2 - notFinite;
}
