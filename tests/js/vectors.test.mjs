// `npm test` (node --test): the JavaScript decoder against every conformance vector of
// spec/vectors (spec/FORMAT.md §12), each a test of its own. A valid vector must decode to the
// header facts, names, segment index, SHA-256 digests and reconstruction its JSON gives; an
// invalid one must be refused with its rule and error class. What the decoder makes of a vector
// is observed by conformance_observe.mjs, which the pytest run (tests/test_js_conformance.py,
// tests/support/js_decoder.py) and the browser test use too; these are the same judgments.

import assert from 'node:assert/strict';
import { readFileSync, readdirSync } from 'node:fs';
import { dirname, join } from 'node:path';
import { test } from 'node:test';
import { fileURLToPath } from 'node:url';
import { observeVector, readNpyFloat64 } from './conformance_observe.mjs';
import { openTkc } from '../../tuckercodec/web/tkc/decoder.js';

const VECTORS = join(dirname(fileURLToPath(import.meta.url)), '..', '..', 'spec', 'vectors');
const names = readdirSync(VECTORS).filter((n) => n.endsWith('.json')).sort();

/** A vector's JSON and what the decoder makes of its file (and reference, for a valid one). */
async function observe(name) {
  const expected = JSON.parse(readFileSync(join(VECTORS, name), 'utf8'));
  const tkc = new Uint8Array(readFileSync(join(VECTORS, expected.file)));
  const npy = expected.valid ? new Uint8Array(readFileSync(join(VECTORS, expected.reference))) : null;
  return { expected, got: await observeVector(tkc, npy) };
}

/** A valid vector: everything its JSON gives, the positions within its tolerance (§8). */
function checkValid(expected, got) {
  assert.ok(got.accepted, got.message);
  for (const [key, value] of Object.entries(expected.header)) {
    assert.deepEqual(got.header[key], value, `header ${key}`);
  }
  assert.deepEqual(got.frame_names, expected.frame_names);
  assert.deepEqual(got.segments, expected.segments ?? []);
  assert.deepEqual(got.sha256, expected.sha256); // bit for bit (§6.3)
  assert.deepEqual(got.residual, expected.residual); // 1.3: the corrections' integers
  const reference = got.reference;
  const relative = expected.tolerance.relative_to_max_abs;
  if (relative === 0) {
    // a file with corrections: the same bits (§8.1)
    assert.ok(reference.identical, `positions differ by up to ${reference.max_abs_difference}`);
    return;
  }
  const tolerance = relative * reference.max_abs_reference;
  assert.ok(
    reference.max_abs_difference <= tolerance + 1e-12,
    `positions differ by ${reference.max_abs_difference}, more than ${tolerance}`,
  );
}

/**
 * Format 1.5's fields (§6.13): each one's description, every frame's values in modes grid and
 * exact by their SHA-256 (bit for bit), in mode tucker within the tolerance of its reference.
 * @param {{fields: object[]}} expected
 */
async function checkFields(expected) {
  const file = openTkc(new Uint8Array(readFileSync(join(VECTORS, expected.file))));
  assert.equal(file.fieldNames.length, expected.fields.length);
  for (const [n, entry] of expected.fields.entries()) {
    const { name, role, domain, components, type, mode } = entry;
    assert.deepEqual(file.fieldInfo(n), { name, role, domain, components, type, mode });
    const frames = Array.from({ length: file.frames }, (_, f) => file.field(n, f));
    const size = frames[0].length;
    const all = new (type === 'f32' ? Float32Array : Float64Array)(size * file.frames);
    frames.forEach((values, f) => all.set(values, f * size));
    assert.equal(all.length, entry.shape.reduce((a, b) => a * b));
    if (entry.reference === undefined) {
      const digest = await globalThis.crypto.subtle.digest('SHA-256', all); // little-endian hosts
      assert.equal(Buffer.from(digest).toString('hex'), entry.sha256, `field ${name}'s values`);
      continue;
    }
    const reference = readNpyFloat64(new Uint8Array(readFileSync(join(VECTORS, entry.reference)))).values;
    let largest = 0;
    let worst = 0;
    reference.forEach((value, j) => {
      largest = Math.max(largest, Math.abs(value));
      worst = Math.max(worst, Math.abs(all[j] - value));
    });
    const tolerance = entry.tolerance.relative_to_max_abs * largest + 1e-12;
    assert.ok(worst <= tolerance, `field ${name} differs by ${worst}, more than ${tolerance}`);
  }
}

/** An invalid vector: refused by a TkcError with its rule and error class. */
function checkInvalid(expected, got) {
  assert.ok(!got.accepted, `accepted a file that breaks ${expected.rule}`);
  assert.ok(!got.crashed, `threw something other than a TkcError: ${got.message}`);
  assert.deepEqual([got.rule, got.kind], [expected.rule, expected.error], got.message);
  assert.ok(got.message.endsWith(`[${expected.rule}]`), got.message);
}

test('spec/vectors holds the conformance vectors', () => {
  assert.ok(names.length >= 50, `only ${names.length} vectors in ${VECTORS}`);
});

for (const name of names) {
  test(name, async () => {
    const { expected, got } = await observe(name);
    if (expected.valid) checkValid(expected, got);
    else checkInvalid(expected, got);
    if (expected.fields) await checkFields(expected);
  });
}
