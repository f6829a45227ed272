// node --import ./three_from_vendor.mjs loader_attributes.mjs IN.tkc FRAME: the geometry TKCLoader
// makes of a file with attributes and face sets (format 1.5), at frame FRAME, as JSON: its
// attributes' arrays (base64, little-endian), the index, the groups and material names, each
// drawn vertex's file vertex, and the frame's positions as the decoder gives them (float32).
// Run by tests/test_js_loader_attributes.py, which checks them against the Python decoder.

import { readFileSync } from 'node:fs';
import { TKCLoader } from '../../tuckercodec/web/three/TKCLoader.js';

const [input, frame] = process.argv.slice(2);
const bytes = readFileSync(input);
/** @param {ArrayLike<number> & {buffer: ArrayBuffer, byteOffset: number, byteLength: number}} values */
const base64 = (values) => Buffer.from(new Uint8Array(values.buffer, values.byteOffset, values.byteLength)).toString('base64');
const animation = await new TKCLoader().parseAsync(new Uint8Array(bytes));
animation.setFrame(Number(frame));
const geometry = animation.mesh.geometry;
/** @type {{[name: string]: {array: string, itemSize: number}}} */
const attributes = {};
for (const [name, attribute] of Object.entries(geometry.attributes)) {
  attributes[name] = { array: base64(/** @type {Float32Array} */ (attribute.array)), itemSize: attribute.itemSize };
}
process.stdout.write(JSON.stringify({
  attributes,
  index: base64(/** @type {Uint32Array} */ (/** @type {import('three').BufferAttribute} */ (geometry.index).array)),
  groups: geometry.groups,
  materialNames: geometry.userData.materialNames,
  vertexOf: base64(animation.drawLayout.vertexOf),
  frame: base64(animation.file.frameFloat32(Number(frame))),
  updateNormals: animation.updateNormals,
  vertexColors: /** @type {import('three').MeshStandardMaterial} */ (animation.mesh.material).vertexColors,
}));
