// node decode_file.mjs IN.tkc OUT.bin: decodes a whole file with the JavaScript decoder and writes
// its faces (M*n int32) then every frame (F*K*3 float64), little-endian, to OUT.bin; prints the
// facts as JSON, or the error's rule. Run by tests/test_js_decoder.py, which compares the
// result with the Python decoder's on real sequences.

import { readFileSync, writeFileSync } from 'node:fs';
import { openTkc, TkcError } from '../../tuckercodec/web/tkc/decoder.js';

const [input, output] = process.argv.slice(2);
try {
  const started = performance.now();
  const file = openTkc(new Uint8Array(readFileSync(input)));
  const opened = performance.now();
  const K3 = 3 * file.vertices;
  const positions = new Float64Array(file.frames * K3);
  for (let t = 0; t < file.frames; t++) positions.set(file.frame(t), t * K3);
  const decoded = performance.now();
  const faces = new Uint8Array(file.faces.buffer, file.faces.byteOffset, file.faces.byteLength);
  const all = new Uint8Array(faces.length + positions.byteLength);
  all.set(faces, 0);
  all.set(new Uint8Array(positions.buffer), faces.length);
  writeFileSync(output, all);
  process.stdout.write(JSON.stringify({
    accepted: true, version: file.version, vertices: file.vertices, frames: file.frames,
    faces: file.faceCount, face_width: file.faceWidth, names: file.names, ranks: file.ranks,
    frame_rate: file.frameRate, open_ms: opened - started, frames_ms: decoded - opened,
  }));
} catch (error) {
  if (!(error instanceof TkcError)) throw error;
  process.stdout.write(JSON.stringify({ accepted: false, rule: error.rule, kind: error.kind, message: error.message }));
}
