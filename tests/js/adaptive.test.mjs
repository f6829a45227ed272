// `npm test` (node --test): adaptive.js (spec/FORMAT.md §6.14) against the reference coder, on
// the streams of adaptive_fixture.json (written by tools/generate/adaptive_fixture.py from
// tuckercodec/format/adaptive.py): every stream decodes to the reference's integers, or is
// refused with R46 where the reference refuses it; U1's coding order (meshCodingOrder) is the
// reference's on the fixture's mesh; and a section declaring far more integers than its bytes can
// hold is refused before anything of their size is made. The streams of 5 to 8 planes (`wide`,
// 64-bit integers: a RESD chunk's, format 1.7) go through decodeAdaptiveWide, which must also
// make of every 32-bit stream in the ascending order what decodeAdaptive makes of it. The
// `uniform` cases are uniform streams (§6.8, format 1.9: faces-traverse's places with `ranks` 1),
// which decodeUniform must read to the reference's places or refuse where it refuses them.

import assert from 'node:assert/strict';
import { readFileSync } from 'node:fs';
import { dirname, join } from 'node:path';
import { test } from 'node:test';
import { fileURLToPath } from 'node:url';
import { decodeAdaptive, decodeAdaptiveWide, decodeUniform } from '../../tuckercodec/web/tkc/adaptive.js';
import { TkcError } from '../../tuckercodec/web/tkc/errors.js';
import { meshCodingOrder, meshTopology } from '../../tuckercodec/web/tkc/topology.js';

const HERE = dirname(fileURLToPath(import.meta.url));
const { cases } = JSON.parse(readFileSync(join(HERE, 'adaptive_fixture.json'), 'utf8'));
const mesh = cases.find((c) => c.topology !== undefined).topology;

/** The fixture mesh's coding order, as the decoder makes it from the faces. */
function fixtureOrder() {
  const faces = Int32Array.from(mesh.faces);
  const K = Math.max(...mesh.order) + 1;
  return meshCodingOrder(meshTopology(faces, mesh.face_count, mesh.face_width, K));
}

/**
 * What the decoder makes of a case: its integers, or the rule it throws. A wide case's (or with
 * `wide`, any case's) through decodeAdaptiveWide, its integers as decimal strings for a wide case.
 */
function observe(c, wide = c.wide === true) {
  const payload = new Uint8Array(Buffer.from(c.payload, 'base64'));
  const order = c.mesh ? () => fixtureOrder() : null;
  try {
    if (c.uniform) return { integers: Array.from(decodeUniform(payload, c.count, c.total, `case ${c.name}`)) };
    if (!wide) return { integers: Array.from(decodeAdaptive(payload, c.rows, c.cols, order, c.planes, `case ${c.name}`)) };
    const halves = decodeAdaptiveWide(payload, c.rows, c.cols, c.planes, `case ${c.name}`);
    const values = Array.from(new BigInt64Array(halves.buffer)); // little-endian hosts
    return { integers: c.wide ? values.map(String) : values.map(Number) };
  } catch (error) {
    if (!(error instanceof TkcError)) throw error;
    assert.equal(error.kind, 'FormatError');
    return { rule: error.rule };
  }
}

test('the fixture covers every way a stream is refused, and damaged streams both ways', () => {
  const names = new Set(cases.map((c) => c.name));
  for (const name of ['sequence-cut', 'sequence-byte-after', 'sequence-bad-ending', 'sequence-first-byte', 'sequence-short', 'sequence-too-many', 'bound-positive', 'bound-negative', 'bound-long']) {
    assert.ok(names.has(name), name);
  }
  const damaged = cases.filter((c) => c.name.includes('damaged'));
  assert.ok(damaged.some((c) => c.rule) && damaged.some((c) => c.integers), 'damaged streams refused and accepted');
});

for (const c of cases) {
  test(`${c.name}: ${c.rule ?? `${c.integers.length} integers`}`, () => {
    const got = observe(c);
    if (c.rule !== undefined) assert.deepEqual(got, { rule: c.rule });
    else assert.deepEqual(got, { integers: c.integers });
  });
}

test('decodeAdaptiveWide makes of every 32-bit stream in the ascending order what the reference makes', () => {
  const narrow = cases.filter((c) => !c.mesh && !c.wide && !c.uniform);
  assert.ok(narrow.length > 20 && narrow.some((c) => c.rule) && narrow.some((c) => c.integers));
  for (const c of narrow) {
    const got = observe(c, true);
    assert.deepEqual(got, c.rule !== undefined ? { rule: c.rule } : { integers: c.integers }, c.name);
  }
});

test('the uniform cases reach 2^31 − 1 and every refusal of a uniform stream', () => {
  const uniform = cases.filter((c) => c.uniform);
  const largest = uniform.flatMap((c) => c.integers ?? []).reduce((a, v) => Math.max(a, v), 0);
  assert.equal(largest, 2 ** 31 - 1);
  for (const name of ['uniform-cut', 'uniform-byte-after', 'uniform-first-byte', 'uniform-short', 'uniform-bad-ending', 'uniform-too-many']) {
    assert.equal(uniform.find((c) => c.name === name)?.rule, 'R46-adaptive-stream', name);
  }
  const damaged = uniform.filter((c) => c.name.includes('damaged'));
  assert.ok(damaged.some((c) => c.rule) && damaged.some((c) => c.integers), 'damaged uniform streams refused and accepted');
});

test('the wide cases reach 63 bits and every refusal of a wide stream', () => {
  const wide = cases.filter((c) => c.wide);
  const largest = wide.flatMap((c) => c.integers ?? []).reduce((a, v) => (BigInt(v) > a ? BigInt(v) : a), 0n);
  assert.equal(largest, 2n ** 63n - 1n);
  for (const name of ['wide-bound-positive-5', 'wide-bound-negative-5', 'wide-64-bits']) {
    assert.equal(wide.find((c) => c.name === name)?.rule, 'R46-adaptive-stream', name);
  }
  const damaged = wide.filter((c) => c.name.includes('damaged'));
  assert.ok(damaged.some((c) => c.rule) && damaged.some((c) => c.integers), 'damaged wide streams refused and accepted');
});

test("U1's coding order is the reference's: depth 0 ascending, then predictor 2's rows and sources", () => {
  const { order, ends, source } = fixtureOrder();
  assert.deepEqual(Array.from(order), mesh.order);
  assert.deepEqual(Array.from(ends), mesh.ends);
  // each row's sources as a set: only their magnitudes' sum is used
  for (let j = 0; j < order.length; j++) {
    const ours = Array.from(source.subarray(ends[j], ends[j + 1])).sort((a, b) => a - b);
    const theirs = mesh.sources.slice(mesh.ends[j], mesh.ends[j + 1]).sort((a, b) => a - b);
    assert.deepEqual(ours, theirs, `row ${order[j]}`);
  }
});

test('a section of 2^36 integers in 5 bytes is refused before they are made', () => {
  const payload = new Uint8Array([0, 0, 0, 0, 0]);
  assert.throws(
    () => decodeAdaptive(payload, 2 ** 26, 2 ** 10, () => assert.fail('no order is made'), 4, "section 'U1'"),
    (error) => error instanceof TkcError && error.rule === 'R46-adaptive-stream' && /cannot come from 5 bytes/.test(error.message),
  );
});
