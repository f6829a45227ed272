// node outcomes.mjs FILE...: for each .tkc, what the JavaScript decoder says of the whole file
// (opened, every segment checked, every frame reconstructed): "ok", or the error's kind and
// rule; anything but a TkcError is reported as a crash. Prints a JSON array in argument order.
// Run by tests/test_js_decoder.py to compare with the Python decoder on damaged files.

import { readFileSync } from 'node:fs';
import { openTkc, TkcError } from '../../tuckercodec/web/tkc/decoder.js';

const results = process.argv.slice(2).map((path) => {
  try {
    const file = openTkc(new Uint8Array(readFileSync(path))).check();
    const out = new Float64Array(3 * file.vertices);
    for (let t = 0; t < file.frames; t++) file.frame(t, out);
    return { accepted: true };
  } catch (error) {
    if (error instanceof TkcError) return { accepted: false, rule: error.rule, kind: error.kind, message: error.message };
    return { accepted: false, crashed: true, message: `${error && error.name}: ${error && error.message}` };
  }
});
process.stdout.write(JSON.stringify(results));
