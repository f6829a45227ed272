export type SimdBasis = {
    product(W: Float64Array, i: number): Float64Array;
};
/** True where this engine runs WebAssembly SIMD (every current browser and node 16+). */
export declare const SIMD_AVAILABLE: boolean;
/**
 * U1 (K × columns, row-major) laid out for the SIMD loop, vertex pairs interleaved:
 * (u[2p, a], u[2p+1, a]) for every column. Returns null where the module cannot run or its
 * memory cannot be had (the caller then uses the JavaScript loop).
 * @param {Float64Array} u1
 * @param {number} K
 * @param {number} columns
 * @returns {SimdBasis | null}
 */
export declare function simdBasis(u1: Float64Array, K: number, columns: number): SimdBasis | null;
