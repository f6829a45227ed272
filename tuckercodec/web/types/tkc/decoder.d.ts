import { formatError } from './errors.js';
import { FieldReader } from './fields.js';
export { TkcError } from './errors.js';
export { DEFAULT_LIMITS } from './limits.js';
/**
 * Decoded segments a file keeps by default, the most recently used: the Python decoder's two, so
 * that playing a long segmented file (in a loop, say) holds two segments' factors, not all.
 */
export declare const CACHED_SEGMENTS = 2;
export type Factors = import('./reconstruct.js').Factors;
export type Residual = import('./residual.js').Residual;
export type SimdBasis = import('./simd.js').SimdBasis;
export type Topology = import('./topology.js').Topology;
export type Attribute = import('./attributes.js').Attribute;
export type FaceSet = import('./face_sets.js').FaceSet;
export type FieldInfo = import('./fields.js').FieldInfo;
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
export declare function openTkc(bytes: Uint8Array | ArrayBuffer, options?: {
    limits?: {
        [name: string]: number;
    };
    simd?: boolean;
    cachedSegments?: number;
}): TkcFile;
/** An opened file: its header facts, faces and names, and its frames on demand. */
export declare class TkcFile {
    bytes: Uint8Array<ArrayBufferLike>;
    _useSimd: boolean;
    _cachedSegments: number;
    limits: import("./limits.js").Limits;
    container: import("./container.js").Container;
    layout: import("./header.js").Layout;
    version: string;
    flags: number;
    vertices: number;
    frames: number;
    frameRate: number | null;
    /** Each frame's time code (§4, 1.4; in frames, seconds = code / frameRate), or null: 0, 1, 2... */
    timeCodes: Float64Array<ArrayBufferLike> | null;
    /** The length of a unit of the positions in metres (1.4), or null: unknown. */
    metersPerUnit: number | null;
    /** "Y" or "Z", the source's up axis (1.4), or null: unknown. */
    upAxis: string | null;
    header: Map<string, import("./msgpack.js").MsgValue>;
    encoder: string | null;
    error: {
        kg: number | null;
        truncationKg: number | null;
        targetKg: number | null;
        definition: string | null;
        maxDistance: number | null;
        maxDistanceAt: number[] | null;
        targetMaxDistance: number | null;
        lossless: boolean | null;
    } | null;
    faceCount: number;
    faceWidth: number;
    /** @type {Int32Array} the M × n faces, -1 padded, in the order they were given (§6.10) */
    faces: Int32Array;
    /** The faces as FACE decodes them (the walk's order): the mesh predictors' (§6.8). */
    _codedFaces: Int32Array<ArrayBufferLike>;
    /** @type {Topology | null} */
    _topology: Topology | null;
    /** @type {Float64Array | null} */
    _sharedU1: Float64Array | null;
    /** @type {{q?: Float64Array, steps?: Float64Array}} the shared U1's integers and steps */
    _sharedKept: {
        q?: Float64Array;
        steps?: Float64Array;
    };
    /** @type {SimdBasis | null | undefined} */
    _sharedSimd: SimdBasis | null | undefined;
    /** @type {Map<number, Factors>} decoded segments, the most recently used last (an LRU) */
    _decoded: Map<number, Factors>;
    /** @type {Map<string, Int32Array>} decoded correction chunks, the most recent last */
    _chunks: Map<string, Int32Array>;
    segments: {
        start: number;
        frames: number;
        ranks: number[];
        basis: "own" | "shared" | "whole";
    }[];
    ranks: number[];
    _segmentOfFrame: Int32Array<ArrayBuffer>;
    names: string[];
    _scratch: Float64Array<ArrayBuffer>;
    /** @type {Float64Array} P of §8.1, before its corrections */
    _exact: Float64Array;
    attached: import("./attachments.js").Attached;
    /** @type {Attribute[]} the static attributes (§6.11), in order */
    attributes: Attribute[];
    /** @type {FaceSet[]} the face sets (§6.12), in order */
    faceSets: FaceSet[];
    _fields: FieldReader;
    /**
     * @param {Uint8Array} bytes
     * @param {import('./limits.js').Limits} limits
     * @param {boolean} [simd]
     * @param {number} [cachedSegments] decoded segments kept, the most recently used
     */
    constructor(bytes: Uint8Array, limits: import('./limits.js').Limits, simd?: boolean, cachedSegments?: number);
    /**
     * The names of the animated fields (FLD.n, §6.13), in order; each field's parameters are
     * checked (a damaged one is a TkcError R45-field, or R21 beyond a limit), and no two fields
     * may share a name (R45-field).
     * @returns {string[]}
     */
    get fieldNames(): string[];
    /**
     * Field `which` (its number, or its name)'s description: name, role (`velocity`, `color`,
     * `generic`), domain (`vertex`: a value per vertex, `face`: per face), components (1 to 4),
     * type (`f32` or `f64`: the values' array) and mode (how it is stored: `tucker`, `grid` or
     * `exact`). Its parameters are checked, nothing is decoded.
     * @param {number | string} which
     * @returns {FieldInfo}
     */
    fieldInfo(which: number | string): FieldInfo;
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
    field(which: number | string, f: number): Float32Array | Float64Array;
    /**
     * The faces in the order they were given (ORDER, §6.10), or as FACE decodes them.
     * @returns {Int32Array}
     */
    _facesInGivenOrder(): Int32Array;
    /** Every ATTR.n in order (§6.11): its parameters and sizes, then its payload; names unique. */
    _decodeAttributes(): import("./attributes.js").Attribute[];
    /**
     * Frame f's positions (§8), K*3 binary64 values; `out` is reused when given.
     * @param {number} f
     * @param {Float64Array} [out]
     */
    frame(f: number, out?: Float64Array): Float64Array<ArrayBufferLike>;
    /**
     * Frame f's positions rounded to float32 (for a GPU buffer), into `out` (K*3).
     * @param {number} f
     * @param {Float32Array} [out]
     */
    frameFloat32(f: number, out?: Float32Array): Float32Array<ArrayBufferLike>;
    /** The faces as a triangle list (fan triangulation of each polygon), for drawing. */
    triangles(): Uint32Array<ArrayBuffer>;
    /**
     * The dequantized factors of segment s: u1 (K × i, the columns the segment uses), u3 (F_s × k),
     * core (i × 3 × k), cent (F_s × 3), all row-major Float64Arrays, and u2 (9 values, row-major).
     */
    factors(s?: number): {
        u1: Float64Array<ArrayBufferLike>;
        u3: Float64Array<ArrayBufferLike>;
        core: Float64Array<ArrayBufferLike>;
        cent: Float64Array<ArrayBufferLike>;
        u2: Float64Array<ArrayBufferLike>;
        ranks: number[];
    };
    /**
     * Decodes every segment and, with corrections, each segment's chunks and values, after its
     * factors (R29, R41; §5 step 16s), then every frame of every field (§6.13): checks the whole
     * file, as the Python `Decoder.check()` does. Like it, it does not look for R36 (frames are asked for that).
     */
    check(): this;
    /**
     * Segment s's corrections (§6.9): null in a file without them (flag bit 2), else the RESD
     * section's domain, grid step (0 outside domain "grid"), scale (the places or digits of a
     * decimal domain, else null), §8.1's exponent, predict, (1.7) coder (0: zstd planes, 1:
     * adaptive streams), (1.8) codebooks (each axis's count of entries, 0 for none; null where
     * the section has no `codebooks`), frames per chunk and chunks.
     */
    residual(s?: number): {
        domain: string;
        step: number;
        scale: number | null;
        exponent: number;
        predict: number;
        coder: number;
        codebooks: number[] | null;
        chunkFrames: number;
        chunks: number;
    } | null;
    /**
     * Segment s's restored correction integers e (§6.9), F_s × K × 3 in C order, or null in a
     * file without corrections. Decodes every chunk of the segment (for tests and tools: a frame
     * needs only its own chunk).
     */
    residualIntegers(s?: number): BigInt64Array<ArrayBuffer> | null;
    /**
     * Segment s's codebooks (format 1.8, §6.9): each axis's entries C, or null for an axis
     * without one; null where the section has none (or the file no corrections).
     */
    residualCodebooks(s?: number): (BigInt64Array<ArrayBuffer> | null)[] | null;
    /**
     * @template {Float64Array | Float32Array} T
     * @param {number} f
     * @param {T} out
     * @param {boolean} [finite] false: do not require finite positions (R36)
     * @returns {T}
     */
    _reconstruct<T extends Float64Array | Float32Array>(f: number, out: T, finite?: boolean): T;
    /**
     * §8.1's integer weights of frame t of a segment into this._scratch, R41 unless they fit.
     * @param {Factors} d
     * @param {number} t
     * @param {number} f the frame within the file, for messages
     */
    _weights(d: Factors, t: number, f: number): void;
    /**
     * A segment's codebooks (format 1.8, §6.9), decoded on its first frame (R29, R47) and kept
     * with its factors; null where its section has none.
     * @param {Factors} d the segment, its residual read
     */
    _codebooks(d: Factors): import("./residual.js").Codebooks | null;
    /**
     * Chunk c of segment s's corrections, decoded (R29) and restored, from the cache when there.
     * @param {number} s
     * @param {Factors} d the segment, its residual read
     * @param {number} c
     */
    _chunk(s: number, d: Factors, c: number): Int32Array<ArrayBufferLike>;
    /**
     * §5 step 18: the RESD section's parameters (R40, R21), then its CRC (R19).
     * @param {Factors} d
     * @param {number} s
     */
    _readResidual(d: Factors, s: number): void;
    /**
     * The segment's U1 for simd.js, made once per basis (a shared U1 serves every segment).
     * @param {Factors} d
     */
    _simdOnce(d: Factors): import("./simd.js").SimdBasis | null;
    /** @param {import('./container.js').Section} section */
    _payload(section: import('./container.js').Section): Uint8Array<ArrayBufferLike>;
    _topologyOnce(): import("./topology.js").Topology;
    /**
     * @param {number} s
     * @returns {Factors}
     */
    _segment(s: number): Factors;
    /**
     * Keeps segment s decoded, forgetting the least recently used beyond the bound, with its
     * correction chunks: a forgotten segment is decoded again (and checked again) when needed.
     * @param {number} s
     * @param {Factors} decoded
     */
    _keepSegment(s: number, decoded: Factors): void;
}
export { formatError };
