// The script of tests/js/pixels.html (served as pixels/page.mjs, beside the viewer's folders).
// window.tkcPixels, once `ready`:
//   draw('original')  the source's mesh, built here from data/original.json's arrays: the frame's
//                     positions, the faces (fanned), a UV and a colour per corner, and a group
//                     per material (its faces in the file's order, then the faces of none);
//   draw('decoded')   the .tkc's mesh as TKCLoader gives it, at the same frame;
//   draw('decoded', 'reversed-uv' | 'next-uv')  the same with its UVs broken on purpose (the
//                     drawn vertices' UV rows reversed, or each taking the next one's): the
//                     negative controls;
//   drawn(name)       from the loader's geometry, per index entry (triangle corner): 'uv',
//                     'color', 'position' (float32, as drawn) or 'vertex' (the file's vertex);
//   layout()          the loader's groups and geometry.userData.materialNames.
// Both meshes have one MeshBasicMaterial per material (unlit: normals change nothing), with the
// checker texture, its material's tint and the vertex colours; the camera is fixed by the
// original's bounding box, so both pictures are taken from the same place.
import * as THREE from 'three';
import { TKCLoader } from '../three/TKCLoader.js';

const SIZE = 480;
const CHECKER_TEXELS = 64;
const CHECKER_SQUARES = 8;
/** The tint of each material, in the order of the original's materialBind sets. */
const TINTS = [0xffffff, 0xffd070, 0x80ffd0, 0xd0a0ff];
const FALLBACK_TINT = 0x909090;

async function fetchOk(url) {
  const response = await fetch(url);
  if (!response.ok) throw new Error(`${url}: HTTP ${response.status}`);
  return response;
}

/** A checker of CHECKER_SQUARES squares a side, light and dark, with a red mark in one corner
 *  square so that a UV flipped or rotated shows too. */
function checkerTexture() {
  const n = CHECKER_TEXELS;
  const square = n / CHECKER_SQUARES;
  const texels = new Uint8Array(4 * n * n);
  for (let y = 0; y < n; y++) {
    for (let x = 0; x < n; x++) {
      const light = (Math.floor(x / square) + Math.floor(y / square)) % 2 === 0;
      const marked = x < square && y < square;
      const i = 4 * (y * n + x);
      texels.set(marked ? [230, 40, 40, 255] : light ? [235, 235, 235, 255] : [40, 40, 40, 255], i);
    }
  }
  const texture = new THREE.DataTexture(texels, n, n, THREE.RGBAFormat);
  texture.magFilter = THREE.NearestFilter;
  texture.minFilter = THREE.NearestFilter;
  texture.wrapS = texture.wrapT = THREE.RepeatWrapping;
  texture.needsUpdate = true;
  return texture;
}

/** The typed arrays data/original.json describes, from data/original.bin. */
function unpack(description, bytes) {
  const kinds = { float32: Float32Array, int32: Int32Array };
  const arrays = {};
  for (const [name, { dtype, offset, length }] of Object.entries(description.arrays)) {
    arrays[name] = new kinds[dtype](bytes, offset, length);
  }
  return arrays;
}

/**
 * The original's geometry: not indexed, three corners per triangle, each with its vertex's
 * position at the frame, its own UV and colour; faces fanned, grouped by material (a face in
 * two sets drawn with the first), the faces of none last.
 */
function originalGeometry(description, arrays) {
  const { faces: M, width: n, materials } = description;
  const material = new Int32Array(M).fill(-1);
  materials.forEach((name, m) => {
    for (const f of arrays[`set:${name}`]) if (material[f] < 0) material[f] = m;
  });
  const starts = new Int32Array(M + 1);
  for (let f = 0; f < M; f++) {
    let real = 0;
    while (real < n && arrays.faces[f * n + real] >= 0) real++;
    starts[f + 1] = starts[f] + real;
  }
  const triangles = starts[M] - 2 * M;
  const position = new Float32Array(9 * triangles);
  const uv = new Float32Array(6 * triangles);
  const color = new Float32Array(9 * triangles);
  const geometry = new THREE.BufferGeometry();
  let t = 0;
  const put = (f, c) => {
    const v = arrays.faces[f * n + (c - starts[f])];
    position.set(arrays.positions.subarray(3 * v, 3 * v + 3), 3 * t);
    uv.set(arrays.uv.subarray(2 * c, 2 * c + 2), 2 * t);
    color.set(arrays.color.subarray(3 * c, 3 * c + 3), 3 * t);
    t++;
  };
  for (let m = 0; m <= materials.length; m++) {
    const start = t;
    const wanted = m === materials.length ? -1 : m;
    for (let f = 0; f < M; f++) {
      if (material[f] !== wanted) continue;
      for (let c = starts[f] + 1; c + 1 < starts[f + 1]; c++) {
        put(f, starts[f]);
        put(f, c);
        put(f, c + 1);
      }
    }
    if (t > start) geometry.addGroup(start, t - start, m);
  }
  geometry.setAttribute('position', new THREE.BufferAttribute(position, 3));
  geometry.setAttribute('uv', new THREE.BufferAttribute(uv, 2));
  geometry.setAttribute('color', new THREE.BufferAttribute(color, 3));
  geometry.userData.materialNames = [...materials, null];
  return geometry;
}

/** One unlit, textured material per name (in the original's order), and one for the faces of
 *  none: `materialNames.map(...)` as the loader's README says. */
function materialsFor(names, texture) {
  const made = new Map();
  const make = (tint) => new THREE.MeshBasicMaterial({
    map: texture, color: tint, vertexColors: true, side: THREE.DoubleSide,
  });
  names.forEach((name, i) => made.set(name, make(TINTS[i % TINTS.length])));
  const fallback = make(FALLBACK_TINT);
  return (/** @type {(string | null)[]} */ wanted) => wanted.map((name) => made.get(name) ?? fallback);
}

/** A camera looking down on the original's bounding sphere, from above and to one side. */
function cameraFor(geometry) {
  geometry.computeBoundingSphere();
  const { center, radius } = geometry.boundingSphere;
  const fov = 35;
  const camera = new THREE.PerspectiveCamera(fov, 1, radius / 100, radius * 100);
  const distance = (1.05 * radius) / Math.sin(THREE.MathUtils.degToRad(fov / 2));
  camera.position.copy(new THREE.Vector3(0.3, 1.0, 0.7).normalize().multiplyScalar(distance).add(center));
  camera.lookAt(center);
  return camera;
}

/** The UV rows of a drawn mesh, broken on purpose (a negative control). */
function brokenUv(uv, how) {
  const count = uv.length / 2;
  const out = new Float32Array(uv.length);
  for (let d = 0; d < count; d++) {
    const from = how === 'reversed-uv' ? count - 1 - d : (d + 1) % count;
    out[2 * d] = uv[2 * from];
    out[2 * d + 1] = uv[2 * from + 1];
  }
  return out;
}

/** Per index entry of `geometry`, the `size` values of `values` at its drawn vertex. */
function perCorner(geometry, values, size) {
  const index = geometry.index.array;
  const out = new values.constructor(index.length * size);
  for (let i = 0; i < index.length; i++) {
    for (let j = 0; j < size; j++) out[i * size + j] = values[index[i] * size + j];
  }
  return out;
}

async function setUp() {
  document.body.style.margin = '0';
  const description = await (await fetchOk('../data/original.json')).json();
  const arrays = unpack(description, await (await fetchOk('../data/original.bin')).arrayBuffer());
  const animation = await new TKCLoader().loadAsync(`../data/${description.tkc}`);
  animation.updateNormals = false; // unlit: the normals are not drawn
  animation.setFrame(description.frame);
  const original = originalGeometry(description, arrays);
  const decoded = animation.mesh.geometry;
  const materials = materialsFor(description.materials, checkerTexture());
  const canvas = /** @type {HTMLCanvasElement} */ (document.getElementById('canvas'));
  const renderer = new THREE.WebGLRenderer({ canvas, antialias: false, preserveDrawingBuffer: true });
  renderer.setPixelRatio(1);
  renderer.setSize(SIZE, SIZE);
  renderer.setClearColor(0x203040);
  const camera = cameraFor(original);
  const uv = decoded.getAttribute('uv').array;

  const draw = (which, control = null) => {
    const geometry = which === 'original' ? original : decoded;
    decoded.setAttribute('uv', new THREE.BufferAttribute(control ? brokenUv(uv, control) : uv, 2));
    const scene = new THREE.Scene();
    scene.add(new THREE.Mesh(geometry, materials(geometry.userData.materialNames)));
    renderer.render(scene, camera);
    return { width: SIZE, height: SIZE, triangles: (geometry.index ? geometry.index.count : geometry.getAttribute('position').count) / 3 };
  };
  const drawn = (name) => {
    if (name === 'vertex') return perCorner(decoded, animation.drawLayout.vertexOf, 1);
    const attribute = decoded.getAttribute(name);
    return perCorner(decoded, name === 'uv' ? uv : attribute.array, attribute.itemSize);
  };
  const layout = () => ({
    groups: decoded.groups.map(({ start, count, materialIndex }) => ({ start, count, materialIndex })),
    materialNames: decoded.userData.materialNames,
    frame: animation.frame,
  });
  return { draw, drawn, layout };
}

const ready = setUp();
window.tkcPixels = { ready };
ready.then((api) => Object.assign(window.tkcPixels, api));
