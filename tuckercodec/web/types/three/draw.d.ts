export type Attribute = import('../tkc/attributes.js').Attribute;
export type Group = {
    start: number;
    count: number;
    materialIndex: number;
};
/**
 * A file drawn with its UVs, normals, colours and materials (the first attribute of each role).
 * Without any, it is the file's vertices and faces as they are.
 */
export declare class DrawLayout {
    /** The file's vertex of each drawn vertex (the first K are the file's own). */
    vertexOf: Uint32Array<ArrayBufferLike>;
    /** The number of drawn vertices. */
    count: number;
    /** The drawn vertices' UVs (2 each), normals (3), colours (3 or 4), or null. */
    uv: Float32Array<ArrayBuffer> | null;
    normal: Float32Array<ArrayBuffer> | null;
    color: Float32Array<ArrayBuffer> | null;
    colorSize: number;
    triangles: Uint32Array<ArrayBufferLike>;
    /** Ranges of `triangles` drawn with one material each (none without materialBind sets). */
    groups: Group[];
    /** The material of each group's materialIndex (null: the faces of no material). */
    materialNames: (string | null)[];
    /** @type {{groupOf: Uint32Array, vertexOf: Uint32Array | null, triangles: Uint32Array, positions: Float32Array, normals: Float32Array} | null} null: the drawn vertices are the file's */
    _groups: {
        groupOf: Uint32Array;
        vertexOf: Uint32Array | null;
        triangles: Uint32Array;
        positions: Float32Array;
        normals: Float32Array;
    } | null;
    /** @param {import('../tkc/decoder.js').TkcFile} file */
    constructor(file: import('../tkc/decoder.js').TkcFile);
    /**
     * The drawn vertices' positions from a frame's (K*3), into `out` (count*3).
     * @param {Float32Array} frame
     * @param {Float32Array} out
     */
    positionsInto(frame: Float32Array, out: Float32Array): void;
    /**
     * The drawn vertices' normals from a frame's positions (K*3): area-weighted per normal group.
     * @param {Float32Array} frame
     * @param {Float32Array} out count*3
     */
    normalsInto(frame: Float32Array, out: Float32Array): void;
}
