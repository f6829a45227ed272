/**
 * Decodes a qmat section into its dequantized matrix, row-major (C order).
 * @param {import('./container.js').Section} section the section entry (readContainer)
 * @param {Uint8Array} payload its bytes, CRC already checked
 * @param {number} rows
 * @param {number} cols
 * @param {'mesh'|'time'|'none'} relation the parents §6.6 assigns: U1 mesh, U3/CENT time, CORE none
 * @param {boolean} codingTools preamble flag bit 1 (version 1.2)
 * @param {() => import('./topology.js').Topology} topology the mesh topology, built on first
 *   use (for U1 only)
 * @param {{q?: Float64Array, steps?: Float64Array}} [keep] when given, also the restored
 *   integers q (rows*cols, row-major, as binary64) and the steps (the f32 widened) are set in
 *   it: §8.1 multiplies U1's integers
 * @returns {Float64Array} rows*cols values
 */
export declare function decodeQmat(section: import('./container.js').Section, payload: Uint8Array, rows: number, cols: number, relation: 'mesh' | 'time' | 'none', codingTools: boolean, topology: () => import('./topology.js').Topology, keep?: {
    q?: Float64Array;
    steps?: Float64Array;
}): Float64Array;
