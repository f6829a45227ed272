// The JavaScript decoder of the tuckercodec format, written from spec/FORMAT.md (version 1.9):
// openTkc(bytes) checks the container and header, decodes the faces and names, and, for a file
// that is not segmented, every factor and its corrections' parameters; a segmented file's
// segments are decoded when one of their frames is asked for (§6.7), and the two most recently
// used are kept (as the Python decoder keeps them; openTkc's cachedSegments). A file with
// corrections (§6.9) decodes a chunk of them when one of its frames is first asked for, and
// keeps the last few chunks. Every failure is a TkcError carrying its §11 rule.
//
//   import { openTkc } from './tkc/decoder.js';
//   const file = openTkc(new Uint8Array(await (await fetch('a.tkc')).arrayBuffer()));
//   const positions = file.frame(12);  // Float64Array K*3: x, y, z of each vertex
//
// No DOM and no build step: the same modules run in node and in browsers.

import { findAttachments } from './attachments.js';
import { checkAttributeParams, decodeAttribute } from './attributes.js';
import { readContainer, sectionPayload } from './container.js';
import { formatError } from './errors.js';
import { decodeFaceOrder, inGivenOrder } from './face_order.js';
import { decodeFaceSets } from './face_sets.js';
import { decodeFaces, fanTriangles } from './faces.js';
import { FieldReader } from './fields.js';
import { readLayout } from './header.js';
import { resolveLimits } from './limits.js';
import { MsgFloat, isInt } from './msgpack.js';
import { decodeNames, defaultNames, nameSize } from './names.js';
import { decodeQmat } from './qmat.js';
import { coreTimesU2, exactWeights, reconstructExact, reconstructFrame, weightsFit } from './reconstruct.js';
import { correct, decodeChunk, decodeCodebooks, readResidual } from './residual.js';
import { simdBasis } from './simd.js';
import { meshTopology } from './topology.js';

export { TkcError } from './errors.js';
export { DEFAULT_LIMITS } from './limits.js';

/** Bytes of decoded correction chunks a file keeps (at least the last one, whatever its size). */
const CHUNK_CACHE_BYTES = 64 * 2 ** 20;
/**
 * Decoded segments a file keeps by default, the most recently used: the Python decoder's two, so
 * that playing a long segmented file (in a loop, say) holds two segments' factors, not all.
 */
export const CACHED_SEGMENTS = 2;

/**
 * @typedef {import('./reconstruct.js').Factors} Factors
 * @typedef {import('./residual.js').Residual} Residual
 * @typedef {import('./simd.js').SimdBasis} SimdBasis
 * @typedef {import('./topology.js').Topology} Topology
 * @typedef {import('./attributes.js').Attribute} Attribute
 * @typedef {import('./face_sets.js').FaceSet} FaceSet
 * @typedef {import('./fields.js').FieldInfo} FieldInfo
 */

/**
 * Opens a .tkc file held in memory.
 * @param {Uint8Array|ArrayBuffer} bytes the whole file
 * @param {{limits?: {[name: string]: number}, simd?: boolean, cachedSegments?: number}} [options] decoder limits (§7) to use instead of the
 *   defaults; `simd: false` reconstructs frames with the JavaScript loop instead of WebAssembly
 *   SIMD (the same bits, five times slower: for tests and engines that misbehave);
 *   `cachedSegments`: how many decoded segments of a segmented file to keep, the most recently
 *   used (an int >= 1, default CACHED_SEGMENTS = 2; the others are decoded again when needed)
 * @returns {TkcFile}
 * @throws {TkcError} when the file breaks a rule of §11
 */
export function openTkc(bytes, options = {}) {
  const data = bytes instanceof Uint8Array ? bytes : new Uint8Array(bytes);
  const cached = options.cachedSegments ?? CACHED_SEGMENTS;
  if (!Number.isInteger(cached) || cached < 1) throw new TypeError(`cachedSegments must be an int >= 1, not ${cached}`);
  return new TkcFile(data, resolveLimits(options.limits), options.simd !== false, cached);
}

/** An opened file: its header facts, faces and names, and its frames on demand. */
export class TkcFile {
  /**
   * @param {Uint8Array} bytes
   * @param {import('./limits.js').Limits} limits
   * @param {boolean} [simd]
   * @param {number} [cachedSegments] decoded segments kept, the most recently used
   */
  constructor(bytes, limits, simd = true, cachedSegments = CACHED_SEGMENTS) {
    this.bytes = bytes;
    this._useSimd = simd;
    this._cachedSegments = cachedSegments;
    this.limits = limits;
    const container = readContainer(bytes, limits);
    const layout = readLayout(container, limits);
    this.container = container;
    this.layout = layout;
    this.version = `${container.major}.${container.minor}`;
    this.flags = container.flags;
    this.vertices = layout.vertices;
    this.frames = layout.frames;
    this.frameRate = layout.frameRate;
    /** Each frame's time code (§4, 1.4; in frames, seconds = code / frameRate), or null: 0, 1, 2... */
    this.timeCodes = layout.timeCodes;
    /** The length of a unit of the positions in metres (1.4), or null: unknown. */
    this.metersPerUnit = layout.metersPerUnit;
    /** "Y" or "Z", the source's up axis (1.4), or null: unknown. */
    this.upAxis = layout.upAxis;
    this.header = container.header;
    const encoder = container.header.get('encoder');
    this.encoder = typeof encoder === 'string' ? encoder : null;
    this.error = errorClaims(container.header.get('error'));
    // step 15: the faces
    const [M, n] = layout.faceShape;
    this.faceCount = M;
    this.faceWidth = n;
    /** @type {Int32Array} the M × n faces, -1 padded, in the order they were given (§6.10) */
    this.faces = decodeFaces(layout.face, this._payload(layout.face), this.vertices, M, n, limits, layout.adaptive, layout.uniformRanks);
    /** The faces as FACE decodes them (the walk's order): the mesh predictors' (§6.8). */
    this._codedFaces = this.faces;
    /** @type {Topology | null} */
    this._topology = null;
    /** @type {Float64Array | null} */
    this._sharedU1 = null;
    /** @type {{q?: Float64Array, steps?: Float64Array}} the shared U1's integers and steps */
    this._sharedKept = {};
    /** @type {SimdBasis | null | undefined} */
    this._sharedSimd = undefined;
    /** @type {Map<number, Factors>} decoded segments, the most recently used last (an LRU) */
    this._decoded = new Map();
    /** @type {Map<string, Int32Array>} decoded correction chunks, the most recent last */
    this._chunks = new Map();
    this.segments = layout.segments.map(({ start, frames, ranks, basis }) => ({ start, frames, ranks: [...ranks], basis }));
    // [i, k]; for a segmented file the summary §12 reports: the shared U1's columns (else the
    // largest i_s) and the largest k_s
    /** @param {number} j */
    const largest = (j) => Math.max(...this.segments.map((s) => s.ranks[j]));
    this.ranks = layout.segmented ? [layout.sharedColumns || largest(0), largest(1)] : [...this.segments[0].ranks];
    this._segmentOfFrame = new Int32Array(this.frames);
    layout.segments.forEach((segment, s) => this._segmentOfFrame.fill(s, segment.start, segment.start + segment.frames));
    // step 16 for a whole file (a segmented file decodes its segments when they are needed)
    if (!layout.segmented) this._segment(0);
    // step 17: the names
    if (layout.name !== null) {
      const size = nameSize(layout.name, limits);
      this.names = decodeNames(this._payload(layout.name), size, this.frames);
    } else {
      this.names = defaultNames(this.frames);
    }
    this._scratch = new Float64Array(0);
    /** @type {Float64Array} P of §8.1, before its corrections */
    this._exact = new Float64Array(0);
    // step 18: the corrections' parameters (a segmented file's, with their segment)
    if (!layout.segmented && layout.corrections) this._readResidual(this._segment(0), 0);
    // step 19 (1.5): the faces' given order, the attributes and the face sets
    this.attached = findAttachments(container.sections);
    this.faces = this._facesInGivenOrder();
    /** @type {Attribute[]} the static attributes (§6.11), in order */
    this.attributes = this._decodeAttributes();
    /** @type {FaceSet[]} the face sets (§6.12), in order */
    this.faceSets = this.attached.faceSets === null ? [] : decodeFaceSets(this.attached.faceSets, this._payload(this.attached.faceSets), M, limits);
    // the fields (§6.13): each checked and decoded when asked for
    const counts = { vertices: this.vertices, faces: M, frames: this.frames };
    this._fields = new FieldReader(this.attached.fields, this.attached.factors, counts, limits, (section) => this._payload(section), () => this._topologyOnce());
  }

  /**
   * The names of the animated fields (FLD.n, §6.13), in order; each field's parameters are
   * checked (a damaged one is a TkcError R45-field, or R21 beyond a limit), and no two fields
   * may share a name (R45-field).
   * @returns {string[]}
   */
  get fieldNames() {
    return this._fields.names();
  }

  /**
   * Field `which` (its number, or its name)'s description: name, role (`velocity`, `color`,
   * `generic`), domain (`vertex`: a value per vertex, `face`: per face), components (1 to 4),
   * type (`f32` or `f64`: the values' array) and mode (how it is stored: `tucker`, `grid` or
   * `exact`). Its parameters are checked, nothing is decoded.
   * @param {number | string} which
   * @returns {FieldInfo}
   */
  fieldInfo(which) {
    const { name, role, domain, components, type, mode } = this._fields.params(this._fields.number(which));
    return { name, role, domain, components, type, mode };
  }

  /**
   * Frame f of field `which` (its number, or its name): N·c values (N the vertices or the
   * faces, c the components), element-major, a Float32Array for type `f32`, a Float64Array for
   * `f64`. Grid and exact fields are the Python decoder's bits; a tucker field is its §6.13 sum
   * (to the rounding of the sum's order). Decodes only what the frame needs: a tucker field's
   * factors (once), a chunked field's chunk (the last one is kept).
   * @param {number | string} which
   * @param {number} f
   * @returns {Float32Array | Float64Array}
   */
  field(which, f) {
    return this._fields.frame(this._fields.number(which), f);
  }

  /**
   * The faces in the order they were given (ORDER, §6.10), or as FACE decodes them.
   * @returns {Int32Array}
   */
  _facesInGivenOrder() {
    const section = this.attached.order;
    if (section === null) return this.faces;
    const order = decodeFaceOrder(section, this._payload(section), this.faceCount);
    return inGivenOrder(this.faces, order, this.faceWidth);
  }

  /** Every ATTR.n in order (§6.11): its parameters and sizes, then its payload; names unique. */
  _decodeAttributes() {
    let corners = 0;
    for (const v of this.faces) if (v >= 0) corners++;
    /** @type {import('./attributes.js').Mesh} */
    const mesh = { vertices: this.vertices, faces: this.faces, faceCount: this.faceCount, faceWidth: this.faceWidth, corners };
    /** @type {Attribute[]} */
    const decoded = [];
    for (const section of this.attached.attributes) {
      const params = checkAttributeParams(section, mesh, this.limits);
      decoded.push(decodeAttribute(params, this._payload(section), mesh, section.id));
    }
    decoded.forEach(({ name }, n) => {
      if (decoded.findIndex((a) => a.name === name) < n) {
        throw formatError('R43-attribute', `section '${this.attached.attributes[n].id}': two attributes are named ${JSON.stringify(name)}`);
      }
    });
    return decoded;
  }

  /**
   * Frame f's positions (§8), K*3 binary64 values; `out` is reused when given.
   * @param {number} f
   * @param {Float64Array} [out]
   */
  frame(f, out = new Float64Array(3 * this.vertices)) {
    return this._reconstruct(f, out);
  }

  /**
   * Frame f's positions rounded to float32 (for a GPU buffer), into `out` (K*3).
   * @param {number} f
   * @param {Float32Array} [out]
   */
  frameFloat32(f, out = new Float32Array(3 * this.vertices)) {
    return this._reconstruct(f, out);
  }

  /** The faces as a triangle list (fan triangulation of each polygon), for drawing. */
  triangles() {
    return fanTriangles(this.faces, this.faceCount, this.faceWidth);
  }

  /**
   * The dequantized factors of segment s: u1 (K × i, the columns the segment uses), u3 (F_s × k),
   * core (i × 3 × k), cent (F_s × 3), all row-major Float64Arrays, and u2 (9 values, row-major).
   */
  factors(s = 0) {
    const d = this._segment(s);
    let u1 = d.u1;
    if (d.columns !== d.i) {
      u1 = new Float64Array(this.vertices * d.i);
      for (let v = 0; v < this.vertices; v++) u1.set(d.u1.subarray(v * d.columns, v * d.columns + d.i), v * d.i);
    }
    return { u1, u3: d.u3, core: d.core, cent: d.cent, u2: d.u2, ranks: [d.i, d.k] };
  }

  /**
   * Decodes every segment and, with corrections, each segment's chunks and values, after its
   * factors (R29, R41; §5 step 16s), then every frame of every field (§6.13): checks the whole
   * file, as the Python `Decoder.check()` does. Like it, it does not look for R36 (frames are asked for that).
   */
  check() {
    const out = new Float64Array(3 * this.vertices);
    this.layout.segments.forEach((segment, s) => {
      const d = this._segment(s);
      if (!this.layout.corrections) return;
      // the weights of every frame of the segment (R41), then its chunks and values in order
      if (this._scratch.length < 3 * d.i) this._scratch = new Float64Array(3 * d.i);
      for (let t = 0; t < segment.frames; t++) this._weights(d, t, segment.start + t);
      for (let f = segment.start; f < segment.start + segment.frames; f++) this._reconstruct(f, out, false);
    });
    this._fields.checkAll(); // every frame of every field (§6.13)
    return this;
  }

  /**
   * Segment s's corrections (§6.9): null in a file without them (flag bit 2), else the RESD
   * section's domain, grid step (0 outside domain "grid"), scale (the places or digits of a
   * decimal domain, else null), §8.1's exponent, predict, (1.7) coder (0: zstd planes, 1:
   * adaptive streams), (1.8) codebooks (each axis's count of entries, 0 for none; null where
   * the section has no `codebooks`), frames per chunk and chunks.
   */
  residual(s = 0) {
    const r = this._segment(s).residual;
    if (r === null) return null;
    const codebooks = r.codebooks.length === 0 ? null : r.codebooks.map((book) => book.count);
    return { domain: r.domain, step: r.step, scale: r.scale, exponent: r.exponent, predict: r.predict, coder: r.coder, codebooks, chunkFrames: r.chunkFrames, chunks: r.chunks.length };
  }

  /**
   * Segment s's restored correction integers e (§6.9), F_s × K × 3 in C order, or null in a
   * file without corrections. Decodes every chunk of the segment (for tests and tools: a frame
   * needs only its own chunk).
   */
  residualIntegers(s = 0) {
    const d = this._segment(s);
    if (d.residual === null) return null;
    const out = new BigInt64Array(d.residual.frames * 3 * this.vertices);
    const halves = new Int32Array(out.buffer);
    d.residual.chunks.forEach((chunk, c) => halves.set(this._chunk(s, d, c), 2 * chunk.start * 3 * this.vertices));
    return out;
  }

  /**
   * Segment s's codebooks (format 1.8, §6.9): each axis's entries C, or null for an axis
   * without one; null where the section has none (or the file no corrections).
   */
  residualCodebooks(s = 0) {
    const d = this._segment(s);
    if (d.residual === null) return null;
    const books = this._codebooks(d);
    return books === null ? null : books.map((C) => (C === null ? null : new BigInt64Array(C.slice().buffer)));
  }

  /**
   * @template {Float64Array | Float32Array} T
   * @param {number} f
   * @param {T} out
   * @param {boolean} [finite] false: do not require finite positions (R36)
   * @returns {T}
   */
  _reconstruct(f, out, finite = true) {
    if (!Number.isInteger(f) || f < 0 || f >= this.frames) {
      throw new RangeError(`frame ${f} does not exist: the file has frames 0..${this.frames - 1}`);
    }
    if (out.length !== 3 * this.vertices) throw new RangeError(`out must hold ${3 * this.vertices} values`);
    const s = this._segmentOfFrame[f];
    const d = this._segment(s);
    if (d.simd === undefined) d.simd = this._simdOnce(d); // on the first frame, not at open
    if (this._scratch.length < 3 * d.i) this._scratch = new Float64Array(3 * d.i);
    const t = f - this.layout.segments[s].start;
    const residual = d.residual;
    if (residual === null) return reconstructFrame(d, t, out, this._scratch, f);
    // §8.1's weights (R41) and P, the frame's chunk (R29), the correction (R41, on the values
    // whose P is finite), and last, a position that is not finite (R36): the Python decoder's
    // order
    const P = this._exact.length === out.length ? this._exact : (this._exact = new Float64Array(out.length));
    this._weights(d, t, f);
    reconstructExact(d, t, P, this._scratch, residual.exponent);
    const books = this._codebooks(d); // (1.8) before the chunk: R29, then R47, axis by axis
    const c = Math.floor(t / residual.chunkFrames);
    const pairs = this._chunk(s, d, c);
    const j = correct(residual, P, pairs, (t - residual.chunks[c].start) * out.length, out, f, books);
    if (finite && j >= 0) {
      throw formatError('R36-reconstruction-finite', `frame ${f}, vertex ${Math.floor(j / 3)}, axis ${'xyz'[j % 3]}: the decoded position is not finite (P of §8.1 is ${P[j]})`);
    }
    return out;
  }

  /**
   * §8.1's integer weights of frame t of a segment into this._scratch, R41 unless they fit.
   * @param {Factors} d
   * @param {number} t
   * @param {number} f the frame within the file, for messages
   */
  _weights(d, t, f) {
    const residual = /** @type {Residual} */ (d.residual);
    const exact = /** @type {import('./reconstruct.js').Exact} */ (d.exact);
    const largest = exactWeights(d, t, this._scratch, residual.exponent);
    if (!weightsFit(exact.rowSum, largest)) {
      const what = largest === largest ? `R = ${exact.rowSum} times the largest |w| = ${largest} exceeds 2^53` : 'a weight is not finite';
      throw formatError('R41-residual-value', `section '${residual.section.id}', frame ${f}: §8.1's integer weights at exponent ${residual.exponent} do not fit: ${what}`);
    }
  }

  /**
   * A segment's codebooks (format 1.8, §6.9), decoded on its first frame (R29, R47) and kept
   * with its factors; null where its section has none.
   * @param {Factors} d the segment, its residual read
   */
  _codebooks(d) {
    const residual = /** @type {Residual} */ (d.residual);
    if (residual.codebooks.length === 0) return null;
    if (d.codebooks === undefined) d.codebooks = decodeCodebooks(residual, /** @type {Uint8Array} */ (d.residualPayload));
    return d.codebooks;
  }

  /**
   * Chunk c of segment s's corrections, decoded (R29) and restored, from the cache when there.
   * @param {number} s
   * @param {Factors} d the segment, its residual read
   * @param {number} c
   */
  _chunk(s, d, c) {
    const key = `${s}/${c}`;
    let pairs = this._chunks.get(key);
    if (pairs !== undefined) {
      this._chunks.delete(key); // most recently used: last
    } else {
      const residual = /** @type {Residual} */ (d.residual);
      pairs = decodeChunk(residual, c, /** @type {Uint8Array} */ (d.residualPayload), this.vertices);
      let bytes = pairs.byteLength;
      for (const held of this._chunks.values()) bytes += held.byteLength;
      for (const [old, held] of this._chunks) {
        if (bytes <= CHUNK_CACHE_BYTES) break;
        this._chunks.delete(old);
        bytes -= held.byteLength;
      }
    }
    this._chunks.set(key, pairs);
    return pairs;
  }

  /**
   * §5 step 18: the RESD section's parameters (R40, R21), then its CRC (R19).
   * @param {Factors} d
   * @param {number} s
   */
  _readResidual(d, s) {
    const segment = this.layout.segments[s];
    const section = /** @type {import('./container.js').Section} */ (segment.resd);
    // (1.7) with flag bit 4 its `coder` is read: each chunk may be an adaptive stream (§6.14);
    // (1.8) with flag bit 5 its `codebooks`: an axis may correct through a sorted list
    const { adaptiveCorrections, codebooks } = this.layout;
    const residual = readResidual(section, segment.frames, this.vertices, this.limits, adaptiveCorrections, codebooks);
    d.residualPayload = this._payload(section);
    d.residual = residual;
  }

  /**
   * The segment's U1 for simd.js, made once per basis (a shared U1 serves every segment).
   * @param {Factors} d
   */
  _simdOnce(d) {
    if (!this._useSimd) return null;
    // the matrix each frame multiplies: U1, or with corrections its integers (§8.1)
    const matrix = d.exact ? d.exact.q1 : d.u1;
    const shared = d.exact ? this._sharedKept.q : this._sharedU1;
    if (matrix !== shared) return simdBasis(matrix, this.vertices, d.columns);
    if (this._sharedSimd === undefined) this._sharedSimd = simdBasis(matrix, this.vertices, d.columns);
    return this._sharedSimd;
  }

  /** @param {import('./container.js').Section} section */
  _payload(section) {
    return sectionPayload(this.bytes, this.container.dataStart, section);
  }

  _topologyOnce() {
    if (this._topology === null) this._topology = meshTopology(this._codedFaces, this.faceCount, this.faceWidth, this.vertices);
    return this._topology;
  }

  /**
   * @param {number} s
   * @returns {Factors}
   */
  _segment(s) {
    const cached = this._decoded.get(s);
    if (cached !== undefined) {
      this._decoded.delete(s); // the most recently used: last
      this._decoded.set(s, cached);
      return cached;
    }
    const segment = this.layout.segments[s];
    const [i, k] = segment.ranks;
    const K = this.vertices;
    // a position factor may use the adaptive coder in a file with flag bit 3 (§6.14)
    /** @type {import('./qmat.js').Coding} */
    const tools = { tools: this.layout.codingTools, adaptive: this.layout.adaptive };
    const topology = () => this._topologyOnce();
    let u1;
    let columns = i;
    // with corrections, §8.1 multiplies U1's integers: kept with its steps
    const corrections = this.layout.corrections;
    /** @type {{q?: Float64Array, steps?: Float64Array}} */
    let kept = {};
    if (segment.basis === 'shared') {
      if (this._sharedU1 === null) {
        const c = this.layout.sharedColumns;
        this._sharedU1 = decodeQmat(segment.u1, this._payload(segment.u1), K, c, 'mesh', tools, topology, corrections ? this._sharedKept : undefined);
      }
      u1 = this._sharedU1;
      kept = this._sharedKept;
      columns = this.layout.sharedColumns;
    } else {
      u1 = decodeQmat(segment.u1, this._payload(segment.u1), K, i, 'mesh', tools, topology, corrections ? kept : undefined);
    }
    const u3 = decodeQmat(segment.u3, this._payload(segment.u3), segment.frames, k, 'time', tools, topology);
    const core = decodeQmat(segment.core, this._payload(segment.core), i * 3 * k, 1, 'none', tools, topology);
    const cent = decodeQmat(segment.cent, this._payload(segment.cent), segment.frames, 3, 'time', tools, topology);
    /** @type {Factors} */
    const decoded = {
      u1, columns, i, k, u3, core, cent, u2: segment.u2, B: coreTimesU2(core, segment.u2, i, k),
      residual: null, residualPayload: null, exact: null,
    };
    if (corrections) {
      const q1 = /** @type {Float64Array} */ (kept.q);
      decoded.exact = { q1, steps1: /** @type {Float64Array} */ (kept.steps), rowSum: rowSum(q1, K, columns, i) };
    }
    // step 16s: a segment's RESD.s after its factors (a whole file's RESD comes after NAME)
    if (this.layout.segmented && this.layout.corrections) this._readResidual(decoded, s);
    this._keepSegment(s, decoded);
    return decoded;
  }

  /**
   * Keeps segment s decoded, forgetting the least recently used beyond the bound, with its
   * correction chunks: a forgotten segment is decoded again (and checked again) when needed.
   * @param {number} s
   * @param {Factors} decoded
   */
  _keepSegment(s, decoded) {
    this._decoded.set(s, decoded);
    for (const old of this._decoded.keys()) {
      if (this._decoded.size <= this._cachedSegments) break;
      this._decoded.delete(old);
      for (const key of [...this._chunks.keys()]) if (key.startsWith(`${old}/`)) this._chunks.delete(key);
    }
  }
}

/**
 * The header's informative `error` map (§4.1): used only where its types are right.
 * @param {import('./msgpack.js').MsgValue | undefined} error
 */
function errorClaims(error) {
  if (!(error instanceof Map)) return null;
  /** @param {import('./msgpack.js').MsgValue | undefined} value */
  const number = (value) => (value instanceof MsgFloat ? value.value : isInt(value) ? Number(value) : null);
  const definition = error.get('definition');
  const at = error.get('max_distance_at');
  const lossless = error.get('lossless');
  return {
    kg: number(error.get('kg')),
    truncationKg: number(error.get('truncation_kg')),
    targetKg: number(error.get('target_kg')),
    definition: typeof definition === 'string' ? definition : null,
    // 1.3: the largest vertex distance the encoder measured, where, the bound it was given,
    // and whether it checked the decoded values are the input's bits
    maxDistance: number(error.get('max_distance')),
    maxDistanceAt: Array.isArray(at) && at.length === 2 && at.every((v) => isInt(v)) ? at.map(Number) : null,
    targetMaxDistance: number(error.get('target_max_distance')),
    lossless: typeof lossless === 'boolean' ? lossless : null,
  };
}

export { formatError };

/**
 * R of §8.1: the largest Σ_a |q1[v, a]| over the first i of U1's columns (exact below 2^53).
 * @param {Float64Array} q1 K × columns
 * @param {number} K
 * @param {number} columns
 * @param {number} i
 */
function rowSum(q1, K, columns, i) {
  let largest = 0;
  for (let v = 0; v < K; v++) {
    let sum = 0;
    for (let a = 0; a < i; a++) sum += Math.abs(q1[v * columns + a]);
    if (sum > largest) largest = sum;
  }
  return largest;
}
