// TKCLoader: a three.js loader of .tkc files, in the convention of three.js's own loaders
// (DRACOLoader, KTX2Loader, GLTFLoader): it extends THREE.Loader, fetches with THREE.FileLoader
// (path, request header, credentials and LoadingManager honoured) and resolves to a TKCAnimation,
// whose `mesh` shows one frame at a time, decoded on demand by the JavaScript decoder
// (../tkc/decoder.js): no frame is decoded before it is shown, and any frame can be shown next.
//
//   import { TKCLoader } from 'tuckercodec/three';
//   const animation = await new TKCLoader().loadAsync('anim.tkc');
//   scene.add(animation.mesh);
//   // in the render loop:
//   animation.update(clock.getDelta());
//
// The page that imports it resolves the bare specifier `three` (an import map, or a bundler).

import {
  Box3, BufferAttribute, BufferGeometry, DoubleSide, DynamicDrawUsage, FileLoader, Loader, Mesh,
  MeshStandardMaterial, Sphere,
} from 'three';
import { openTkc } from '../tkc/decoder.js';
import { DrawLayout } from './draw.js';
import { computeBounds } from './normals.js';

export { TkcError } from '../tkc/decoder.js';

/** The rate, in frames per second, of a file that records none. */
export const DEFAULT_FRAME_RATE = 24;

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
export const WEB_LIMITS = Object.freeze({
  max_vertices: 2 ** 18,
  max_faces: 2 ** 19,
  max_frames: 2 ** 19,
  max_header_bytes: 2 ** 23,
  max_factor_values: 2 ** 22,
  max_section_bytes: 2 ** 28,
});

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
export class TKCAnimation {
  /**
   * @param {TkcFile} file an opened file (the decoder's openTkc)
   * @param {import('three').Material} [material] the mesh's material (default: a
   *   MeshStandardMaterial drawn on both sides, which dispose() disposes)
   */
  constructor(file, material) {
    /** The decoder's file: header facts, names, faces, any frame as binary64. */
    this.file = file;
    /** The number of frames (F); frames are 0 .. frameCount - 1. */
    this.frameCount = file.frames;
    const rate = file.frameRate;
    /** Frames per second that update() plays at: the file's rate, or DEFAULT_FRAME_RATE. */
    this.frameRate = typeof rate === 'number' && Number.isFinite(rate) && rate > 0 ? rate : DEFAULT_FRAME_RATE;
    /** Whether update() goes back to frame 0 after the last frame (else it stays there). */
    this.loop = true;
    /** Whether setFrame recomputes the vertex normals (a flat-shaded material needs none). */
    this.updateNormals = true;
    /** The frame the mesh shows. */
    this.frame = 0;
    /** The playback time in seconds, within [0, duration). */
    this.time = 0;
    /**
     * When each frame starts, in seconds from frame 0: from the file's time codes (format 1.4:
     * a cache sampled unevenly plays unevenly), else frame f at f / frameRate.
     */
    this.frameTimes = new Float64Array(this.frameCount);
    const codes = file.timeCodes;
    for (let f = 0; f < this.frameCount; f++) {
      this.frameTimes[f] = codes ? (codes[f] - codes[0]) / this.frameRate : f / this.frameRate;
    }
    /** Milliseconds the last setFrame spent decoding the frame (file.frameFloat32 alone). */
    this.decodeMs = 0;

    /** How the faces and attributes are drawn (three.js's one value per vertex: draw.js). */
    this.drawLayout = new DrawLayout(file);
    const layout = this.drawLayout;
    const K = file.vertices;
    /** The positions of the frame shown, K*3 (the position attribute's array, unless split). */
    this._frame = new Float32Array(3 * K);
    /** The drawn vertices' positions (the position attribute's array). */
    this._positions = layout.count === K ? this._frame : new Float32Array(3 * layout.count);
    /** Their normals (the normal attribute's array): the authored ones until a frame recomputes them. */
    this._normals = layout.normal ? layout.normal.slice() : new Float32Array(3 * layout.count);
    /** The triangles (the index's array), grouped by material. */
    this._triangles = layout.triangles;
    const geometry = this._geometry(layout);
    /** @type {import('three').BufferAttribute} */
    this._position = /** @type {import('three').BufferAttribute} */ (geometry.getAttribute('position'));
    /** @type {import('three').BufferAttribute} */
    this._normal = /** @type {import('three').BufferAttribute} */ (geometry.getAttribute('normal'));
    if (layout.normal !== null && file.frames === 1) this.updateNormals = false; // the authored normals
    /** @type {import('three').Material | null} the material made here, disposed by dispose() */
    this._ownMaterial = material ? null : new MeshStandardMaterial({ side: DoubleSide, vertexColors: layout.color !== null });
    /** @type {number[]} */
    this._box = new Array(6).fill(0);
    /** The mesh to add to a scene; its geometry and material are the animation's. */
    this.mesh = new Mesh(geometry, material || /** @type {import('three').Material} */ (this._ownMaterial));
    this.mesh.name = 'tkc';
    this.setFrame(0);
  }

  /**
   * The geometry: position and normal (updated per frame), uv and color when the file has them
   * (static), the index, a group per material (userData.materialNames) and bounds.
   * @param {DrawLayout} layout
   */
  _geometry(layout) {
    const geometry = new BufferGeometry();
    geometry.setAttribute('position', new BufferAttribute(this._positions, 3).setUsage(DynamicDrawUsage));
    geometry.setAttribute('normal', new BufferAttribute(this._normals, 3).setUsage(DynamicDrawUsage));
    if (layout.uv !== null) geometry.setAttribute('uv', new BufferAttribute(layout.uv, 2));
    if (layout.color !== null) geometry.setAttribute('color', new BufferAttribute(layout.color, layout.colorSize));
    geometry.setIndex(new BufferAttribute(this._triangles, 1));
    for (const { start, count, materialIndex } of layout.groups) geometry.addGroup(start, count, materialIndex);
    geometry.userData.materialNames = layout.materialNames;
    geometry.boundingBox = new Box3();
    geometry.boundingSphere = new Sphere();
    return geometry;
  }

  /** The length of one pass through every frame, in seconds (the last frame lasts 1 / frameRate). */
  get duration() {
    return this.frameTimes[this.frameCount - 1] + 1 / this.frameRate;
  }

  /**
   * Shows frame t: decodes it into the position attribute (float32), then recomputes the
   * normals (when updateNormals) and the geometry's bounds. Playback by update() goes on from
   * the start of frame t.
   * @param {number} t an integer, 0 .. frameCount - 1
   * @returns {this}
   * @throws {RangeError} when the file has no frame t; a TkcError when the frame is damaged
   */
  setFrame(t) {
    if (!Number.isInteger(t) || t < 0 || t >= this.frameCount) {
      throw new RangeError(`frame ${t} does not exist: the file has frames 0..${this.frameCount - 1}`);
    }
    const began = performance.now();
    this.file.frameFloat32(t, this._frame);
    this.decodeMs = performance.now() - began;
    this.drawLayout.positionsInto(this._frame, this._positions);
    this._position.needsUpdate = true;
    if (this.updateNormals) {
      this.drawLayout.normalsInto(this._frame, this._normals);
      this._normal.needsUpdate = true;
    }
    this._bound(this._frame);
    this.frame = t;
    this.time = Math.min(this.frameTimes[t], Number.MAX_VALUE); // finite at any frame rate
    return this;
  }

  /**
   * Advances playback by `seconds` on the real clock (THREE.Clock's getDelta(), say) at
   * frameRate, looping after the last frame unless `loop` is false, and shows the frame that
   * time falls in (the last frame that starts at or before it, frameTimes) when it is not the
   * one shown. A frame the clock passes over is not decoded.
   * @param {number} seconds time since the last call (negative plays backwards)
   * @returns {this}
   */
  update(seconds) {
    if (!Number.isFinite(seconds)) throw new RangeError(`update takes a finite number of seconds, not ${seconds}`);
    const duration = this.duration;
    let time = this.time + seconds;
    // A valid frame rate as small as 5e-324 makes frame times, and a pass, infinite: such a
    // pass never ends, so it is played without looping, and the time stays finite (it once
    // went to Infinity on a step back, then NaN).
    if (this.loop && Number.isFinite(duration)) {
      time %= duration;
      if (time < 0) time += duration;
      // a tiny step back from 0 rounds to duration itself: the end of the last frame
      if (!(time < duration)) time = duration * (1 - Number.EPSILON);
    } else {
      const last = Math.min(this.frameTimes[this.frameCount - 1], Number.MAX_VALUE);
      time = Math.min(Math.max(time, 0), last);
    }
    const frame = this._frameAt(time);
    if (frame !== this.frame) this.setFrame(frame);
    this.time = time;
    return this;
  }

  /**
   * The last frame that starts at or before `time` (binary search of frameTimes).
   * @param {number} time seconds from frame 0
   * @returns {number}
   */
  _frameAt(time) {
    let low = 0;
    let high = this.frameCount - 1;
    while (low < high) {
      const middle = (low + high + 1) >> 1;
      if (this.frameTimes[middle] <= time) low = middle;
      else high = middle - 1;
    }
    return low;
  }

  /** Frees the geometry's GPU buffers and the material made here (not one passed in). */
  dispose() {
    this.mesh.geometry.dispose();
    if (this._ownMaterial) this._ownMaterial.dispose();
  }

  /**
   * The geometry's bounding box and sphere from this frame (three.js culls and picks by them).
   * @private
   * @param {Float32Array} positions
   */
  _bound(positions) {
    const geometry = this.mesh.geometry;
    const box = /** @type {import('three').Box3} */ (geometry.boundingBox);
    const sphere = /** @type {import('three').Sphere} */ (geometry.boundingSphere);
    const radius2 = computeBounds(positions, this._box);
    if (radius2 < 0) {
      box.makeEmpty();
      sphere.makeEmpty();
      return;
    }
    const b = this._box;
    box.min.set(b[0], b[1], b[2]);
    box.max.set(b[3], b[4], b[5]);
    box.getCenter(sphere.center);
    sphere.radius = Math.sqrt(radius2);
  }
}

/**
 * Loads .tkc files as TKCAnimation objects.
 * @extends {Loader<TKCAnimation>}
 */
export class TKCLoader extends Loader {
  /** @param {import('three').LoadingManager} [manager] */
  constructor(manager) {
    super(manager);
    /** @type {DecoderOptions} */
    this.decoderOptions = {};
    /** @type {FileLoader | null} what fetches the files, made by the first load() */
    this._fileLoader = null;
  }

  /**
   * The options every file is opened with (see DecoderOptions): the limits given replace
   * WEB_LIMITS' (or the decoder's default) one by one, the others stay.
   * @param {DecoderOptions} options
   * @returns {this}
   */
  setDecoderOptions(options) {
    this.decoderOptions = { ...options };
    return this;
  }

  /**
   * What openTkc is given: the options, with WEB_LIMITS under the caller's limits.
   * @returns {DecoderOptions}
   */
  _openOptions() {
    return { ...this.decoderOptions, limits: { ...WEB_LIMITS, ...this.decoderOptions.limits } };
  }

  /**
   * Fetches `url` (after the loader's path) and parses it. The LoadingManager counts the file
   * until it is parsed, so its onLoad does not fire between the fetch and the parse.
   * @param {string} url
   * @param {(animation: TKCAnimation) => void} onLoad
   * @param {(event: ProgressEvent) => void} [onProgress]
   * @param {(error: unknown) => void} [onError] the fetch's error, or the decoder's TkcError
   */
  load(url, onLoad, onProgress, onError) {
    this.manager.itemStart(url);
    /** @param {unknown} error */
    const failed = (error) => {
      if (onError) onError(error);
      else console.error(error);
      this.manager.itemError(url);
      this.manager.itemEnd(url);
    };
    const loader = (this._fileLoader ??= new FileLoader(this.manager));
    loader.setPath(this.path);
    loader.setResponseType('arraybuffer');
    loader.setRequestHeader(this.requestHeader);
    loader.setWithCredentials(this.withCredentials);
    loader.load(url, (buffer) => {
      this.parse(/** @type {ArrayBuffer} */ (buffer), (animation) => {
        onLoad(animation);
        this.manager.itemEnd(url);
      }, failed);
    }, onProgress, failed);
  }

  /**
   * Stops the files being fetched: their load() calls onError with the fetch's AbortError.
   * @returns {this}
   */
  abort() {
    if (this._fileLoader) this._fileLoader.abort();
    return this;
  }

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
  parse(buffer, onLoad, onError) {
    let animation;
    try {
      animation = new TKCAnimation(openTkc(buffer, this._openOptions()));
    } catch (error) {
      if (!onError) throw error;
      onError(error);
      return;
    }
    onLoad(animation);
  }

  /**
   * parse() as a promise.
   * @param {ArrayBuffer | Uint8Array} buffer
   * @returns {Promise<TKCAnimation>}
   */
  parseAsync(buffer) {
    return new Promise((resolve, reject) => this.parse(buffer, resolve, reject));
  }
}
