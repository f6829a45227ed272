// The viewer: plays a .tkc file in the browser, decoding it with the JavaScript decoder.
//
//   index.html?file=URL[&reference=URL]
//
// `file` is the compressed file; `reference` (optional) a small JSON describing the original's
// positions, {vertices, frames, dtype: "float32", data: "reference.bin", ...}, `data` being
// F*K*3 little-endian float32 (relative to the JSON's URL): the original rounded to float32.
//
// The file is loaded and played by TKCLoader (../three/TKCLoader.js), as any page using the npm
// package plays one: every frame is reconstructed when it is shown, animation.setFrame(t)
// writing X_t straight into the position attribute of one indexed BufferGeometry, in the file's
// vertex order (then the copies of the vertices a file's UVs, normals or colours split), whose
// index is the faces fanned into triangles; nothing is allocated per frame. Playback follows
// the real clock: the frame shown is floor(elapsed * rate), so it never runs slow; a frame index
// skipped on the way counts as dropped.
//
// window.tkcViewer is the page's contract with its tests (tests/ and tools/ drive it in
// headless Chromium): ready, info, setFrame, drawnPositions, decodedPositions, frameError,
// play, pause, stats.

import { attachedRows, checkerTexture } from './attached.js';
import { DEFAULT_LIMITS } from '../tkc/limits.js';
import {
  FRAME_KG_DEFINITION, colourScale, computeNormals, emptyBox, extendBox, frameError,
  paintDistances,
} from './measure.js';
/** Frames sampled to frame the camera: the box holding them, not just frame 0. */
const FRAMING_SAMPLES = 9;
/** Reconstruction times kept by stats() (the oldest half is dropped beyond it). */
const MAX_TIMINGS = 100000;

/**
 * @typedef {typeof import('three')} Three
 * @typedef {import('../tkc/decoder.js').TkcFile} TkcFile
 * @typedef {import('../three/TKCLoader.js').TKCAnimation} TKCAnimation
 * @typedef {import('three').Mesh<import('three').BufferGeometry, import('three').MeshStandardMaterial>} SolidMesh
 * @typedef {import('three').Mesh<import('three').BufferGeometry, import('three').MeshBasicMaterial>} WireMesh
 * @typedef {{vertices: number, frames: number, positions: Float32Array, maxDistance: number | null,
 *   kg: number | null, source: string}} Reference
 */

/**
 * The page's element of that id (every id asked for is in index.html).
 * @type {(id: string) => HTMLElement}
 */
const $ = (id) => /** @type {HTMLElement} */ (document.getElementById(id));

/** @type {(value?: any) => void} */
let resolveReady;
/** @type {(reason?: any) => void} */
let rejectReady;
const ready = new Promise((resolve, reject) => { resolveReady = resolve; rejectReady = reject; });
ready.catch(() => {}); // shown on the page and logged; not also an "uncaught" rejection

/**
 * The page's state. The file and the scene's fields (THREE ... index) are set in start(), the
 * original's (refGeometry ... lut) by setupReference when there is one, before anything reads
 * them; what may be read before (file, positions, renderer) or without an original (refMesh,
 * refWire) is tested first where it is read.
 * @type {{
 *   THREE: Three, file: TkcFile, animation: TKCAnimation, renderer: import('three').WebGLRenderer,
 *   scene: import('three').Scene, camera: import('three').PerspectiveCamera,
 *   controls: import('../vendor/three/OrbitControls.js').OrbitControls,
 *   group: import('three').Group, geometry: import('three').BufferGeometry,
 *   material: import('three').MeshStandardMaterial, mesh: SolidMesh, wire: WireMesh,
 *   positions: Float32Array, normals: Float32Array, index: Uint32Array,
 *   colours: Float32Array, reference: Reference | null,
 *   refGeometry: import('three').BufferGeometry, refMesh: SolidMesh,
 *   refWire: WireMesh, refPositions: Float32Array, refNormals: Float32Array,
 *   distances: Float32Array, lut: Float32Array, scale: number, scaleFixed: boolean,
 *   colourByError: boolean, layout: string, up: string, shading: string,
 *   frame: number, startFrame: number, rate: number, rateNote: string, bytes: number,
 *   playing: boolean, clockStart: number, lastTick: number, rafPending: boolean, dirty: boolean,
 *   frameMs: number[], updateMs: number[], renderMs: number[], played: number, dropped: number,
 *   openMs: number | null, error: unknown,
 *   lastError: {kg: number | null, maxError: number, definition: string} | null,
 *   box: number[] | null, offset: number, authoredNormals: boolean,
 * }}
 */
const state = /** @type {any} */ ({
  THREE: null, file: null, animation: null, renderer: null, scene: null, camera: null, controls: null,
  group: null, geometry: null, material: null, mesh: null, wire: null,
  positions: null, normals: null, index: null, colours: null,
  reference: null, // {positions: Float32Array F*K*3, maxDistance, kg, note}
  refGeometry: null, refMesh: null, refWire: null, refPositions: null, refNormals: null,
  distances: null, lut: null, scale: 0, scaleFixed: false,
  frame: 0, rate: 0, rateNote: '', bytes: 0,
  playing: false, clockStart: 0, lastTick: 0, rafPending: false, dirty: false,
  frameMs: [], updateMs: [], renderMs: [], played: 0, dropped: 0, openMs: null, error: null,
  lastError: null, box: null, offset: 0, authoredNormals: false,
  // set when the controls first change (undefined before, which read as these)
  colourByError: false, layout: 'beside', up: 'y', shading: 'smooth', startFrame: 0,
});

const info = {
  version: null, vertices: null, frames: null, frameRate: null, faces: null, openMs: null,
  // a file with corrections (format 1.3): the first segment's domain, and the bound the panel
  // shows ("every vertex within D", "lossless"), or null
  corrections: null, bound: null,
};

/** @type {Window & {tkcViewer?: object}} */ (window).tkcViewer = {
  ready,
  info,
  /** @param {number} t */
  async setFrame(t) {
    await ready;
    if (!Number.isInteger(t) || t < 0 || t >= state.file.frames) {
      throw new RangeError(`frame ${t} does not exist: the file has ${state.file.frames} frames`);
    }
    pause();
    showFrame(t);
    render();
    await nextPaint();
  },
  drawnPositions() {
    // the file's vertices: the drawn copies of split vertices follow them
    return state.positions ? state.positions.slice(0, 3 * state.file.vertices) : null;
  },
  /**
   * @param {number} t
   * @param {Float64Array} [out]
   */
  decodedPositions(t, out) {
    // `out` (a Float64Array of K*3) is reused when given, as file.frame's is
    return out === undefined ? state.file.frame(t) : state.file.frame(t, out);
  },
  frameError() {
    return state.lastError;
  },
  play() { play(); },
  pause() { pause(); },
  stats() {
    // frameMs: file.frameFloat32 alone, per frame shown; updateMs: all the page's work for a
    // frame (reconstruction, normals, the original's positions, error colours); renderMs: the
    // renderer.render calls (the GPU's work is not in it)
    return {
      openMs: state.openMs, frameMs: state.frameMs.slice(), played: state.played,
      dropped: state.dropped, updateMs: state.updateMs.slice(), renderMs: state.renderMs.slice(),
    };
  },
};

start().then(
  () => resolveReady(),
  (error) => { fail(error); rejectReady(error); },
);

// ---------------------------------------------------------------------------------------------
// opening

async function start() {
  const params = new URLSearchParams(location.search);
  const fileUrl = params.get('file');
  if (!fileUrl) {
    throw new Error('no file to show: open this page as index.html?file=URL-of-a-.tkc-file');
  }
  const referenceUrl = params.get('reference');
  $('file-name').textContent = fileUrl.split('/').pop() || fileUrl; // already decoded once
  status('loading…');
  // Loaded here rather than imported at the top, so that a missing or broken script is
  // reported on the page like any other failure.
  const [THREE, controls, { TKCLoader }] = await Promise.all([
    import('three'),
    import('../vendor/three/OrbitControls.js'),
    import('../three/TKCLoader.js'),
  ]);
  const [{ animation, fetched }, reference] = await Promise.all([
    // the file is the one its user chose to view: the decoder's own limits, as the command
    // line decodes it, not the loader's WEB_LIMITS for pages that play files from anywhere
    loadAnimation(new TKCLoader().setDecoderOptions({ limits: { ...DEFAULT_LIMITS } }), fileUrl),
    referenceUrl ? fetchReference(referenceUrl) : null,
  ]);
  const opened = performance.now();
  // openMs: the file fetched -> first frame drawn (a reference still arriving is not counted)
  const began = fetched;
  const file = animation.file;
  state.THREE = THREE;
  state.bytes = file.bytes.byteLength;
  state.animation = animation;
  state.file = file;
  if (reference) checkReference(reference, file, /** @type {string} */ (referenceUrl));
  state.reference = reference;
  setupRate(animation);
  setupScene(THREE, controls.OrbitControls, animation);
  if (reference) setupReference(THREE, file);
  const built = performance.now();
  frameCamera();
  const framed = performance.now();
  showFacts(file);
  showFrame(0);
  render();
  const drawn = performance.now();
  state.openMs = drawn - began;
  Object.assign(info, {
    version: file.version, vertices: file.vertices, frames: file.frames,
    frameRate: file.frameRate, faces: file.faceCount, openMs: state.openMs,
    corrections: file.residual(0), bound: boundText(file),
    // where openMs went: TKCLoader's parse (openTkc, the triangles, buffers and frame 0); the
    // rest of the scene; sampling frames to frame the camera; frame 0 shown and the first render
    // (which compiles the shaders)
    openParts: {
      decodeMs: opened - began, sceneMs: built - opened, framingMs: framed - built,
      firstFrameMs: drawn - framed,
    },
  });
  $('open-ms').textContent = `${state.openMs.toFixed(1)} ms (fetched → first frame drawn)`;
  setupControls();
  status('');
  await nextPaint();
}

/**
 * The file's animation, loaded by TKCLoader, and when its last bytes arrived (the last progress
 * event of the fetch; when the browser gives none, when loading began).
 * @param {InstanceType<typeof import('../three/TKCLoader.js').TKCLoader>} loader
 * @param {string} url
 * @returns {Promise<{animation: TKCAnimation, fetched: number}>}
 */
async function loadAnimation(loader, url) {
  let fetched = performance.now();
  let animation;
  try {
    animation = await loader.loadAsync(url, () => {
      fetched = performance.now();
      status('decoding…');
    });
  } catch (error) {
    if (error instanceof Error && !('rule' in error)) {
      throw new Error(`could not fetch the file ${url}: ${error.message}`);
    }
    throw error; // the decoder's TkcError, with its rule
  }
  return { animation, fetched };
}

/**
 * @param {string} url
 * @param {string} what
 */
async function fetchBytes(url, what) {
  let response;
  try {
    response = await fetch(url);
  } catch (error) {
    throw new Error(`could not fetch ${what} ${url}: ${/** @type {Error} */ (error).message}`);
  }
  if (!response.ok) {
    throw new Error(`could not fetch ${what} ${url}: HTTP ${response.status} ${response.statusText}`);
  }
  return new Uint8Array(await response.arrayBuffer());
}

/**
 * The reference's JSON description and its positions (F*K*3 float32).
 * @param {string} url
 * @returns {Promise<Reference>}
 */
async function fetchReference(url) {
  const text = new TextDecoder().decode(await fetchBytes(url, 'the reference'));
  let meta;
  try {
    meta = JSON.parse(text);
  } catch (error) {
    throw new Error(`the reference ${url} is not JSON: ${/** @type {Error} */ (error).message}`);
  }
  /** @param {string} why */
  const bad = (why) => new Error(`the reference ${url}: ${why}`);
  if (meta === null || typeof meta !== 'object') throw bad('expected a JSON object');
  for (const key of ['vertices', 'frames']) {
    if (!Number.isSafeInteger(meta[key]) || meta[key] < 1) throw bad(`"${key}" must be a positive integer`);
  }
  if (meta.dtype !== 'float32') throw bad(`"dtype" must be "float32", got ${JSON.stringify(meta.dtype)}`);
  if (typeof meta.data !== 'string') throw bad('"data" must name the file of positions');
  const dataUrl = new URL(meta.data, new URL(url, location.href)).href;
  const raw = await fetchBytes(dataUrl, 'the reference positions');
  const expected = meta.frames * meta.vertices * 12;
  if (raw.byteLength !== expected) {
    throw bad(`${meta.data} holds ${raw.byteLength} bytes, ${meta.frames} frames of ${meta.vertices} vertices need ${expected}`);
  }
  return {
    vertices: meta.vertices, frames: meta.frames, positions: littleEndianFloat32(raw),
    maxDistance: Number.isFinite(meta.maxDistance) ? meta.maxDistance : null,
    kg: Number.isFinite(meta.kg) ? meta.kg : null,
    source: typeof meta.source === 'string' ? meta.source : url,
  };
}

/** @param {Uint8Array} raw */
function littleEndianFloat32(raw) {
  const aligned = raw.byteOffset % 4 === 0 ? raw : raw.slice();
  const values = new Float32Array(aligned.buffer, aligned.byteOffset, aligned.byteLength / 4);
  if (new Uint8Array(new Uint16Array([1]).buffer)[0] === 1) return values;
  const view = new DataView(aligned.buffer, aligned.byteOffset, aligned.byteLength);
  const swapped = new Float32Array(values.length); // a big-endian machine: read each value
  for (let i = 0; i < swapped.length; i++) swapped[i] = view.getFloat32(i * 4, true);
  return swapped;
}

/**
 * @param {Reference} reference
 * @param {TkcFile} file
 * @param {string} url
 */
function checkReference(reference, file, url) {
  if (reference.vertices !== file.vertices || reference.frames !== file.frames) {
    throw new Error(
      `the reference ${url} has ${reference.frames} frames of ${reference.vertices} vertices, ` +
      `the file ${file.frames} of ${file.vertices}`);
  }
}

/**
 * The rate the animation plays at: the file's, or TKCLoader's default when it records none.
 * @param {TKCAnimation} animation
 */
function setupRate(animation) {
  state.rate = animation.frameRate;
  state.rateNote = animation.frameRate === animation.file.frameRate
    ? `plays at ${formatNumber(animation.frameRate)} frames per second (the file's rate)`
    : `plays at ${formatNumber(animation.frameRate)} frames per second: the file records no frame rate`;
  $('rate-label').textContent = state.rateNote;
}

// ---------------------------------------------------------------------------------------------
// the scene

/**
 * @param {Three} THREE
 * @param {typeof import('../vendor/three/OrbitControls.js').OrbitControls} OrbitControls
 * @param {TKCAnimation} animation
 */
function setupScene(THREE, OrbitControls, animation) {
  const canvas = /** @type {HTMLCanvasElement} */ ($('canvas'));
  const antialias = chooseAntialias();
  const renderer = new THREE.WebGLRenderer({
    canvas, antialias: antialias.on, preserveDrawingBuffer: true, // the tests read the picture back
  });
  $('renderer').textContent = antialias.why;
  renderer.setPixelRatio(window.devicePixelRatio || 1);
  renderer.setClearColor(0x101114);
  const scene = new THREE.Scene();
  const camera = new THREE.PerspectiveCamera(40, 1, 0.01, 100);
  scene.add(camera);
  scene.add(new THREE.HemisphereLight(0xffffff, 0x404048, 1.2));
  const headlight = new THREE.DirectionalLight(0xffffff, 2.2); // follows the camera
  headlight.position.set(0.4, 0.6, 1);
  camera.add(headlight, headlight.target);

  // the animation's mesh: its geometry holds the frame shown (positions, normals, bounds), its
  // index the file's faces fanned into triangles
  const geometry = animation.mesh.geometry;
  state.positions = /** @type {Float32Array} */ (geometry.getAttribute('position').array);
  state.normals = /** @type {Float32Array} */ (geometry.getAttribute('normal').array);
  const index = /** @type {Uint32Array} */ (/** @type {import('three').BufferAttribute} */ (geometry.getIndex()).array);
  const material = new THREE.MeshStandardMaterial({
    color: 0xd8d2c4, roughness: 0.65, metalness: 0, side: THREE.DoubleSide,
  });
  const mesh = /** @type {SolidMesh} */ (animation.mesh);
  mesh.material.dispose(); // the loader's default, never drawn
  mesh.material = material;
  // a file of one frame with authored normals shows them (the loader's choice) unless flat
  state.authoredNormals = !animation.updateNormals;
  if (animation.drawLayout.color !== null) { // the file's colours (format 1.5)
    material.vertexColors = true;
    material.color.set(0xffffff);
  }
  const wire = new THREE.Mesh(geometry, new THREE.MeshBasicMaterial({
    color: 0x000000, wireframe: true, transparent: true, opacity: 0.35,
  }));
  wire.visible = false;
  const group = new THREE.Group();
  group.add(mesh, wire);
  scene.add(group);

  const controls = new OrbitControls(camera, canvas);
  controls.enableDamping = false;
  controls.addEventListener('change', requestRender);

  Object.assign(state, { renderer, scene, camera, controls, group, geometry, material, mesh, wire, index });
  const resize = () => {
    const { clientWidth: width, clientHeight: height } = canvas;
    if (!width || !height) return;
    renderer.setSize(width, height, false);
    camera.aspect = width / height;
    camera.updateProjectionMatrix();
    if (state.openMs !== null) render(); // a resized canvas is blank until drawn again
  };
  new ResizeObserver(resize).observe(canvas);
  resize();
  setUp('y');
}

/**
 * Whether to antialias (multisampling): yes on a graphics card, no on a software renderer
 * (SwiftShader, llvmpipe), where multisampling costs more than drawing and playback would drop
 * frames; the URL's `antialias=on|off` decides instead when given.
 */
function chooseAntialias() {
  const asked = new URLSearchParams(location.search).get('antialias');
  if (asked === 'on' || asked === 'off') {
    return { on: asked === 'on', why: `antialiasing ${asked} (asked for in the URL)` };
  }
  let name = '';
  try {
    const gl = document.createElement('canvas').getContext('webgl2');
    if (gl) {
      const debug = gl.getExtension('WEBGL_debug_renderer_info');
      name = String(gl.getParameter(debug ? debug.UNMASKED_RENDERER_WEBGL : gl.RENDERER));
      const lose = gl.getExtension('WEBGL_lose_context');
      if (lose) lose.loseContext();
    }
  } catch {
    name = '';
  }
  const software = /swiftshader|llvmpipe|softpipe|software/i.test(name);
  return software
    ? { on: false, why: `antialiasing off: a software renderer (${name})` }
    : { on: true, why: `antialiasing on${name ? ` (${name})` : ''}` };
}

/**
 * @param {import('three').BufferAttribute} attribute
 * @param {Three} THREE
 */
function dynamic(attribute, THREE) {
  attribute.setUsage(THREE.DynamicDrawUsage);
  return attribute;
}

/**
 * @param {Three} THREE
 * @param {TkcFile} file
 */
function setupReference(THREE, file) {
  const K = file.vertices;
  state.refPositions = new Float32Array(K * 3);
  state.refNormals = new Float32Array(K * 3);
  state.distances = new Float32Array(K);
  // the error colours of the drawn vertices: the file's K, then the copies of split vertices
  state.colours = new Float32Array(state.animation.drawLayout.count * 3);
  const geometry = new THREE.BufferGeometry();
  geometry.setAttribute('position', dynamic(new THREE.BufferAttribute(state.refPositions, 3), THREE));
  geometry.setAttribute('normal', dynamic(new THREE.BufferAttribute(state.refNormals, 3), THREE));
  // the original has the file's vertices, not the drawn copies: its own index
  state.index = file.triangles();
  geometry.setIndex(new THREE.BufferAttribute(state.index, 1));
  const material = new THREE.MeshStandardMaterial({
    color: 0x9fb4c8, roughness: 0.7, metalness: 0, side: THREE.DoubleSide, transparent: true, opacity: 1,
  });
  const refMesh = new THREE.Mesh(geometry, material);
  const refWire = new THREE.Mesh(geometry, state.wire.material);
  // the original's bounds are not kept up to date: never culled (the decoded mesh's are, by the
  // animation)
  refMesh.frustumCulled = refWire.frustumCulled = false;
  refWire.visible = false;
  state.group.add(refMesh, refWire);
  Object.assign(state, { refGeometry: geometry, refMesh, refWire });

  state.geometry.setAttribute('color', dynamic(new THREE.BufferAttribute(state.colours, 3), THREE));
  state.material.vertexColors = true;
  state.material.color.set(0xffffff);
  // the scale's colours are sRGB; the renderer takes vertex colours in linear RGB
  const scale = colourScale(256);
  state.lut = new Float32Array(scale.length * 3);
  const colour = new THREE.Color();
  scale.forEach(([r, g, b], s) => {
    colour.setRGB(r, g, b, THREE.SRGBColorSpace);
    state.lut.set([colour.r, colour.g, colour.b], s * 3);
  });
  drawLegendBar(scale);
  state.colourByError = true;
  const ref = /** @type {Reference} */ (state.reference); // called only with one
  if (ref.maxDistance !== null) {
    state.scale = ref.maxDistance;
    state.scaleFixed = true;
    $('legend-scale').textContent =
      'Colours: distance to the original on a fixed scale, from 0 (pale yellow) to the largest ' +
      'distance over all frames (dark red), measured when this page was made (the Python ' +
      'decoder against the original rounded to float32).';
  } else {
    $('legend-scale').textContent =
      'Colours: distance to the original, from 0 (pale yellow) to the largest distance over the ' +
      'frames shown so far (dark red; the scale only grows).';
  }
  $('legend').hidden = false;
  $('reference-controls').hidden = false;
  $('frame-error').hidden = false;
  $('frame-kg-definition').textContent = FRAME_KG_DEFINITION +
    '. Original: the reference rounded to float32; decoded: the drawn float32 positions.';
  setLayout('beside');
}

/** @param {number[][]} scale */
function drawLegendBar(scale) {
  const bar = /** @type {HTMLCanvasElement} */ ($('legend-bar'));
  const context = /** @type {CanvasRenderingContext2D} */ (bar.getContext('2d'));
  for (let y = 0; y < bar.height; y++) {
    const s = Math.round((1 - y / (bar.height - 1)) * (scale.length - 1));
    const [r, g, b] = scale[s].map((c) => Math.round(c * 255));
    context.fillStyle = `rgb(${r}, ${g}, ${b})`;
    context.fillRect(0, y, bar.width, 1);
  }
}

function updateLegend() {
  $('legend-max').textContent = formatNumber(state.scale);
  $('legend-mid').textContent = formatNumber(state.scale / 2);
}

/** The box of frames sampled over the first segment (the whole file if it has one), so that a
 * moving mesh stays in view; sampling costs a few reconstructions at opening, no more. */
function sampledBox() {
  const file = state.file;
  const first = file.segments && file.segments.length ? file.segments[0] : { start: 0, frames: file.frames };
  const count = Math.min(FRAMING_SAMPLES, first.frames);
  const box = emptyBox();
  // the file's vertices (the drawn copies of split ones follow): overwritten by showFrame after
  const scratch = state.positions.subarray(0, 3 * file.vertices);
  for (let s = 0; s < count; s++) {
    const t = first.start + (count === 1 ? 0 : Math.round((s * (first.frames - 1)) / (count - 1)));
    extendBox(box, file.frameFloat32(t, scratch));
  }
  if (state.reference) extendBox(box, state.reference.positions.subarray(0, file.vertices * 3));
  return box;
}

function frameCamera() {
  const THREE = state.THREE;
  if (!state.box) state.box = sampledBox();
  const [x0, y0, z0, x1, y1, z1] = state.box;
  const finite = [x0, y0, z0, x1, y1, z1].every(Number.isFinite);
  const min = finite ? new THREE.Vector3(x0, y0, z0) : new THREE.Vector3(-1, -1, -1);
  const max = finite ? new THREE.Vector3(x1, y1, z1) : new THREE.Vector3(1, 1, 1);
  const size = new THREE.Vector3().subVectors(max, min);
  // the original stands beside the decoded mesh at +x, one box width and a gap away
  state.offset = Math.max(size.x, 1e-9) * 1.15;
  if (state.refMesh) placeReference();
  const box = new THREE.Box3(min, max);
  if (state.refMesh && state.layout === 'beside') box.max.x += state.offset;
  // the box in the scene: the group turns the file's up axis to the screen's
  state.group.updateMatrixWorld(true);
  box.applyMatrix4(state.group.matrixWorld);
  const centre = box.getCenter(new THREE.Vector3());
  const radius = Math.max(box.getSize(new THREE.Vector3()).length() / 2, 1e-9);
  const camera = state.camera;
  const distance = radius / Math.sin(THREE.MathUtils.degToRad(camera.fov) / 2) * 1.05;
  camera.near = distance / 100;
  camera.far = distance * 100;
  camera.position.copy(centre).add(new THREE.Vector3(0.35, 0.25, 1).normalize().multiplyScalar(distance));
  camera.updateProjectionMatrix();
  state.controls.target.copy(centre);
  state.controls.update();
  requestRender();
}

/** @param {string} axis */
function setUp(axis) {
  const group = state.group;
  group.rotation.set(0, 0, 0);
  if (axis === 'z') group.rotation.x = -Math.PI / 2;
  if (axis === 'x') group.rotation.z = Math.PI / 2;
  state.up = axis;
}

/** @param {string} layout */
function setLayout(layout) {
  state.layout = layout;
  if (!state.refMesh) return;
  placeReference();
  requestRender();
}

function placeReference() {
  const { refMesh, refWire } = state;
  const layout = state.layout;
  refMesh.visible = layout !== 'hidden';
  refWire.visible = refMesh.visible && state.wire.visible;
  refMesh.position.x = refWire.position.x = layout === 'beside' ? state.offset : 0;
  const overlay = layout === 'overlay';
  refMesh.material.opacity = overlay ? 0.35 : 1;
  refMesh.material.depthWrite = !overlay;
  refMesh.renderOrder = overlay ? 1 : 0; // drawn after the decoded mesh, through it
  refMesh.material.needsUpdate = true;
}

// ---------------------------------------------------------------------------------------------
// one frame

/**
 * Reconstruct frame t into the drawn geometry (and the original's, and the error colours).
 * @param {number} t
 */
function showFrame(t) {
  const file = state.file;
  const animation = state.animation;
  const began = performance.now();
  // smooth normals are only kept up to date while they are used
  const smooth = state.shading !== 'flat';
  animation.updateNormals = smooth && !state.authoredNormals;
  animation.setFrame(t); // the frame, its normals and bounds
  const took = animation.decodeMs;
  if (state.frameMs.length >= MAX_TIMINGS) {
    for (const list of [state.frameMs, state.updateMs, state.renderMs]) list.splice(0, MAX_TIMINGS / 2);
  }
  state.frameMs.push(took);
  state.frame = t;
  const geometry = state.geometry;
  if (state.reference) {
    const K = file.vertices;
    const original = state.reference.positions.subarray(t * K * 3, (t + 1) * K * 3);
    state.refPositions.set(original);
    state.refGeometry.attributes.position.needsUpdate = true;
    if (smooth) {
      computeNormals(state.refPositions, state.index, state.refNormals);
      state.refGeometry.attributes.normal.needsUpdate = true;
    }
    const { kg, maxError } = frameError(original, state.positions, state.distances);
    state.lastError = { kg, maxError, definition: FRAME_KG_DEFINITION };
    if (!state.scaleFixed && maxError > state.scale) state.scale = maxError;
    if (state.colourByError) {
      paintDistances(state.distances, state.scale, state.lut, state.colours);
      copyToSplit(state.colours, animation.drawLayout.vertexOf, file.vertices);
      geometry.attributes.color.needsUpdate = true;
    }
    updateLegend();
    $('frame-kg').textContent = kg === null ? 'undefined (the frame has no spread)' : `${formatNumber(kg)} %`;
    $('frame-max').textContent = `${formatNumber(maxError)} scene units`;
  }
  state.updateMs.push(performance.now() - began);
  const slider = /** @type {HTMLInputElement} */ ($('slider'));
  slider.value = String(t);
  const name = file.names && file.names[t] ? ` — ${file.names[t]}` : '';
  $('frame-label').textContent = `frame ${t} of 0–${file.frames - 1}${name}`;
  $('frame-ms').textContent = `${took.toFixed(2)} ms (frame ${t})`;
  requestRender();
}

/**
 * The values of each drawn copy of a split vertex, from its vertex's (3 each).
 * @param {Float32Array} values
 * @param {Uint32Array} vertexOf the file's vertex of each drawn vertex
 * @param {number} K
 */
function copyToSplit(values, vertexOf, K) {
  for (let d = K; d < vertexOf.length; d++) values.set(values.subarray(3 * vertexOf[d], 3 * vertexOf[d] + 3), 3 * d);
}

function render() {
  state.dirty = false;
  const began = performance.now();
  state.renderer.render(state.scene, state.camera);
  state.renderMs.push(performance.now() - began);
}

function requestRender() {
  state.dirty = true;
  schedule();
}

function schedule() {
  if (state.rafPending || !state.renderer) return;
  state.rafPending = true;
  requestAnimationFrame(tick);
}

/** Resolves once the browser has had a chance to paint (or after 100 ms in a hidden page,
 * where animation frames never come). */
function nextPaint() {
  return new Promise(/** @param {(value?: unknown) => void} resolve */ (resolve) => {
    const timer = setTimeout(resolve, 100);
    requestAnimationFrame(() => { clearTimeout(timer); resolve(); });
  });
}

// ---------------------------------------------------------------------------------------------
// playback

/** @param {number} now */
function tick(now) {
  state.rafPending = false;
  if (state.playing) {
    // frames since play() began, on the real clock; the frame shown is this count past the
    // frame playback started from
    const count = Math.floor(((now - state.clockStart) / 1000) * state.rate);
    if (count > state.lastTick) {
      const skipped = count - state.lastTick - 1;
      state.lastTick = count;
      const F = state.file.frames;
      let t = state.startFrame + count;
      if (t >= F && !loopChecked()) {
        showFrame(F - 1);
        pause();
      } else {
        if (skipped > 0) state.dropped += skipped;
        t %= F;
        showFrame(t);
        state.played += 1;
      }
      updatePlayed();
    }
  }
  if (state.dirty) render();
  if (state.playing) schedule();
}

function play() {
  if (!state.file || state.playing) return;
  let from = state.frame;
  if (from >= state.file.frames - 1 && !loopChecked()) from = 0;
  if (from !== state.frame) showFrame(from);
  state.playing = true;
  state.startFrame = from;
  state.lastTick = 0;
  state.clockStart = performance.now();
  $('play').textContent = 'pause';
  schedule();
}

function pause() {
  if (!state.playing) return;
  state.playing = false;
  $('play').textContent = 'play';
}

/** Whether playback starts again after the last frame. */
function loopChecked() {
  return /** @type {HTMLInputElement} */ ($('loop')).checked;
}

function updatePlayed() {
  $('played').textContent = `${state.played} / ${state.dropped}`;
}

// ---------------------------------------------------------------------------------------------
// controls and facts

function setupControls() {
  const file = state.file;
  const slider = /** @type {HTMLInputElement} */ ($('slider'));
  slider.max = String(file.frames - 1);
  for (const id of ['play', 'step-back', 'step-forward', 'slider', 'reframe']) {
    /** @type {HTMLButtonElement | HTMLInputElement} */ ($(id)).disabled = false;
  }
  $('play').addEventListener('click', () => (state.playing ? pause() : play()));
  /** @param {number} delta */
  const step = (delta) => {
    pause();
    showFrame((state.frame + delta + file.frames) % file.frames);
  };
  $('step-back').addEventListener('click', () => step(-1));
  $('step-forward').addEventListener('click', () => step(1));
  slider.addEventListener('input', () => {
    const t = Number(slider.value);
    const wasPlaying = state.playing;
    pause();
    showFrame(t);
    if (wasPlaying) play(); // scrubbing while playing goes on from the new frame
  });
  $('shading').addEventListener('change', (event) => {
    state.shading = selected(event);
    const flat = state.shading === 'flat';
    state.material.flatShading = flat;
    state.material.needsUpdate = true;
    if (state.refMesh) {
      state.refMesh.material.flatShading = flat;
      state.refMesh.material.needsUpdate = true;
    }
    showFrame(state.frame); // smooth normals are only kept up to date while they are used
  });
  $('wireframe').addEventListener('change', (event) => {
    state.wire.visible = ticked(event);
    if (state.refWire) state.refWire.visible = ticked(event) && state.refMesh.visible;
    requestRender();
  });
  $('up').addEventListener('change', (event) => {
    setUp(selected(event));
    frameCamera();
  });
  $('layout').addEventListener('change', (event) => {
    setLayout(selected(event));
    frameCamera();
  });
  $('colour').addEventListener('change', (event) => {
    state.colourByError = ticked(event);
    const fileColours = state.animation.drawLayout.color;
    if (!state.colourByError && fileColours !== null) { // back to the file's own colours
      state.geometry.setAttribute('color', new state.THREE.BufferAttribute(fileColours, state.animation.drawLayout.colorSize));
    } else if (state.colourByError) {
      state.geometry.setAttribute('color', dynamic(new state.THREE.BufferAttribute(state.colours, 3), state.THREE));
    }
    state.material.vertexColors = state.colourByError || fileColours !== null;
    state.material.color.set(state.material.vertexColors ? 0xffffff : 0xd8d2c4);
    state.material.needsUpdate = true;
    $('legend').hidden = !state.colourByError;
    showFrame(state.frame);
  });
  $('reframe').addEventListener('click', frameCamera);
  setupAttached();
  window.addEventListener('keydown', (event) => {
    if (event.target instanceof HTMLInputElement && event.target.type !== 'range' && event.target.type !== 'checkbox') return;
    if (event.target instanceof HTMLSelectElement) return;
    if (event.key === ' ') { event.preventDefault(); state.playing ? pause() : play(); }
    else if (event.key === 'ArrowRight') { event.preventDefault(); step(1); }
    else if (event.key === 'ArrowLeft') { event.preventDefault(); step(-1); }
  });
  updatePlayed();
}

/** The UV checker toggle, when the file has UVs, and the list of its attributes (format 1.5). */
function setupAttached() {
  const file = state.file;
  if (state.animation.drawLayout.uv !== null) {
    $('uv-control').hidden = false;
    /** @type {import('three').Texture | null} */
    let texture = null;
    $('uv').addEventListener('change', (event) => {
      texture ??= checkerTexture(state.THREE);
      state.material.map = ticked(event) ? texture : null;
      state.material.needsUpdate = true;
      requestRender();
    });
  }
  const rows = attachedRows(file);
  if (rows.length === 0) return;
  const list = $('attached-list');
  for (const [term, value] of rows) {
    const dt = document.createElement('dt');
    dt.textContent = term;
    const dd = document.createElement('dd');
    dd.textContent = value;
    list.append(dt, dd);
  }
  $('attached').hidden = false;
}

/**
 * The value of the select element an event came from.
 * @param {Event} event
 */
function selected(event) {
  return /** @type {HTMLSelectElement} */ (event.target).value;
}

/**
 * Whether the checkbox an event came from is ticked.
 * @param {Event} event
 */
function ticked(event) {
  return /** @type {HTMLInputElement} */ (event.target).checked;
}

/** @param {TkcFile} file */
function showFacts(file) {
  const bytes = state.bytes;
  const bpfv = (8 * bytes) / (file.frames * file.vertices);
  const error = file.error;
  const rows = [
    ['format', file.version],
    ['vertices (K)', file.vertices.toLocaleString('en')],
    ['frames (F)', file.frames.toLocaleString('en')],
    ['faces', `${file.faceCount.toLocaleString('en')} of up to ${file.faceWidth} corners`],
    ['size', `${bytes.toLocaleString('en')} bytes`],
    ['bpfv', `${bpfv.toFixed(4)} bits per frame per vertex (8·bytes / (F·K), the whole file)`],
    ['frame rate', file.frameRate ? `${formatNumber(file.frameRate)} fps` : `none recorded (plays at ${formatNumber(state.rate)})`],
    ['segments', segmentsText(file.segments)],
    ['KG error', error && Number.isFinite(error.kg) ? `${formatNumber(/** @type {number} */ (error.kg))} % (the encoder's claim, in the header)` : 'not recorded in the header'],
  ];
  if (error && Number.isFinite(error.targetKg)) rows.push(['target KG', `${formatNumber(/** @type {number} */ (error.targetKg))} %`]);
  const corrections = correctionsText(file);
  if (corrections !== null) rows.push(['corrections', corrections]);
  const bound = boundText(file);
  if (bound !== null) rows.push(['vertex bound', bound]);
  const ref = state.reference;
  if (ref) {
    rows.push(['original', `${ref.source}, positions rounded to float32`]);
    if (ref.kg !== null) rows.push(['measured KG', `${formatNumber(ref.kg)} % over the whole sequence, against the original (float32)`]);
  }
  const list = $('facts-list');
  list.replaceChildren();
  for (const [term, value] of rows) {
    const dt = document.createElement('dt');
    dt.textContent = term;
    const dd = document.createElement('dd');
    dd.textContent = value;
    list.append(dt, dd);
  }
  $('facts-note').textContent = error && error.definition ? `KG: ${error.definition}` : '';
}

/**
 * What a file with corrections (§6.9) stores: the domain of each segment's RESD, or null.
 * @param {TkcFile} file
 */
function correctionsText(file) {
  if (!file.layout.corrections) return null;
  // a segmented file decodes a segment when a frame of it is first shown: segment 0 is decoded
  const r = /** @type {NonNullable<ReturnType<TkcFile['residual']>>} */ (file.residual(0));
  const more = file.segments.length > 1 ? ' (segment 0)' : '';
  if (r.domain === 'grid') return `on a grid of step ${formatNumber(r.step)} scene units${more}`;
  if (r.domain === 'decimal-places') return `to decimals of ${r.scale} places${more}`;
  if (r.domain === 'decimal-digits') return `to decimals of ${r.scale} significant digits${more}`;
  if (r.domain === 'decimal-digits-float32') return `to binary32 values of decimals of ${r.scale} significant digits${more}`;
  return `to exact ${r.domain === 'float32' ? 'binary32' : 'binary64'} values${more}`;
}

/**
 * The bound on every vertex the header claims (§4.1, 1.3): "lossless", or "every vertex within
 * D" from target_max_distance (else max_distance), with the distance measured and where; null
 * when the header claims neither.
 * @param {TkcFile} file
 * @returns {string | null}
 */
function boundText(file) {
  const error = file.error;
  if (!error) return null;
  const claim = "(the encoder's claim, in the header)";
  if (error.lossless === true) return `lossless: every value is the original's, bit for bit ${claim}`;
  const measured = error.maxDistance;
  const at = error.maxDistanceAt ? ` at frame ${error.maxDistanceAt[0]}, vertex ${error.maxDistanceAt[1]}` : '';
  if (error.targetMaxDistance !== null && Number.isFinite(error.targetMaxDistance)) {
    const largest = measured !== null && Number.isFinite(measured) ? `; the largest is ${formatNumber(measured)}${at}` : '';
    return `every vertex within ${formatNumber(error.targetMaxDistance)} scene units of the original${largest} ${claim}`;
  }
  if (measured !== null && Number.isFinite(measured)) {
    return `every vertex within ${formatNumber(measured)} scene units of the original, the largest distance measured${at} ${claim}`;
  }
  return null;
}

/** @param {TkcFile['segments']} segments */
function segmentsText(segments) {
  if (!segments || segments.length <= 1) {
    const ranks = segments && segments[0] ? segments[0].ranks : null;
    return ranks ? `one; ranks (i, 3, k) = (${ranks[0]}, 3, ${ranks[1]})` : 'one';
  }
  const bases = new Set(segments.map((s) => s.basis));
  return `${segments.length} (${[...bases].join(', ')} U1)`;
}

// ---------------------------------------------------------------------------------------------
// messages

/** @param {string} text */
function status(text) {
  $('status').textContent = text;
}

/** @param {any} error whatever was thrown */
function fail(error) {
  state.error = error;
  pause();
  console.error(error);
  const box = $('error');
  const message = error && error.message ? error.message : String(error);
  // a TkcError's message already ends with its rule, "[R10-file-truncated]"
  const rule = error && error.rule && !message.includes(error.rule) ? ` [${error.rule}]` : '';
  const kind = error && error.kind ? `${error.kind}: ` : '';
  box.textContent = `Cannot show this file. ${kind}${message}${rule}`;
  box.hidden = false;
  status('');
}

/** @param {number} value */
function formatNumber(value) {
  if (!Number.isFinite(value)) return String(value);
  if (value === 0) return '0';
  const magnitude = Math.abs(value);
  if (magnitude >= 1e5 || magnitude < 1e-3) return value.toExponential(3);
  return value.toPrecision(4).replace(/(\.\d*?)0+$/, '$1').replace(/\.$/, '');
}

window.addEventListener('error', (event) => {
  if (!state.error) fail(event.error || new Error(event.message));
});
