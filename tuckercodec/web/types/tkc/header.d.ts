export type MsgValue = import('./msgpack.js').MsgValue;
export type Limits = import('./limits.js').Limits;
export type Container = import('./container.js').Container;
export type Section = import('./container.js').Section;
export type Segment = {
    start: number;
    frames: number;
    ranks: number[];
    u2: Float64Array;
    basis: 'whole' | 'shared' | 'own';
    u1: Section;
    u3: Section;
    core: Section;
    cent: Section;
    resd: Section | null;
};
export type Layout = {
    vertices: number;
    frames: number;
    frameRate: number | null;
    timeCodes: Float64Array | null;
    metersPerUnit: number | null;
    upAxis: string | null;
    segmented: boolean;
    codingTools: boolean;
    corrections: boolean;
    adaptive: boolean;
    adaptiveCorrections: boolean;
    codebooks: boolean;
    uniformRanks: boolean;
    segments: Segment[];
    face: Section;
    faceShape: number[];
    name: Section | null;
    sharedU1: Section | null;
    sharedColumns: number;
};
/**
 * Steps 10-14 (or 10s-14): the layout of the file.
 * @param {Container} container
 * @param {Limits} limits
 * @returns {Layout}
 */
export declare function readLayout(container: Container, limits: Limits): Layout;
