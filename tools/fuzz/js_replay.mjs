// node js_replay.mjs LIST: decodes each file named in LIST (one path a line) with the JavaScript
// decoder, in this one process, as a viewer would: open it, its faces, every frame. Prints one
// JSON line per file as soon as it is done (so that a hang or a crash of node names the file it
// was on): {"accepted": true} or {"accepted": false, "rule", "kind", "message"} for a TkcError, or
// {"crashed": true, "name", "message", "stack"} for anything else, which is a finding. Run by
// tools/fuzz/javascript.py, which compares it with the Python decoder on the same files.

import { readFileSync } from 'node:fs';
import { openTkc, TkcError } from '../../tuckercodec/web/tkc/decoder.js';

/**
 * Every part a caller can ask for: the header's facts, faces, names, every segment's factors
 * (check(), as the Python decode reads them all before a frame), every frame.
 */
function decodeAll(bytes) {
  const file = openTkc(bytes).check();
  const out = new Float64Array(3 * file.vertices);
  let sum = file.faces.length + (file.names ? file.names.length : 0);
  for (let t = 0; t < file.frames; t++) {
    file.frame(t, out);
    sum += out.length;
  }
  return { accepted: true, version: file.version, vertices: file.vertices, frames: file.frames, sum };
}

function outcome(path) {
  try {
    return decodeAll(new Uint8Array(readFileSync(path)));
  } catch (error) {
    if (error instanceof TkcError) return { accepted: false, rule: error.rule, kind: error.kind, message: error.message };
    const e = error instanceof Error ? error : new Error(String(error));
    return { crashed: true, name: e.name, message: e.message, stack: (e.stack || '').split('\n').slice(0, 6).join('\n') };
  }
}

const [list] = process.argv.slice(2);
for (const path of readFileSync(list, 'utf8').split('\n').filter(Boolean)) {
  process.stdout.write(JSON.stringify({ path, ...outcome(path) }) + '\n');
}
