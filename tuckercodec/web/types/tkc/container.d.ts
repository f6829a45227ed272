export declare const SIGNATURE: readonly number[];
export declare const FLAG_SEGMENTED: number;
export declare const FLAG_CODING_TOOLS: number;
export declare const FLAG_CORRECTIONS: number;
export declare const FLAG_ADAPTIVE: number;
export declare const FLAG_ADAPTIVE_CORRECTIONS: number;
export declare const FLAG_CODEBOOKS: number;
export declare const FLAG_UNIFORM_RANKS: number;
export type MsgValue = import('./msgpack.js').MsgValue;
export type Limits = import('./limits.js').Limits;
export type Section = {
    id: string;
    offset: number;
    length: number;
    crc32: number;
    critical: boolean;
    codec: string;
    entry: Map<string, MsgValue>;
};
export type Container = {
    major: number;
    minor: number;
    flags: number;
    headerLength: number;
    totalLength: number;
    header: Map<string, MsgValue>;
    sections: Section[];
    dataStart: number;
};
/**
 * Steps 1-8 of §5 on the whole file.
 * @param {Uint8Array} bytes
 * @param {Limits} limits
 * @returns {Container}
 */
export declare function readContainer(bytes: Uint8Array, limits: Limits): Container;
/**
 * A section's payload, its CRC checked first (§5 step 9, R19-section-crc).
 * @param {Uint8Array} bytes the whole file
 * @param {number} dataStart where the data area starts
 * @param {Section} section an entry of readContainer's `sections`
 * @returns {Uint8Array}
 */
export declare function sectionPayload(bytes: Uint8Array, dataStart: number, section: Section): Uint8Array;
