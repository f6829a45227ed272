/**
 * The given number of each decoded face: a permutation of 0..M-1 (R42), after the parameters
 * `faces` (R42) and `planes` (R30).
 * @param {import('./container.js').Section} section the ORDER entry
 * @param {Uint8Array} payload its bytes, CRC already checked
 * @param {number} M the FACE section's faces
 * @returns {Int32Array}
 */
export declare function decodeFaceOrder(section: import('./container.js').Section, payload: Uint8Array, M: number): Int32Array;
/**
 * The faces of the walk (M × n, as FACE decodes them) put back in the given order.
 * @param {Int32Array} walked
 * @param {Int32Array} order
 * @param {number} n the face width
 */
export declare function inGivenOrder(walked: Int32Array, order: Int32Array, n: number): Int32Array<ArrayBuffer>;
