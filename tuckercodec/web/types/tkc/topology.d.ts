/** Predictor 2's push where a section gives none (§6.2): a third (2/6) of a step. */
export declare const MEAN_PUSH = 2;
export type MeanPlan = {
    restore: Int32Array;
    first: Int32Array;
    source: Int32Array;
    anchor: Int32Array;
    sources: number;
};
export type Topology = {
    K: number;
    start: Int32Array;
    neighbours: Int32Array;
    parent: Int32Array;
    order: Int32Array;
    depth: Int32Array;
    rank: Int32Array;
    maxDepth: number;
    plan: MeanPlan | null;
};
/**
 * The mesh mean's plan (meanPlan); `sources` is the most sources of any vertex.
 * @typedef {{restore: Int32Array, first: Int32Array, source: Int32Array, anchor: Int32Array,
 *   sources: number}} MeanPlan
 */
/**
 * The face edges' structure (meshTopology).
 * @typedef {{K: number, start: Int32Array, neighbours: Int32Array, parent: Int32Array,
 *   order: Int32Array, depth: Int32Array, rank: Int32Array, maxDepth: number,
 *   plan: MeanPlan | null}} Topology
 */
/**
 * The structure of the face edges that U1's prediction needs (§6.2).
 * @param {Int32Array} faces M*n vertex indices, row-major, −1 padded (already valid: R33, R34)
 * @param {number} M faces
 * @param {number} n face width
 * @param {number} K vertices
 * @returns {Topology}
 *   `neighbours[start[v] .. start[v+1]−1]` is N(v), ascending and without repeats; `order` lists
 *   every vertex in the order the walk reaches it (a parent before its children); the predictor-2
 *   plan is built on first use.
 */
export declare function meshTopology(faces: Int32Array, M: number, n: number, K: number): Topology;
/**
 * U1's adaptive coding order (§6.14): the depth-0 vertices (roots and vertices on no face) in
 * ascending index, without earlier neighbours, then predictor 2's restoring order (by depth, then
 * phase, then the walk's reach order), each vertex with its sources S(v). It holds whatever the
 * mesh's depth (predictor 2's depth limit is not this order's), and shares predictor 2's plan,
 * built once per topology.
 * @param {Topology} topo
 * @returns {import('./adaptive.js').CodingOrder}
 */
export declare function meshCodingOrder(topo: Topology): import('./adaptive.js').CodingOrder;
/**
 * Restores one predicted U1 column (§6.2) from its residuals.
 * @param {Int32Array} residuals the section's decoded stream
 * @param {number} offset where the column starts in it (column-major: c·K)
 * @param {number} predictor 1 (mesh parents) or 2 (mesh mean)
 * @param {Topology} topo meshTopology(...) of the file's faces
 * @param {string} where the section and column, for messages
 * @param {number} [push] predictor 2's push a, 0..9 (version 1.6's `mean_push`, already checked:
 *   R32); MEAN_PUSH when the section gives none
 * @returns {Float64Array} K values: float64(q), exact while |q| <= 2^53, else rounded to nearest
 *   (ties to even) from the exact integer, as §6.3's dequantization needs
 * @throws {TkcError} R32-predictor: predictor 2 on a forest deeper than 2048 depths, or a restored
 *   value outside −2^32..2^32
 */
export declare function restoreMeshColumn(residuals: Int32Array, offset: number, predictor: number, topo: Topology, where: string, push?: number): Float64Array;
