export declare const FIELD_ROLES: readonly string[];
export type Section = import('./container.js').Section;
export type MsgValue = import('./msgpack.js').MsgValue;
export type Limits = import('./limits.js').Limits;
export type FieldValues = Float32Array | Float64Array;
export type FieldInfo = {
    name: string;
    role: 'velocity' | 'color' | 'generic';
    domain: 'vertex' | 'face';
    components: number;
    type: 'f32' | 'f64';
    mode: 'tucker' | 'grid' | 'exact';
};
export type TuckerParams = {
    i: number;
    k: number;
    u2: Float64Array;
    sections: Section[];
};
export type ChunkParams = {
    step: number;
    predict: number;
    chunkFrames: number;
    planes: number[];
    offsets: number[];
};
export type FieldParams = FieldInfo & {
    id: string;
    elements: number;
    frames: number;
    tucker: TuckerParams | null;
    chunks: ChunkParams | null;
};
export type Counts = {
    vertices: number;
    faces: number;
    frames: number;
};
/**
 * §6.13 for the section FLD.n: the descriptor's parameters in order (R45-field), the values'
 * count against max_positions (R21), the mode's parameters, and for mode tucker the payload's
 * emptiness and the sub-sections (present, each's shape R28 and size R21). Nothing is read.
 * @param {Section} section
 * @param {Map<string, Section>} factors the file's FLD.n.X sections by id
 * @param {Counts} counts
 * @param {Limits} limits
 * @returns {FieldParams}
 */
export declare function checkFieldParams(section: Section, factors: Map<string, Section>, counts: Counts, limits: Limits): FieldParams;
/**
 * A chunk's values, frame-major (frames of the chunk × N × c): its zstd frame (R29), the
 * running sums of `predict` (wrapping at 64 bits), then each value (R45).
 * @param {FieldParams} params
 * @param {ChunkParams} chunks
 * @param {Uint8Array} payload the descriptor's payload, CRC checked
 * @param {number} chunk
 * @returns {FieldValues}
 */
export declare function decodeFieldChunk(params: FieldParams, chunks: ChunkParams, payload: Uint8Array, chunk: number): FieldValues;
export type TuckerFactors = {
    u1: Float64Array;
    u3: Float64Array;
    mean: Float64Array;
    basis: Float64Array;
};
/**
 * @typedef {{u1: Float64Array, u3: Float64Array, mean: Float64Array, basis: Float64Array}}
 *   TuckerFactors dequantized U1 (N × i), U3 (F × k), MEAN (F × c) and CORE times U2:
 *   basis[a, x, b] = Σ_d CORE[a, d, b] · U2[x, d] (i × c × k), all row-major
 */
/**
 * The qmat sections of a field in mode tucker, each CRC-checked then decoded (R30-R32, R29):
 * U1 (a vertex field's over the mesh parents: predictors 0, 1, 2; a face field's predictor 0),
 * U3 and MEAN (along frames: 0, 1, 3) and CORE (0), whatever the preamble's flag bit 1.
 * @param {FieldParams} params
 * @param {(section: Section) => Uint8Array} payloadOf
 * @param {() => import('./topology.js').Topology} topology the file's mesh topology
 * @returns {TuckerFactors}
 */
export declare function decodeTuckerFactors(params: FieldParams, payloadOf: (section: Section) => Uint8Array, topology: () => import('./topology.js').Topology): TuckerFactors;
/**
 * Frame f of a field in mode tucker: Σ_a U1[e, a] · (Σ_b basis[a, x, b] · U3[f, b]) +
 * MEAN[f, x] in binary64, rounded to the type by `out`; every value finite (R45).
 * @template {FieldValues} T
 * @param {FieldParams} params
 * @param {TuckerFactors} factors
 * @param {number} f
 * @param {T} out N·c values
 * @returns {T}
 */
export declare function tuckerFrame<T extends FieldValues>(params: FieldParams, factors: TuckerFactors, f: number, out: T): T;
/**
 * A file's fields, decoded on demand: the parameters of each when first needed, a tucker
 * field's factors once, and a chunked field's last chunk (the next frames of a playing field
 * are usually in it).
 */
export declare class FieldReader {
    _sections: import("./container.js").Section[];
    _factors: Map<string, import("./container.js").Section>;
    _counts: Counts;
    _limits: import("./limits.js").Limits;
    _payloadOf: (section: Section) => Uint8Array;
    _topology: () => import('./topology.js').Topology;
    /** @type {Map<number, FieldParams>} */
    _params: Map<number, FieldParams>;
    /** @type {Map<number, TuckerFactors>} */
    _tucker: Map<number, TuckerFactors>;
    /** @type {Map<number, {chunk: number, values: FieldValues}>} */
    _lastChunk: Map<number, {
        chunk: number;
        values: FieldValues;
    }>;
    /**
     * @param {Section[]} sections the FLD.n, in order
     * @param {Map<string, Section>} factors the FLD.n.X by id
     * @param {Counts} counts
     * @param {Limits} limits
     * @param {(section: Section) => Uint8Array} payloadOf a section's payload, CRC checked (R19)
     * @param {() => import('./topology.js').Topology} topology the file's mesh topology
     */
    constructor(sections: Section[], factors: Map<string, Section>, counts: Counts, limits: Limits, payloadOf: (section: Section) => Uint8Array, topology: () => import('./topology.js').Topology);
    /** The number of fields. */
    get count(): number;
    /**
     * Field n's checked parameters.
     * @param {number} n
     * @returns {FieldParams}
     */
    params(n: number): FieldParams;
    /**
     * Every field's name, each field's parameters checked, and no two the same (R45-field).
     * @returns {string[]}
     */
    names(): string[];
    /**
     * The number of the field `which` names (its number, or the first of that name).
     * @param {number | string} which
     */
    number(which: number | string): number;
    /**
     * Frame f of field n: N·c values, element-major, of the field's type.
     * @param {number} n
     * @param {number} f
     * @returns {FieldValues}
     */
    frame(n: number, f: number): FieldValues;
    /** Decodes every frame of every field, in order (the Python `Decoder.check()`'s fields). */
    checkAll(): void;
}
