// Sections FLD.n (codec `field`, format 1.5, spec/FORMAT.md §6.13): animated fields, c values
// (1 to 4) per vertex or per face per frame (velocities, colours, simulation data), each stored
// in one of three modes:
//
// - `tucker`: each frame's per-component mean (FLD.n.MEAN, F × c) and a Tucker decomposition
//   of the rest, the qmat sections FLD.n.U1 (N × i), FLD.n.U3 (F × k) and FLD.n.CORE (i·c·k),
//   with U2 (c × c) in the parameters; a frame is reconstructed in binary64 and rounded to the
//   field's type, as the positions are (§8).
// - `grid`: integers q whose values are q · step; `exact`: the ordered integers (§6.9) of the
//   values' binary32 or binary64 bits. Both are predicted along frames within chunks of
//   `chunk_frames` frames, each chunk one zstd frame of 64-bit integers in byte planes; a frame
//   decodes only its own chunk. The integers are held as 32-bit halves (decodeWideStream), so
//   the float64 bit patterns are made exactly with no BigInt per value.
//
// checkFieldParams checks the parameters in §6.13's order (R45-field) and every size against
// the limits (R21) before anything is read; FieldReader decodes frames and keeps what a next
// frame of the same field reuses (the tucker factors, the last chunk).

import { formatError, limitError } from './errors.js';
import { MsgFloat, describe, isInt } from './msgpack.js';
import { nameProblem } from './attributes.js';
import { decodeQmat } from './qmat.js';
import { decodeWideStream } from './streams.js';

const RULE = 'R45-field';
export const FIELD_ROLES = Object.freeze(['velocity', 'color', 'generic']);
const DOMAINS = Object.freeze(['vertex', 'face']);
const TYPES = Object.freeze(['f32', 'f64']);
const MODES = Object.freeze(['tucker', 'grid', 'exact']);
/** The qmat sections of a field in mode tucker, in the order they are read. */
const PARTS = Object.freeze(['U1', 'U3', 'CORE', 'MEAN']);
const MAX_CHUNK_PLANES = 8;
const TWO32 = 4294967296;
/** A grid integer's largest |q| (2^53): hi half 2^21 with a zero low half. */
const GRID_HI = 2 ** 21;
/** The ordered integers of finite binary32 values (§6.9), and the high halves of binary64's. */
const FINITE32 = [-2139095040, 2139095039];
const FINITE64_HI = [-2146435072, 2146435071];

/**
 * @typedef {import('./container.js').Section} Section
 * @typedef {import('./msgpack.js').MsgValue} MsgValue
 * @typedef {import('./limits.js').Limits} Limits
 * @typedef {Float32Array | Float64Array} FieldValues
 * @typedef {{name: string, role: 'velocity' | 'color' | 'generic', domain: 'vertex' | 'face',
 *   components: number, type: 'f32' | 'f64', mode: 'tucker' | 'grid' | 'exact'}} FieldInfo
 *   a field's description: N·components values per frame, N the vertices or the faces
 * @typedef {{i: number, k: number, u2: Float64Array, sections: Section[]}} TuckerParams
 *   ranks, U2 (c × c row-major) and the sections U1, U3, CORE, MEAN
 * @typedef {{step: number, predict: number, chunkFrames: number, planes: number[],
 *   offsets: number[]}} ChunkParams each chunk's planes, and its byte offsets (one more)
 * @typedef {FieldInfo & {id: string, elements: number, frames: number,
 *   tucker: TuckerParams | null, chunks: ChunkParams | null}} FieldParams
 * @typedef {{vertices: number, faces: number, frames: number}} Counts K, M and F
 */

/**
 * @param {string} where
 * @param {string} message
 * @returns {never}
 */
function refuse(where, message) {
  throw formatError(RULE, `${where}: ${message}`);
}

/** @param {MsgValue | undefined} value */
function shown(value) {
  return value === undefined ? 'nothing' : describe(value);
}

/**
 * R21 unless `value` is within the limit `name`.
 * @param {bigint | number} value
 * @param {Limits} limits
 * @param {keyof Limits} name
 * @param {string} what
 */
function checkLimit(value, limits, name, what) {
  if (BigInt(value) > BigInt(limits[name])) {
    throw limitError('R21-header-limit', `${what} exceed this decoder's limit ${name} = ${limits[name]}`);
  }
}

/**
 * §6.13 for the section FLD.n: the descriptor's parameters in order (R45-field), the values'
 * count against max_positions (R21), the mode's parameters, and for mode tucker the payload's
 * emptiness and the sub-sections (present, each's shape R28 and size R21). Nothing is read.
 * @param {Section} section
 * @param {Map<string, Section>} factors the file's FLD.n.X sections by id
 * @param {Counts} counts
 * @param {Limits} limits
 * @returns {FieldParams}
 */
export function checkFieldParams(section, factors, counts, limits) {
  const where = `section '${section.id}'`;
  const info = readInfo(section.entry, where);
  const elements = info.domain === 'face' ? counts.faces : counts.vertices;
  const frames = counts.frames;
  // a position is 3 values: a field may decode as many values as max_positions positions
  const values = BigInt(frames) * BigInt(elements) * BigInt(info.components);
  checkLimit((values + 2n) / 3n, limits, 'max_positions', `${where}: ${frames} × ${elements} × ${info.components} field values (as positions of 3)`);
  /** @type {FieldParams} */
  const params = { ...info, id: section.id, elements, frames, tucker: null, chunks: null };
  if (info.mode === 'tucker') {
    params.tucker = readTucker(section, params, factors, limits);
  } else {
    params.chunks = readChunks(section, params, limits);
  }
  return params;
}

/**
 * `name`, `role`, `domain`, `components`, `type`, `mode`, in that order (R45-field).
 * @param {Map<string, MsgValue>} entry
 * @param {string} where
 * @returns {FieldInfo}
 */
function readInfo(entry, where) {
  const name = entry.get('name');
  if (typeof name !== 'string') refuse(where, `"name" must be a str, got ${shown(name)}`);
  const problem = nameProblem(name);
  if (problem !== null) refuse(where, `the name ${JSON.stringify(name)} ${problem}`);
  const role = entry.get('role');
  if (typeof role !== 'string') refuse(where, `"role" must be a str, got ${shown(role)}`);
  const domain = entry.get('domain');
  if (typeof domain !== 'string' || !DOMAINS.includes(domain)) refuse(where, `"domain" must be vertex or face, got ${shown(domain)}`);
  const components = entry.get('components');
  if (!isInt(components) || !(components >= 1 && components <= 4)) refuse(where, `"components" must be an int from 1 to 4, got ${shown(components)}`);
  const type = entry.get('type');
  if (typeof type !== 'string' || !TYPES.includes(type)) refuse(where, `"type" must be f32 or f64, got ${shown(type)}`);
  const mode = entry.get('mode');
  if (typeof mode !== 'string' || !MODES.includes(mode)) refuse(where, `"mode" must be one of ${MODES.join(', ')}, got ${shown(mode)}`);
  return {
    name,
    role: /** @type {FieldInfo['role']} */ (FIELD_ROLES.includes(role) ? role : 'generic'), // any other str is generic
    domain: /** @type {FieldInfo['domain']} */ (domain),
    components: Number(components),
    type: /** @type {FieldInfo['type']} */ (type),
    mode: /** @type {FieldInfo['mode']} */ (mode),
  };
}

/**
 * Mode tucker: `ranks` [i, k] (1 <= i <= N, 1 <= k <= F), `u2` (c·c finite floats), both
 * R45; the factors against max_factor_values (R21); an empty payload (R45); then each
 * sub-section present (R45), of its shape (R28) and size (R21).
 * @param {Section} section
 * @param {FieldParams} params
 * @param {Map<string, Section>} factors
 * @param {Limits} limits
 * @returns {TuckerParams}
 */
function readTucker(section, params, factors, limits) {
  const where = `section '${section.id}'`;
  const { elements: n, frames, components: c } = params;
  const ranks = section.entry.get('ranks');
  if (!Array.isArray(ranks) || ranks.length !== 2 || !ranks.every(isInt) || !(ranks[0] >= 1 && ranks[0] <= n) || !(ranks[1] >= 1 && ranks[1] <= frames)) {
    refuse(where, `"ranks" must be [i, k], 1 <= i <= ${n}, 1 <= k <= ${frames}, got ${shown(ranks)}`);
  }
  const u2 = section.entry.get('u2');
  if (!Array.isArray(u2) || u2.length !== c * c || !u2.every((x) => x instanceof MsgFloat && Number.isFinite(x.value))) {
    refuse(where, `"u2" must be ${c * c} finite floats, got ${shown(u2)}`);
  }
  const [i, k] = ranks.map(Number);
  const factorValues = BigInt(n) * BigInt(i) + BigInt(frames) * BigInt(k) + BigInt(c * i) * BigInt(k) + BigInt(c * frames);
  checkLimit(factorValues, limits, 'max_factor_values', `${where}: the factors of ranks (${i}, ${c}, ${k}) on ${n} elements and ${frames} frames`);
  if (section.length !== 0) refuse(where, `a field in mode tucker has an empty payload, not ${section.length} bytes`);
  /** @type {{[part: string]: number[]}} */
  const shapes = { U1: [n, i], U3: [frames, k], CORE: [i * c * k, 1], MEAN: [frames, c] };
  const sections = PARTS.map((part) => {
    const id = `${section.id}.${part}`;
    const found = factors.get(id);
    if (found === undefined) refuse(`section '${id}'`, 'a field in mode tucker needs this section; it is missing');
    expectShape(found, shapes[part], limits);
    return found;
  });
  return { i, k, u2: Float64Array.from(/** @type {MsgFloat[]} */ (u2), (x) => x.value), sections };
}

/**
 * A sub-section's `shape` is [rows, cols] (R28-shape) and rows·cols·4 bytes fit
 * max_section_bytes (R21), as §5 step 13 checks U1's.
 * @param {Section} section
 * @param {number[]} expected
 * @param {Limits} limits
 */
function expectShape(section, expected, limits) {
  const shape = section.entry.get('shape');
  if (!Array.isArray(shape) || shape.length !== 2 || !shape.every((v) => isInt(v) && v >= 0)) {
    throw formatError('R28-shape', `section '${section.id}': "shape" is ${shown(shape)}, not an array of two ints >= 0`);
  }
  if (BigInt(/** @type {number | bigint} */ (shape[0])) !== BigInt(expected[0]) || BigInt(/** @type {number | bigint} */ (shape[1])) !== BigInt(expected[1])) {
    throw formatError('R28-shape', `section '${section.id}' has shape [${shape.join(', ')}]; its field makes it [${expected.join(', ')}]`);
  }
  checkLimit(BigInt(expected[0]) * BigInt(expected[1]) * 4n, limits, 'max_section_bytes', `section '${section.id}': ${expected[0]} × ${expected[1]} values of up to 4 bytes`);
}

/**
 * Modes grid and exact: `step` (grid: a finite float > 0), `predict` (0, 1 or 2),
 * `chunk_frames` (an int >= 1), `chunks` (⌈F / chunk_frames⌉ [planes 1..8, length >= 0]
 * whose lengths add up to the payload's), all R45; then each chunk's size against
 * max_section_bytes and, for a chunk of several frames, max_chunk_values (R21).
 * @param {Section} section
 * @param {FieldParams} params
 * @param {Limits} limits
 * @returns {ChunkParams}
 */
function readChunks(section, params, limits) {
  const where = `section '${section.id}'`;
  const entry = section.entry;
  let step = 0;
  if (params.mode === 'grid') {
    const given = entry.get('step');
    if (!(given instanceof MsgFloat) || !Number.isFinite(given.value) || !(given.value > 0)) refuse(where, `"step" must be a finite float > 0, got ${shown(given)}`);
    step = given.value;
  }
  const predict = entry.get('predict');
  if (!isInt(predict) || !(predict === 0 || predict === 1 || predict === 2)) refuse(where, `"predict" must be 0, 1 or 2, got ${shown(predict)}`);
  const given = entry.get('chunk_frames');
  if (!isInt(given) || !(given >= 1)) refuse(where, `"chunk_frames" must be an int >= 1, got ${shown(given)}`);
  const frames = params.frames;
  const chunkFrames = given > frames ? Math.max(1, frames) : Number(given); // a larger one is one chunk
  const count = Math.ceil(frames / chunkFrames);
  const table = entry.get('chunks');
  if (!Array.isArray(table) || table.length !== count) refuse(where, `"chunks" must be an array of ${count} [planes, length], got ${shown(table)}`);
  const planes = [];
  const offsets = [0];
  let total = 0n;
  for (const [number, chunk] of table.entries()) {
    if (!Array.isArray(chunk) || chunk.length !== 2 || !chunk.every(isInt) || !(chunk[0] >= 1 && chunk[0] <= MAX_CHUNK_PLANES) || !(chunk[1] >= 0)) {
      refuse(where, `chunk ${number} is [planes 1..${MAX_CHUNK_PLANES}, length >= 0], got ${shown(chunk)}`);
    }
    planes.push(Number(chunk[0]));
    total += BigInt(/** @type {number | bigint} */ (chunk[1]));
    offsets.push(Number(total));
  }
  if (total !== BigInt(section.length)) refuse(where, `the chunks' lengths add up to ${total} bytes, the payload has ${section.length}`);
  const perFrame = params.elements * params.components;
  planes.forEach((p, number) => {
    const rows = Math.min(frames, (number + 1) * chunkFrames) - number * chunkFrames;
    checkLimit(BigInt(rows * perFrame) * BigInt(p), limits, 'max_section_bytes', `${where}: chunk ${number}'s ${rows * perFrame} integers of ${p} bytes`);
    // a frame costs its whole chunk: a chunk of several frames is held to a size of its own
    if (rows > 1) checkLimit(rows * perFrame, limits, 'max_chunk_values', `${where}: chunk ${number}'s ${rows * perFrame} integers (${rows} frames)`);
  });
  return { step, predict: Number(predict), chunkFrames, planes, offsets };
}

/**
 * A chunk's values, frame-major (frames of the chunk × N × c): its zstd frame (R29), the
 * running sums of `predict` (wrapping at 64 bits), then each value (R45).
 * @param {FieldParams} params
 * @param {ChunkParams} chunks
 * @param {Uint8Array} payload the descriptor's payload, CRC checked
 * @param {number} chunk
 * @returns {FieldValues}
 */
export function decodeFieldChunk(params, chunks, payload, chunk) {
  const where = `section '${params.id}' chunk ${chunk}`;
  const start = chunk * chunks.chunkFrames;
  const rows = Math.min(params.frames, start + chunks.chunkFrames) - start;
  const perFrame = params.elements * params.components;
  const piece = payload.subarray(chunks.offsets[chunk], chunks.offsets[chunk + 1]);
  const halves = decodeWideStream(piece, rows * perFrame, chunks.planes[chunk], where);
  for (let pass = 0; pass < chunks.predict; pass++) runningSum(halves, 2 * perFrame);
  if (params.mode === 'grid') return gridValues(halves, chunks.step, params.type, where);
  return params.type === 'f32' ? exact32(halves, where) : exact64(halves, where);
}

/**
 * A running sum along frames, in place: each 64-bit value (two halves) plus the one a frame
 * before (`stride` halves back), wrapping, as the encoder's int64 arithmetic did.
 * @param {Int32Array} halves
 * @param {number} stride
 */
function runningSum(halves, stride) {
  for (let j = stride; j < halves.length; j += 2) {
    const sum = (halves[j] >>> 0) + (halves[j - stride] >>> 0);
    halves[j + 1] = (halves[j + 1] + halves[j - stride + 1] + (sum > 0xffffffff ? 1 : 0)) | 0;
    halves[j] = sum | 0;
  }
}

/**
 * Grid values: q · step in binary64 rounded to the type; |q| <= 2^53 and finite values (R45).
 * @param {Int32Array} halves
 * @param {number} step
 * @param {'f32' | 'f64'} type
 * @param {string} where
 * @returns {FieldValues}
 */
function gridValues(halves, step, type, where) {
  const count = halves.length / 2;
  const out = type === 'f32' ? new Float32Array(count) : new Float64Array(count);
  for (let j = 0; j < count; j++) {
    const lo = halves[2 * j] >>> 0;
    const hi = halves[2 * j + 1];
    // within ±2^53 the two halves make q exactly: hi in -2^21..2^21-1, or 2^53 itself
    if (!(hi >= -GRID_HI && (hi < GRID_HI || (hi === GRID_HI && lo === 0)))) refuse(where, `value ${j}'s grid integer is beyond ±2^53`);
    out[j] = (hi * TWO32 + lo) * step;
    if (!Number.isFinite(out[j])) refuse(where, `value ${j} (q · step) is not finite`);
  }
  return out;
}

/**
 * Exact binary32 values from their ordered integers, each that of a finite value (R45).
 * @param {Int32Array} halves
 * @param {string} where
 */
function exact32(halves, where) {
  const count = halves.length / 2;
  const bits = new Int32Array(count);
  for (let j = 0; j < count; j++) {
    const lo = halves[2 * j];
    // an int64 within FINITE32: its high half is its low half's sign
    if (halves[2 * j + 1] !== lo >> 31 || lo < FINITE32[0] || lo > FINITE32[1]) refuse(where, `value ${j} is not the ordered integer of a finite binary32`);
    bits[j] = lo < 0 ? lo ^ 0x7fffffff : lo; // the ordered map is its own inverse (§6.9)
  }
  return new Float32Array(bits.buffer);
}

/**
 * Exact binary64 values from their ordered integers, each that of a finite value (R45).
 * @param {Int32Array} halves
 * @param {string} where
 */
function exact64(halves, where) {
  const count = halves.length / 2;
  for (let j = 0; j < count; j++) {
    const hi = halves[2 * j + 1];
    if (hi < FINITE64_HI[0] || hi > FINITE64_HI[1]) refuse(where, `value ${j} is not the ordered integer of a finite binary64`);
    if (hi < 0) {
      halves[2 * j] = ~halves[2 * j];
      halves[2 * j + 1] = hi ^ 0x7fffffff;
    }
  }
  return new Float64Array(halves.buffer, halves.byteOffset, count);
}

/**
 * @typedef {{u1: Float64Array, u3: Float64Array, mean: Float64Array, basis: Float64Array}}
 *   TuckerFactors dequantized U1 (N × i), U3 (F × k), MEAN (F × c) and CORE times U2:
 *   basis[a, x, b] = Σ_d CORE[a, d, b] · U2[x, d] (i × c × k), all row-major
 */

/**
 * The qmat sections of a field in mode tucker, each CRC-checked then decoded (R30-R32, R29):
 * U1 (a vertex field's over the mesh parents: predictors 0, 1, 2; a face field's predictor 0),
 * U3 and MEAN (along frames: 0, 1, 3) and CORE (0), whatever the preamble's flag bit 1.
 * @param {FieldParams} params
 * @param {(section: Section) => Uint8Array} payloadOf
 * @param {() => import('./topology.js').Topology} topology the file's mesh topology
 * @returns {TuckerFactors}
 */
export function decodeTuckerFactors(params, payloadOf, topology) {
  const { i, k, u2, sections: [u1s, u3s, cores, means] } = /** @type {TuckerParams} */ (params.tucker);
  const { elements: n, frames, components: c } = params;
  // every predictor of 1.2; zstd planes only (coder absent or 0: §6.14 allows 1 only in a
  // position factor)
  /** @type {import('./qmat.js').Coding} */
  const coding = { tools: true, adaptive: false };
  const u1 = decodeQmat(u1s, payloadOf(u1s), n, i, params.domain === 'vertex' ? 'mesh' : 'none', coding, topology);
  const u3 = decodeQmat(u3s, payloadOf(u3s), frames, k, 'time', coding, topology);
  const core = decodeQmat(cores, payloadOf(cores), i * c * k, 1, 'none', coding, topology);
  const mean = decodeQmat(means, payloadOf(means), frames, c, 'time', coding, topology);
  const basis = new Float64Array(i * c * k);
  for (let a = 0; a < i; a++) {
    for (let x = 0; x < c; x++) {
      for (let b = 0; b < k; b++) {
        let sum = 0;
        for (let d = 0; d < c; d++) sum += core[(a * c + d) * k + b] * u2[x * c + d];
        basis[(a * c + x) * k + b] = sum;
      }
    }
  }
  return { u1, u3, mean, basis };
}

/**
 * Frame f of a field in mode tucker: Σ_a U1[e, a] · (Σ_b basis[a, x, b] · U3[f, b]) +
 * MEAN[f, x] in binary64, rounded to the type by `out`; every value finite (R45).
 * @template {FieldValues} T
 * @param {FieldParams} params
 * @param {TuckerFactors} factors
 * @param {number} f
 * @param {T} out N·c values
 * @returns {T}
 */
export function tuckerFrame(params, factors, f, out) {
  const { i, k } = /** @type {TuckerParams} */ (params.tucker);
  const { elements: n, components: c } = params;
  const { u1, u3, mean, basis } = factors;
  // the frame's weights, component-major so that each value is a dot product of two rows
  const weights = new Float64Array(c * i);
  for (let a = 0; a < i; a++) {
    for (let x = 0; x < c; x++) {
      let sum = 0;
      for (let b = 0; b < k; b++) sum += basis[(a * c + x) * k + b] * u3[f * k + b];
      weights[x * i + a] = sum;
    }
  }
  const sums = new Float64Array(n * c); // binary64, then rounded to the type by out.set
  for (let e = 0; e < n; e++) {
    const row = e * i;
    for (let x = 0; x < c; x++) {
      const w = x * i;
      let sum = 0;
      for (let a = 0; a < i; a++) sum += u1[row + a] * weights[w + a];
      sums[e * c + x] = sum + mean[f * c + x];
    }
  }
  out.set(sums);
  for (let at = 0; at < out.length; at++) {
    if (!Number.isFinite(out[at])) {
      refuse(`section '${params.id}'`, `frame ${f}, ${params.domain} ${Math.floor(at / c)}: a reconstructed value is not finite`);
    }
  }
  return out;
}

/**
 * A file's fields, decoded on demand: the parameters of each when first needed, a tucker
 * field's factors once, and a chunked field's last chunk (the next frames of a playing field
 * are usually in it).
 */
export class FieldReader {
  /**
   * @param {Section[]} sections the FLD.n, in order
   * @param {Map<string, Section>} factors the FLD.n.X by id
   * @param {Counts} counts
   * @param {Limits} limits
   * @param {(section: Section) => Uint8Array} payloadOf a section's payload, CRC checked (R19)
   * @param {() => import('./topology.js').Topology} topology the file's mesh topology
   */
  constructor(sections, factors, counts, limits, payloadOf, topology) {
    this._sections = sections;
    this._factors = factors;
    this._counts = counts;
    this._limits = limits;
    this._payloadOf = payloadOf;
    this._topology = topology;
    /** @type {Map<number, FieldParams>} */
    this._params = new Map();
    /** @type {Map<number, TuckerFactors>} */
    this._tucker = new Map();
    /** @type {Map<number, {chunk: number, values: FieldValues}>} */
    this._lastChunk = new Map();
  }

  /** The number of fields. */
  get count() {
    return this._sections.length;
  }

  /**
   * Field n's checked parameters.
   * @param {number} n
   * @returns {FieldParams}
   */
  params(n) {
    if (!Number.isInteger(n) || n < 0 || n >= this.count) {
      throw new RangeError(`field ${n} does not exist: the file has ${this.count} fields`);
    }
    let params = this._params.get(n);
    if (params === undefined) {
      params = checkFieldParams(this._sections[n], this._factors, this._counts, this._limits);
      this._params.set(n, params);
    }
    return params;
  }

  /**
   * Every field's name, each field's parameters checked, and no two the same (R45-field).
   * @returns {string[]}
   */
  names() {
    const names = Array.from({ length: this.count }, (_, n) => this.params(n).name);
    names.forEach((name, n) => {
      if (names.indexOf(name) !== n) refuse(`section FLD.${n}.name`, `two fields are named ${JSON.stringify(name)}`);
    });
    return names;
  }

  /**
   * The number of the field `which` names (its number, or the first of that name).
   * @param {number | string} which
   */
  number(which) {
    if (typeof which === 'number') {
      this.params(which);
      return which;
    }
    for (let n = 0; n < this.count; n++) if (this.params(n).name === which) return n;
    throw new RangeError(`the file has no field named ${JSON.stringify(which)}`);
  }

  /**
   * Frame f of field n: N·c values, element-major, of the field's type.
   * @param {number} n
   * @param {number} f
   * @returns {FieldValues}
   */
  frame(n, f) {
    const params = this.params(n);
    if (!Number.isInteger(f) || f < 0 || f >= params.frames) {
      throw new RangeError(`frame ${f} does not exist: the file has frames 0..${params.frames - 1}`);
    }
    const size = params.elements * params.components;
    if (params.tucker !== null) {
      let factors = this._tucker.get(n);
      if (factors === undefined) {
        factors = decodeTuckerFactors(params, this._payloadOf, this._topology);
        this._tucker.set(n, factors);
      }
      return tuckerFrame(params, factors, f, params.type === 'f32' ? new Float32Array(size) : new Float64Array(size));
    }
    const chunks = /** @type {ChunkParams} */ (params.chunks);
    const chunk = Math.floor(f / chunks.chunkFrames);
    let last = this._lastChunk.get(n);
    if (last === undefined || last.chunk !== chunk) {
      const values = decodeFieldChunk(params, chunks, this._payloadOf(this._sections[n]), chunk);
      last = { chunk, values };
      this._lastChunk.set(n, last);
    }
    const at = (f - chunk * chunks.chunkFrames) * size;
    return last.values.slice(at, at + size);
  }

  /** Decodes every frame of every field, in order (the Python `Decoder.check()`'s fields). */
  checkAll() {
    this.names();
    for (let n = 0; n < this.count; n++) {
      const { frames } = this.params(n);
      for (let f = 0; f < frames; f++) this.frame(n, f);
    }
  }
}
