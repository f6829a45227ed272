/**
 * The low 32 bits of XXH64(bytes, seed 0), as an unsigned number.
 * @param {Uint8Array} bytes
 */
export declare function xxh64Low32(bytes: Uint8Array): number;
