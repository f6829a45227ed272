// node conformance.mjs VECTOR_DIR: prints, as one JSON object keyed by file name, what the
// JavaScript decoder makes of every vector (conformance_observe.mjs). Run by
// tests/test_js_conformance.py, which compares it with the vectors' JSON.

import { readFileSync, readdirSync } from 'node:fs';
import { join } from 'node:path';
import { observeVector } from './conformance_observe.mjs';

const folder = process.argv[2];
const results = {};
for (const name of readdirSync(folder).filter((n) => n.endsWith('.json')).sort()) {
  const expected = JSON.parse(readFileSync(join(folder, name), 'utf8'));
  const tkc = new Uint8Array(readFileSync(join(folder, expected.file)));
  const npy = expected.valid ? new Uint8Array(readFileSync(join(folder, expected.reference))) : null;
  results[name] = await observeVector(tkc, npy);
}
process.stdout.write(JSON.stringify(results));
