/** True where typed arrays are little-endian (the halves above, and the bit views below). */
export declare const LITTLE_ENDIAN: boolean;
export type Chunk = {
    planes: number;
    offset: number;
    length: number;
    start: number;
    frames: number;
};
export type Codebook = {
    count: number;
    planes: number;
    offset: number;
    length: number;
};
export type Residual = {
    section: import('./container.js').Section;
    domain: string;
    step: number;
    scale: number | null;
    exponent: number;
    predict: number;
    coder: number;
    chunkFrames: number;
    chunks: Chunk[];
    frames: number;
    codebooks: Codebook[];
};
export type Codebooks = (Int32Array | null)[];
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
export declare function readResidual(section: import('./container.js').Section, frames: number, K: number, limits: import('./limits.js').Limits, adaptive?: boolean, codebooks?: boolean): Residual;
/**
 * Chunk c's restored integers e (§6.9), as interleaved halves (see the top of this file):
 * N_c = n_c·K·3 values in frame-major order, j = (t·K + v)·3 + x.
 * @param {Residual} residual
 * @param {number} c
 * @param {Uint8Array} payload the whole section's payload, its CRC checked
 * @param {number} K
 * @returns {Int32Array} 2·N_c halves
 */
export declare function decodeChunk(residual: Residual, c: number, payload: Uint8Array, K: number): Int32Array;
/**
 * A section's codebooks (format 1.8), in axis order: each one's zstd frame of n·P bytes (R29),
 * then its entries C[0] = d[0], C[m] = C[m − 1] + d[m] wrapped to 64 bits, each above the one
 * before and all within the domain's ordered integers (R47-codebook).
 * @param {Residual} residual
 * @param {Uint8Array} payload the whole section's payload, its CRC checked
 * @returns {Codebooks}
 */
export declare function decodeCodebooks(residual: Residual, payload: Uint8Array): Codebooks;
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
export declare class MiddleIndex {
    /** The entries, whose sums of neighbours the search within a part compares. */
    C: Int32Array<ArrayBufferLike>;
    /** How many midpoints: n − 1. */
    count: number;
    /** The first midpoint's high half: none lies below a value at or below it. */
    lowHi: number;
    /** The first midpoint's low half (unsigned). */
    lowLo: number;
    /** The last midpoint's distance from the first, high half (unsigned): all lie below a value further. */
    spanHi: number;
    /** Its low half (unsigned). */
    spanLo: number;
    /** A distance's part is the distance shifted right by this: about 2^wanted parts. */
    shift: number;
    /** starts[k]: how many midpoints lie in the parts before part k (one more entry than parts) */
    starts: Int32Array<ArrayBuffer>;
    /** @param {Int32Array} C the codebook's n ≥ 1 entries, increasing, as interleaved halves */
    constructor(C: Int32Array);
    /**
     * The distance of a value at or above the first midpoint from it, as unsigned halves.
     * @param {number} hi
     * @param {number} lo unsigned
     * @returns {[number, number]}
     */
    distance(hi: number, lo: number): [number, number];
    /**
     * The part of a distance within the span: below 2^wanted, a 32-bit integer. (With shift 0,
     * `hi << 32` is `hi << 0` in JavaScript, which shifts by the count mod 32; it is still 0, as
     * shift 0 comes only with a span below 2^32.)
     * @param {number} hi unsigned
     * @param {number} lo unsigned
     */
    part(hi: number, lo: number): number;
    /**
     * How many midpoints lie below b: j of §6.9. Those of the parts before b's are all below it
     * and those of the parts after it all above, as (a >> s) < (c >> s) implies a < c.
     * @param {number} bHi
     * @param {number} bLo unsigned
     */
    countBelow(bHi: number, bLo: number): number;
}
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
export declare function correct(residual: Residual, P: Float64Array, pairs: Int32Array, first: number, out: Float64Array | Float32Array, frameNumber: number, books?: Codebooks | null): number;
export type Digits = {
    digits: number;
    least: number;
    decade: number;
    powers: number[];
    bound: bigint;
    eHigh: number[];
    eLow: number[];
    oHigh: number[];
    oLow: number[];
};
