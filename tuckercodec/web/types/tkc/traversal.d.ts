export type MsgValue = import('./msgpack.js').MsgValue;
export type Limits = import('./limits.js').Limits;
/**
 * Decodes a FACE section coded with faces-traverse.
 * @param {Map<string, MsgValue>} entry the section-table entry (codec parameters corner_order, streams)
 * @param {Uint8Array} payload the section's bytes, CRC already checked
 * @param {number} K vertices
 * @param {number} M faces (the checked `shape`)
 * @param {number} n face width
 * @param {Limits} [limits] the decoder's limits (§7): max_section_bytes bounds the streams
 * @param {boolean} [adaptive] the file sets flag bit 3 (format 1.6): `coder` may be 1
 * @param {boolean} [uniform] the file sets flag bit 6 (format 1.9): `ranks` is read, and may be 1
 * @returns {Int32Array} M*n vertex indices, row-major, in walk order, −1 padded
 * @throws {TkcError} R39-traversal, R30-planes, R21-header-limit, R29-zstd-content-size or
 *   R46-adaptive-stream
 */
export declare function decodeTraverse(entry: Map<string, MsgValue>, payload: Uint8Array, K: number, M: number, n: number, limits?: Limits, adaptive?: boolean, uniform?: boolean): Int32Array;
