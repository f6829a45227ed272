export type Coding = {
    tools: boolean;
    adaptive: boolean;
};
/**
 * What the file allows a qmat section: `tools`, preamble flag bit 1 (version 1.2: predictors 2
 * and 3); `adaptive` (§6.14), whether `coder` may be 1 (flag bit 3, in a position factor: U1,
 * U3, CORE, CENT or a `.s` form), else it must be absent or 0 (R46; a field's factors too, as
 * the reference decoder has it).
 * @typedef {{tools: boolean, adaptive: boolean}} Coding
 */
/**
 * Decodes a qmat section into its dequantized matrix, row-major (C order).
 * @param {import('./container.js').Section} section the section entry (readContainer)
 * @param {Uint8Array} payload its bytes, CRC already checked
 * @param {number} rows
 * @param {number} cols
 * @param {'mesh'|'time'|'none'} relation the parents §6.6 assigns: U1 mesh, U3/CENT time, CORE none
 * @param {Coding} coding what the file allows the section
 * @param {() => import('./topology.js').Topology} topology the mesh topology, built on first
 *   use (for U1 only)
 * @param {{q?: Float64Array, steps?: Float64Array}} [keep] when given, also the restored
 *   integers q (rows*cols, row-major, as binary64) and the steps (the f32 widened) are set in
 *   it: §8.1 multiplies U1's integers
 * @returns {Float64Array} rows*cols values
 */
export declare function decodeQmat(section: import('./container.js').Section, payload: Uint8Array, rows: number, cols: number, relation: 'mesh' | 'time' | 'none', coding: Coding, topology: () => import('./topology.js').Topology, keep?: {
    q?: Float64Array;
    steps?: Float64Array;
}): Float64Array;
