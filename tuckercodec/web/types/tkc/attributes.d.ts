export declare const DOMAINS: readonly string[];
export declare const ROLES: readonly string[];
/** The longest name in UTF-8 bytes (the model's). */
export declare const MAX_NAME_BYTES = 255;
export type AttributeValues = Float32Array | Float64Array | Int32Array;
export type Attribute = {
    name: string;
    domain: 'vertex' | 'corner' | 'face';
    role: 'uv' | 'normal' | 'color' | 'generic';
    type: 'f32' | 'f64' | 'i32';
    rows: number;
    components: number;
    values: AttributeValues;
    indices: Uint32Array | null;
};
export type AttributeParams = {
    name: string;
    domain: 'vertex' | 'corner' | 'face';
    role: 'uv' | 'normal' | 'color' | 'generic';
    type: 'f32' | 'f64' | 'i32';
    rows: number;
    cols: number;
    indexed: boolean;
    predict: number;
    elements: number;
    streams: number[][];
};
export type Mesh = {
    vertices: number;
    faces: Int32Array;
    faceCount: number;
    faceWidth: number;
    corners: number;
};
/**
 * @typedef {Float32Array | Float64Array | Int32Array} AttributeValues
 * @typedef {{name: string, domain: 'vertex' | 'corner' | 'face',
 *   role: 'uv' | 'normal' | 'color' | 'generic', type: 'f32' | 'f64' | 'i32', rows: number,
 *   components: number, values: AttributeValues, indices: Uint32Array | null}} Attribute
 *   An attribute as decoded: `values` holds rows × components values row-major (each row a
 *   value's components), the same bits the encoder was given; `indices` (one per element, into
 *   the rows) or null, when there is a row per element.
 * @typedef {{name: string, domain: 'vertex' | 'corner' | 'face',
 *   role: 'uv' | 'normal' | 'color' | 'generic', type: 'f32' | 'f64' | 'i32', rows: number,
 *   cols: number, indexed: boolean, predict: number, elements: number,
 *   streams: number[][]}} AttributeParams
 * @typedef {{vertices: number, faces: Int32Array, faceCount: number, faceWidth: number,
 *   corners: number}} Mesh the faces in the given order (§6.10) and their counts
 */
/**
 * Why a name is not one the model allows (1 to 255 UTF-8 bytes, no control character), or null.
 * @param {string} name
 */
export declare function nameProblem(name: string): "has a control character" | "is empty" | "is longer than 255 bytes" | null;
/**
 * §5 step 19 for one ATTR section's parameters, in the order of §6.11 (R43), then its streams'
 * sizes against the limits (R21): everything checked before the payload is read.
 * @param {import('./container.js').Section} section
 * @param {Mesh} mesh
 * @param {import('./limits.js').Limits} limits
 * @returns {AttributeParams}
 */
export declare function checkAttributeParams(section: import('./container.js').Section, mesh: Mesh, limits: import('./limits.js').Limits): AttributeParams;
/**
 * The attribute of an ATTR section whose parameters checkAttributeParams gave.
 * @param {AttributeParams} params
 * @param {Uint8Array} payload its bytes, CRC already checked
 * @param {Mesh} mesh
 * @param {string} id the section's id, for messages
 * @returns {Attribute}
 */
export declare function decodeAttribute(params: AttributeParams, payload: Uint8Array, mesh: Mesh, id: string): Attribute;
