import { BufferGeometry, FileLoader, Loader, Mesh } from 'three';
import { DrawLayout } from './draw.js';
export { TkcError } from '../tkc/decoder.js';
/** The rate, in frames per second, of a file that records none. */
export declare const DEFAULT_FRAME_RATE = 24;
/**
 * The decoder limits (spec §7) TKCLoader opens files with unless told otherwise: sized for a
 * web page, where the decoder's own defaults (DEFAULT_LIMITS, the reference's, for a
 * workstation) let a crafted file of a few KB ask for several GiB and seconds. A page's
 * animated meshes are far below these (a game character has thousands of vertices, a scanned
 * performer a few hundred thousand at most), and a file within them costs a tab tens of MiB:
 *
 * - `max_vertices` 2^18 (262,144): one frame is then 3 MiB as float32 for the GPU, as much for
 *   its normals, 6 MiB as binary64 (twice with corrections);
 * - `max_faces` 2^19 (524,288): the triangle index, 6 MiB or more for polygons;
 * - `max_frames` 2^19 (524,288): two and a half hours at 60 frames a second; time codes then
 *   fit the header limit;
 * - `max_header_bytes` 2^23 (8 MiB), for such time codes: the header is parsed whole;
 * - `max_factor_values` 2^22 (4,194,304): what is decoded before any frame, 32 MiB as
 *   binary64, held two or three times over (U1, its integers with corrections, its SIMD copy):
 *   32,768 vertices with 128 basis columns (a lossless file), or 262,144 with 16;
 * - `max_section_bytes` 2^28 (256 MiB): the largest buffer one section decompresses into.
 *
 * The other limits are the decoder's defaults. A page that plays larger files it trusts raises
 * any of them with setDecoderOptions({limits: {...}}), the rest staying as here.
 */
export declare const WEB_LIMITS: Readonly<{
    max_vertices: number;
    max_faces: number;
    max_frames: number;
    max_header_bytes: number;
    max_factor_values: number;
    max_section_bytes: number;
}>;
export type TkcFile = import('../tkc/decoder.js').TkcFile;
export type DecoderOptions = {
    limits?: {
        [name: string]: number;
    };
    simd?: boolean;
    cachedSegments?: number;
};
/**
 * @typedef {import('../tkc/decoder.js').TkcFile} TkcFile
 * @typedef {{limits?: {[name: string]: number}, simd?: boolean, cachedSegments?: number}} DecoderOptions
 *   what openTkc takes: decoder limits (spec §7) instead of WEB_LIMITS, name by name (higher
 *   for large files a page trusts, lower for one that should be asked for less); `simd: false`
 *   for the plain JavaScript reconstruction; `cachedSegments`, the decoded segments of a
 *   segmented file kept (default 2)
 */
/**
 * One .tkc file played on a THREE.Mesh: its position attribute holds the current frame, its
 * normal attribute and bounds follow it, its index is the file's faces fanned into triangles.
 */
export declare class TKCAnimation {
    /** The decoder's file: header facts, names, faces, any frame as binary64. */
    file: import("../tkc/decoder.js").TkcFile;
    /** The number of frames (F); frames are 0 .. frameCount - 1. */
    frameCount: number;
    /** Frames per second that update() plays at: the file's rate, or DEFAULT_FRAME_RATE. */
    frameRate: number;
    /** Whether update() goes back to frame 0 after the last frame (else it stays there). */
    loop: boolean;
    /** Whether setFrame recomputes the vertex normals (a flat-shaded material needs none). */
    updateNormals: boolean;
    /** The frame the mesh shows. */
    frame: number;
    /** The playback time in seconds, within [0, duration). */
    time: number;
    /**
     * When each frame starts, in seconds from frame 0: from the file's time codes (format 1.4:
     * a cache sampled unevenly plays unevenly), else frame f at f / frameRate.
     */
    frameTimes: Float64Array<ArrayBuffer>;
    /** Milliseconds the last setFrame spent decoding the frame (file.frameFloat32 alone). */
    decodeMs: number;
    /** How the faces and attributes are drawn (three.js's one value per vertex: draw.js). */
    drawLayout: DrawLayout;
    /** The positions of the frame shown, K*3 (the position attribute's array, unless split). */
    _frame: Float32Array<ArrayBuffer>;
    /** The drawn vertices' positions (the position attribute's array). */
    _positions: Float32Array<ArrayBuffer>;
    /** Their normals (the normal attribute's array): the authored ones until a frame recomputes them. */
    _normals: Float32Array<ArrayBuffer>;
    /** The triangles (the index's array), grouped by material. */
    _triangles: Uint32Array<ArrayBufferLike>;
    /** @type {import('three').BufferAttribute} */
    _position: import('three').BufferAttribute;
    /** @type {import('three').BufferAttribute} */
    _normal: import('three').BufferAttribute;
    /** @type {import('three').Material | null} the material made here, disposed by dispose() */
    _ownMaterial: import('three').Material | null;
    /** @type {number[]} */
    _box: number[];
    /** The mesh to add to a scene; its geometry and material are the animation's. */
    mesh: Mesh<BufferGeometry<import("three").NormalBufferAttributes, import("three").BufferGeometryEventMap>, import("three").Material<import("three").MaterialEventMap>, import("three").Object3DEventMap>;
    /**
     * @param {TkcFile} file an opened file (the decoder's openTkc)
     * @param {import('three').Material} [material] the mesh's material (default: a
     *   MeshStandardMaterial drawn on both sides, which dispose() disposes)
     */
    constructor(file: TkcFile, material?: import('three').Material);
    /**
     * The geometry: position and normal (updated per frame), uv and color when the file has them
     * (static), the index, a group per material (userData.materialNames) and bounds.
     * @param {DrawLayout} layout
     */
    _geometry(layout: DrawLayout): BufferGeometry<import("three").NormalBufferAttributes, import("three").BufferGeometryEventMap>;
    /** The length of one pass through every frame, in seconds (the last frame lasts 1 / frameRate). */
    get duration(): number;
    /**
     * Shows frame t: decodes it into the position attribute (float32), then recomputes the
     * normals (when updateNormals) and the geometry's bounds. Playback by update() goes on from
     * the start of frame t.
     * @param {number} t an integer, 0 .. frameCount - 1
     * @returns {this}
     * @throws {RangeError} when the file has no frame t; a TkcError when the frame is damaged
     */
    setFrame(t: number): this;
    /**
     * Advances playback by `seconds` on the real clock (THREE.Clock's getDelta(), say) at
     * frameRate, looping after the last frame unless `loop` is false, and shows the frame that
     * time falls in (the last frame that starts at or before it, frameTimes) when it is not the
     * one shown. A frame the clock passes over is not decoded.
     * @param {number} seconds time since the last call (negative plays backwards)
     * @returns {this}
     */
    update(seconds: number): this;
    /**
     * The last frame that starts at or before `time` (binary search of frameTimes).
     * @param {number} time seconds from frame 0
     * @returns {number}
     */
    _frameAt(time: number): number;
    /** Frees the geometry's GPU buffers and the material made here (not one passed in). */
    dispose(): void;
    /**
     * The geometry's bounding box and sphere from this frame (three.js culls and picks by them).
     * @private
     * @param {Float32Array} positions
     */
    private _bound;
}
/**
 * Loads .tkc files as TKCAnimation objects.
 * @extends {Loader<TKCAnimation>}
 */
export declare class TKCLoader extends Loader<TKCAnimation> {
    /** @type {DecoderOptions} */
    decoderOptions: DecoderOptions;
    /** @type {FileLoader | null} what fetches the files, made by the first load() */
    _fileLoader: FileLoader | null;
    /** @param {import('three').LoadingManager} [manager] */
    constructor(manager?: import('three').LoadingManager);
    /**
     * The options every file is opened with (see DecoderOptions): the limits given replace
     * WEB_LIMITS' (or the decoder's default) one by one, the others stay.
     * @param {DecoderOptions} options
     * @returns {this}
     */
    setDecoderOptions(options: DecoderOptions): this;
    /**
     * What openTkc is given: the options, with WEB_LIMITS under the caller's limits.
     * @returns {DecoderOptions}
     */
    _openOptions(): DecoderOptions;
    /**
     * Fetches `url` (after the loader's path) and parses it. The LoadingManager counts the file
     * until it is parsed, so its onLoad does not fire between the fetch and the parse.
     * @param {string} url
     * @param {(animation: TKCAnimation) => void} onLoad
     * @param {(event: ProgressEvent) => void} [onProgress]
     * @param {(error: unknown) => void} [onError] the fetch's error, or the decoder's TkcError
     */
    load(url: string, onLoad: (animation: TKCAnimation) => void, onProgress?: (event: ProgressEvent) => void, onError?: (error: unknown) => void): void;
    /**
     * Stops the files being fetched: their load() calls onError with the fetch's AbortError.
     * @returns {this}
     */
    abort(): this;
    /**
     * Opens a whole .tkc file held in memory and calls onLoad with its animation, showing frame 0,
     * before returning (so it can be used synchronously). A file that breaks a rule of the format,
     * or declares more than the limits (WEB_LIMITS unless raised: rule R21-header-limit, the
     * limit named in the message), calls onError with the decoder's TkcError (its `rule` names
     * the rule), or throws it when there is no onError.
     * @param {ArrayBuffer | Uint8Array} buffer
     * @param {(animation: TKCAnimation) => void} onLoad
     * @param {(error: unknown) => void} [onError]
     */
    parse(buffer: ArrayBuffer | Uint8Array, onLoad: (animation: TKCAnimation) => void, onError?: (error: unknown) => void): void;
    /**
     * parse() as a promise.
     * @param {ArrayBuffer | Uint8Array} buffer
     * @returns {Promise<TKCAnimation>}
     */
    parseAsync(buffer: ArrayBuffer | Uint8Array): Promise<TKCAnimation>;
}
