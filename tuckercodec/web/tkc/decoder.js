// The JavaScript decoder of the tuckercodec format, written from spec/FORMAT.md (version 1.2):
// openTkc(bytes) checks the container and header, decodes the faces and names, and, for a file
// that is not segmented, every factor; a segmented file's segments are decoded when one of
// their frames is first asked for (§6.7). Every failure is a TkcError carrying its §11 rule.
//
//   import { openTkc } from './tkc/decoder.js';
//   const file = openTkc(new Uint8Array(await (await fetch('a.tkc')).arrayBuffer()));
//   const positions = file.frame(12);  // Float64Array K*3: x, y, z of each vertex
//
// No DOM and no build step: the same modules run in node and in browsers.

import { readContainer, sectionPayload } from './container.js';
import { formatError } from './errors.js';
import { decodeFaces, fanTriangles } from './faces.js';
import { readLayout } from './header.js';
import { resolveLimits } from './limits.js';
import { MsgFloat, isInt } from './msgpack.js';
import { decodeNames, defaultNames, nameSize } from './names.js';
import { decodeQmat } from './qmat.js';
import { coreTimesU2, reconstructFrame } from './reconstruct.js';
import { simdBasis } from './simd.js';
import { meshTopology } from './topology.js';

export { TkcError } from './errors.js';
export { DEFAULT_LIMITS } from './limits.js';

/**
 * @typedef {import('./reconstruct.js').Factors} Factors
 * @typedef {import('./simd.js').SimdBasis} SimdBasis
 * @typedef {import('./topology.js').Topology} Topology
 */

/**
 * Opens a .tkc file held in memory.
 * @param {Uint8Array|ArrayBuffer} bytes the whole file
 * @param {{limits?: {[name: string]: number}, simd?: boolean}} [options] decoder limits (§7) to use instead of the
 *   defaults; `simd: false` reconstructs frames with the JavaScript loop instead of WebAssembly
 *   SIMD (the same bits, five times slower: for tests and engines that misbehave)
 * @returns {TkcFile}
 * @throws {TkcError} when the file breaks a rule of §11
 */
export function openTkc(bytes, options = {}) {
  const data = bytes instanceof Uint8Array ? bytes : new Uint8Array(bytes);
  return new TkcFile(data, resolveLimits(options.limits), options.simd !== false);
}

/** An opened file: its header facts, faces and names, and its frames on demand. */
export class TkcFile {
  /**
   * @param {Uint8Array} bytes
   * @param {import('./limits.js').Limits} limits
   */
  constructor(bytes, limits, simd = true) {
    this.bytes = bytes;
    this._useSimd = simd;
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
    this.header = container.header;
    const encoder = container.header.get('encoder');
    this.encoder = typeof encoder === 'string' ? encoder : null;
    this.error = errorClaims(container.header.get('error'));
    // step 15: the faces
    const [M, n] = layout.faceShape;
    this.faceCount = M;
    this.faceWidth = n;
    this.faces = decodeFaces(layout.face, this._payload(layout.face), this.vertices, M, n, limits);
    /** @type {Topology | null} */
    this._topology = null;
    /** @type {Float64Array | null} */
    this._sharedU1 = null;
    /** @type {SimdBasis | null | undefined} */
    this._sharedSimd = undefined;
    /** @type {(Factors | null)[]} */
    this._decoded = new Array(layout.segments.length).fill(null);
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

  /** Decodes every segment: checks the whole file (the Python `Decoder.check()`). */
  check() {
    for (let s = 0; s < this._decoded.length; s++) this._segment(s);
    return this;
  }

  /**
   * @template {Float64Array | Float32Array} T
   * @param {number} f
   * @param {T} out
   * @returns {T}
   */
  _reconstruct(f, out) {
    if (!Number.isInteger(f) || f < 0 || f >= this.frames) {
      throw new RangeError(`frame ${f} does not exist: the file has frames 0..${this.frames - 1}`);
    }
    if (out.length !== 3 * this.vertices) throw new RangeError(`out must hold ${3 * this.vertices} values`);
    const s = this._segmentOfFrame[f];
    const d = this._segment(s);
    if (d.simd === undefined) d.simd = this._simdOnce(d); // on the first frame, not at open
    if (this._scratch.length < 3 * d.i) this._scratch = new Float64Array(3 * d.i);
    return reconstructFrame(d, f - this.layout.segments[s].start, out, this._scratch, f);
  }

  /**
   * The segment's U1 for simd.js, made once per basis (a shared U1 serves every segment).
   * @param {Factors} d
   */
  _simdOnce(d) {
    if (!this._useSimd) return null;
    if (d.u1 !== this._sharedU1) return simdBasis(d.u1, this.vertices, d.columns);
    if (this._sharedSimd === undefined) this._sharedSimd = simdBasis(d.u1, this.vertices, d.columns);
    return this._sharedSimd;
  }

  /** @param {import('./container.js').Section} section */
  _payload(section) {
    return sectionPayload(this.bytes, this.container.dataStart, section);
  }

  _topologyOnce() {
    if (this._topology === null) this._topology = meshTopology(this.faces, this.faceCount, this.faceWidth, this.vertices);
    return this._topology;
  }

  /**
   * @param {number} s
   * @returns {Factors}
   */
  _segment(s) {
    if (this._decoded[s] !== null) return this._decoded[s];
    const segment = this.layout.segments[s];
    const [i, k] = segment.ranks;
    const K = this.vertices;
    const tools = this.layout.codingTools;
    const topology = () => this._topologyOnce();
    let u1;
    let columns = i;
    if (segment.basis === 'shared') {
      if (this._sharedU1 === null) {
        const c = this.layout.sharedColumns;
        this._sharedU1 = decodeQmat(segment.u1, this._payload(segment.u1), K, c, 'mesh', tools, topology);
      }
      u1 = this._sharedU1;
      columns = this.layout.sharedColumns;
    } else {
      u1 = decodeQmat(segment.u1, this._payload(segment.u1), K, i, 'mesh', tools, topology);
    }
    const u3 = decodeQmat(segment.u3, this._payload(segment.u3), segment.frames, k, 'time', tools, topology);
    const core = decodeQmat(segment.core, this._payload(segment.core), i * 3 * k, 1, 'none', tools, topology);
    const cent = decodeQmat(segment.cent, this._payload(segment.cent), segment.frames, 3, 'time', tools, topology);
    const decoded = { u1, columns, i, k, u3, core, cent, u2: segment.u2, B: coreTimesU2(core, segment.u2, i, k) };
    this._decoded[s] = decoded;
    return decoded;
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
  return {
    kg: number(error.get('kg')),
    truncationKg: number(error.get('truncation_kg')),
    targetKg: number(error.get('target_kg')),
    definition: typeof definition === 'string' ? definition : null,
  };
}

export { formatError };
