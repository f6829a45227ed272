/**
 * The `size` parameter (checked before the CRC, §5 step 17).
 * @param {import('./container.js').Section} section
 * @param {import('./limits.js').Limits} limits
 */
export declare function nameSize(section: import('./container.js').Section, limits: import('./limits.js').Limits): number;
/**
 * The names in the payload (CRC already checked).
 * @param {Uint8Array} payload
 * @param {number} size
 * @param {number} F
 * @returns {string[]}
 */
export declare function decodeNames(payload: Uint8Array, size: number, F: number): string[];
/**
 * The names of a file without NAME.
 * @param {number} F
 */
export declare function defaultNames(F: number): string[];
