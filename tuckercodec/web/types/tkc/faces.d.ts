/**
 * @param {import('./container.js').Section} section the FACE entry
 * @param {Uint8Array} payload its bytes, CRC already checked
 * @param {number} K vertices
 * @param {number} M faces
 * @param {number} n face width
 * @param {import('./limits.js').Limits} limits the decoder's limits (§7)
 * @param {boolean} [adaptive] the file sets flag bit 3 (format 1.6): faces-traverse's `coder` may be 1
 * @param {boolean} [uniform] the file sets flag bit 6 (format 1.9): faces-traverse's `ranks` is read
 * @returns {Int32Array} M*n indices, row-major
 */
export declare function decodeFaces(section: import('./container.js').Section, payload: Uint8Array, K: number, M: number, n: number, limits: import('./limits.js').Limits, adaptive?: boolean, uniform?: boolean): Int32Array;
/**
 * A fan triangulation of the faces, for drawing: (c0, cj, cj+1) for each polygon.
 * @param {Int32Array} faces
 * @param {number} M
 * @param {number} n
 */
export declare function fanTriangles(faces: Int32Array, M: number, n: number): Uint32Array<ArrayBuffer>;
