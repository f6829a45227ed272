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
import { observeVector } from './conformance_observe.mjs';

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
  });
}
