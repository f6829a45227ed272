// `npm test` (node --test): the function-size rule's check (tools/js/function_sizes.mjs, which
// .ci/run runs after tsc) counts what it says it counts, fails on a long function, and holds
// for our JavaScript. It parses with the TypeScript that tools/js pins: `npm ci` there first.

import assert from 'node:assert/strict';
import { spawnSync } from 'node:child_process';
import { existsSync, mkdtempSync, rmSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { dirname, join } from 'node:path';
import { after, before, test } from 'node:test';
import { fileURLToPath } from 'node:url';

const TOOLS = join(dirname(fileURLToPath(import.meta.url)), '..', '..', 'tools', 'js');
const SCRIPT = join(TOOLS, 'function_sizes.mjs');
const scratch = mkdtempSync(join(tmpdir(), 'function-sizes-test-'));
/** @type {typeof import('../../tools/js/function_sizes.mjs')} */
let sizes;

before(async () => {
  // a missing install would otherwise surface as an unexplained ERR_MODULE_NOT_FOUND
  assert.ok(
    existsSync(join(TOOLS, 'node_modules', 'typescript')),
    "the function-size check needs tools/js's packages: run 'npm ci' in tools/js",
  );
  sizes = await import(SCRIPT);
});

after(() => rmSync(scratch, { recursive: true, force: true }));

/** Writes a file of `source` in the scratch folder and returns its path. */
function write(name, source) {
  const path = join(scratch, name);
  writeFileSync(path, source);
  return path;
}

/** A function declaration `name` spanning exactly `lines` lines. */
function functionOf(name, lines) {
  const body = Array.from({ length: lines - 2 }, (_, i) => `  const v${i} = ${i};`);
  return [`function ${name}() {`, ...body, '}', ''].join('\n');
}

/** The command on `files`: its exit status and what it printed. */
function run(files) {
  const done = spawnSync(process.execPath, [SCRIPT, ...files], { encoding: 'utf8' });
  return { status: done.status, output: done.stdout + done.stderr };
}

test('a function counts from its first token to its last, its JSDoc excluded', () => {
  const file = write(
    'sample.js',
    [
      "import x from 'y';",
      '/**',
      ' * Doc.',
      ' */',
      'export function f() {',
      '  // a comment',
      '',
      '  return x;',
      '}',
      'class C {',
      '  /** doc */',
      '  async g() {',
      '    const h = () =>',
      '      2;',
      '    return h;',
      '  }',
      '}',
      'obj.prop = function () {',
      '  return { k: (a) => a };',
      '};',
      "test('t', async () => {});",
      '',
    ].join('\n'),
  );
  const found = sizes.functionSpans([file]).map((s) => [s.lines, s.where.split(':').pop()]);
  assert.deepEqual(found.sort(), [
    [1, '<arrow@21>'],
    [1, 'prop.k'],
    [2, 'C.g.h'],
    [3, 'prop'],
    [5, 'C.g'],
    [5, 'f'],
  ].sort());
});

test('a function of 130 lines fails the check, one of 120 passes', () => {
  const long = run([write('long.js', functionOf('tooLong', 130))]);
  assert.equal(long.status, 1, long.output);
  assert.match(long.output, /longer than 120 lines, split them: .*long\.js:tooLong \(130 lines\)/);
  const limit = run([write('limit.js', functionOf('atTheLimit', 120))]);
  assert.equal(limit.status, 0, limit.output);
});

test('three functions over 80 lines fail the check, two pass', () => {
  const two = functionOf('a', 81) + functionOf('b', 100);
  assert.equal(run([write('two.js', two)]).status, 0);
  const three = run([write('three.js', two + functionOf('c', 90))]);
  assert.equal(three.status, 1, three.output);
  assert.match(three.output, /3 functions longer than 80 lines, at most 2 may be/);
});

test('our JavaScript keeps the rule', () => {
  const spans = sizes.functionSpans(sizes.ourFiles());
  assert.ok(spans.length > 300, `only ${spans.length} functions found: are the files there?`);
  assert.deepEqual(sizes.violations(spans), []);
});
