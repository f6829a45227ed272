/** No payload of L bytes holds more than MAX_EXPANSION·L integers (§6.14 "Bound"). */
export declare const MAX_EXPANSION = 32768;
export type CodingOrder = {
    order: Int32Array;
    ends: Int32Array;
    source: Int32Array;
};
/**
 * A coding order (§6.14): `order` lists the rows in the order they are coded, and the row coded
 * j-th has the earlier neighbours `source[ends[j] .. ends[j+1]−1]` (rows coded before it in the
 * same column; none for a depth-0 vertex). U1's is meshCodingOrder's (topology.js); the
 * ascending order of U3, CORE and CENT, each row after the two before it, is given as null.
 * @typedef {{order: Int32Array, ends: Int32Array, source: Int32Array}} CodingOrder
 */
/**
 * The error of every R46 failure (also qmat.js's, for a `coder` that is not allowed).
 * @param {string} where
 * @param {string} message
 */
export declare function adaptiveError(where: string, message: string): import("./errors.js").TkcError;
/**
 * LZMA's range decoder over a payload, with the section's 12,480 adaptive models. Its registers
 * `range` and `code` are unsigned 32-bit values: every operation that can pass 2^31 is taken
 * back to unsigned with `>>> 0`, and (range >>> 15)·p, below 2^32, is Math.imul's low word.
 */
export declare class RangeDecoder {
    data: Uint8Array<ArrayBufferLike>;
    /**
     * the payload then PADDING zeros: decodeColumn reads on past the payload's end until the
     * integer's end, where it refuses the stream (an integer is at most 67 decisions of a
     * model, each taking in at most two bytes, and 60 at even odds, each at most one: 194
     * bytes), so that no byte read checks the end
     */
    padded: Uint8Array<ArrayBuffer>;
    where: string;
    code: number;
    range: number;
    next: number;
    probs: Uint16Array<ArrayBuffer>;
    shifts: Uint8Array<ArrayBuffer>;
    planes: number;
    /** 2^(8P − 1): a positive integer is below it, a negative one's magnitude at most it */
    half: number;
    /** the largest exponent (bit length − 1) of a magnitude within the planes (<= 31 for P <= 4) */
    longest: number;
    /**
     * @param {Uint8Array} data the payload
     * @param {number} planes the section's P (1..4; 1..8 for decodeAdaptiveWide): every integer
     *   zigzags below 2^(8P)
     * @param {string} where the section, for messages
     */
    constructor(data: Uint8Array, planes: number, where: string);
    ended(): import("./errors.js").TkcError;
    unbounded(): import("./errors.js").TkcError;
    /** For an exponent past `longest`: beyond the planes, or (P = 8) beyond 63 bits. */
    tooLong(): import("./errors.js").TkcError;
    /** After the last integer: every byte read and code below range, else R46. */
    finish(): void;
}
/**
 * The integers of an adaptive stream (§6.14), in stream order (column-major, j = c·rows + r):
 * what §6.1's decodeIntStream gives for a zstd payload. The caller has checked `planes` (1..4).
 * @param {Uint8Array} payload the section's bytes, CRC checked
 * @param {number} rows
 * @param {number} cols
 * @param {(() => CodingOrder) | null} meshOrder U1's order (meshCodingOrder), made once the
 *   payload's size and first bytes have passed (its arrays are K long); null: ascending rows
 * @param {number} planes P: every integer zigzags below 2^(8P)
 * @param {string} where the section, for messages
 * @returns {Int32Array}
 * @throws {import('./errors.js').TkcError} R46-adaptive-stream
 */
export declare function decodeAdaptive(payload: Uint8Array, rows: number, cols: number, meshOrder: (() => CodingOrder) | null, planes: number, where: string): Int32Array;
/**
 * The integers of an adaptive stream (§6.14) of up to 63 bits, rows in ascending order (each
 * after the two before it): a RESD chunk's with `coder` 1 (§6.9, version 1.7). In stream order
 * (column-major, j = c·rows + r) as 64-bit two's complement halves, low half first: out[2j] and
 * out[2j + 1]. Any planes 1..8 (the caller has checked them); decodeAdaptive is the faster path
 * where P <= 4 and 32-bit integers will do.
 * @param {Uint8Array} payload
 * @param {number} rows
 * @param {number} cols
 * @param {number} planes P: every integer zigzags below 2^(8P), on 64 bits
 * @param {string} where the section and chunk, for messages
 * @returns {Int32Array} 2·rows·cols halves
 * @throws {import('./errors.js').TkcError} R46-adaptive-stream
 */
export declare function decodeAdaptiveWide(payload: Uint8Array, rows: number, cols: number, planes: number, where: string): Int32Array;
/**
 * The `count` integers of a uniform stream over `total` (§6.8, version 1.9): value i in
 * 0..total−i−1 as truncated binary in §6.14's direct bits, most significant first. With
 * n = total − i, k = floor(log2 n) and u = 2^(k+1) − n, k bits x give x when x < u, else one
 * more bit b gives 2x + b − u. Every value so read is in its range, so the stream fails only as
 * an adaptive stream does (R46): more values than §6.14's bound lets its bytes hold (checked
 * before anything is allocated), a bad start, an end reached too soon or not at all, a bad
 * ending. The caller has checked count <= total <= 2^31: every value fits an int32.
 * @param {Uint8Array} payload
 * @param {number} count
 * @param {number} total T (the vertices, K)
 * @param {string} where the stream, for messages
 * @returns {Int32Array}
 * @throws {import('./errors.js').TkcError} R46-adaptive-stream
 */
export declare function decodeUniform(payload: Uint8Array, count: number, total: number, where: string): Int32Array;
