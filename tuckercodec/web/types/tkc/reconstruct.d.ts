export type Factors = {
    u1: Float64Array;
    columns: number;
    i: number;
    k: number;
    B: Float64Array;
    u3: Float64Array;
    core: Float64Array;
    cent: Float64Array;
    u2: Float64Array;
    simd?: import('./simd.js').SimdBasis | null;
    residual: import('./residual.js').Residual | null;
    residualPayload: Uint8Array | null;
    exact: Exact | null;
    codebooks?: import('./residual.js').Codebooks;
};
export type Exact = {
    q1: Float64Array;
    steps1: Float64Array;
    rowSum: number;
};
/**
 * A decoded segment's factors, as reconstructFrame reads them (decoder.js makes them), and its
 * corrections (§6.9; null without flag bit 2) with their section's payload and, once decoded,
 * (1.8) its codebooks.
 * @typedef {{u1: Float64Array, columns: number, i: number, k: number, B: Float64Array,
 *   u3: Float64Array, core: Float64Array, cent: Float64Array, u2: Float64Array,
 *   simd?: import('./simd.js').SimdBasis | null,
 *   residual: import('./residual.js').Residual | null,
 *   residualPayload: Uint8Array | null, exact: Exact | null,
 *   codebooks?: import('./residual.js').Codebooks}} Factors
 */
/**
 * What §8.1 takes of U1 in a file with corrections: its restored integers q1 (K × columns,
 * row-major, as binary64), its steps (the f32 widened), and R, the largest Σ_a |q1[v, a]| over
 * the segment's i columns (exact below 2^53; a larger R fails every weight but 0 all the same).
 * @typedef {{q1: Float64Array, steps1: Float64Array, rowSum: number}} Exact
 */
/**
 * The per-segment product B (i × 3 × k, C order) of the core and U2.
 * @param {Float64Array} core
 * @param {Float64Array} u2
 * @param {number} i
 * @param {number} k
 */
export declare function coreTimesU2(core: Float64Array, u2: Float64Array, i: number, k: number): Float64Array<ArrayBuffer>;
/**
 * Frame t of a segment into `out` (K*3, any array type: Float64Array, or Float32Array for the
 * GPU, which rounds each binary64 position once). Every position must be finite (R36).
 * @template {Float64Array | Float32Array} T
 * @param {Factors} factors u1 is K × columns row-major (a shared basis may have more columns
 *   than the segment uses); simd, when not null, the same U1 laid out for WebAssembly SIMD
 *   (simd.js)
 * @param {number} t the frame within the segment
 * @param {T} out
 * @param {Float64Array} W scratch of i*3
 * @param {number} frameNumber the frame within the file, for messages
 * @returns {T}
 */
export declare function reconstructFrame<T extends Float64Array | Float32Array>(factors: Factors, t: number, out: T, W: Float64Array, frameNumber: number): T;
/**
 * §8.1's integer weights of frame t of a segment: W[a, x] summed over b in order, then
 * w[a, x] = round((step1[a]·W[a, x])·2^−e), ties to even, into `w` (i·3). Returns the largest
 * |w|, or NaN when a weight is not finite.
 * @param {Factors} factors its `exact` set
 * @param {number} t
 * @param {Float64Array} w
 * @param {number} exponent e
 */
export declare function exactWeights(factors: Factors, t: number, w: Float64Array, exponent: number): number;
/**
 * Whether R·largest <= 2^53 (§8.1, R41): exact, with BigInt where the product nears 2^53.
 * @param {number} rowSum R
 * @param {number} largest the largest |w|, an integer or NaN
 */
export declare function weightsFit(rowSum: number, largest: number): boolean;
/**
 * P of §8.1 for frame t of a segment, from its weights w (exactWeights, checked by
 * weightsFit): S = q1·w, an integer product exact in any order (so WebAssembly SIMD or the
 * JavaScript loop), then P = S·2^e + CENT[t], one multiplication and one addition.
 * @param {Factors} factors its `exact` set; simd, when not null, q1 laid out for SIMD
 * @param {number} t
 * @param {Float64Array} P K·3
 * @param {Float64Array} w
 * @param {number} exponent
 */
export declare function reconstructExact(factors: Factors, t: number, P: Float64Array, w: Float64Array, exponent: number): Float64Array<ArrayBufferLike>;
