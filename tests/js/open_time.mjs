// node open_time.mjs [--runs N] FILE...: how long the JavaScript decoder takes to open each file
// (openTkc: the container, the faces, every factor of a file that is not segmented), a
// measurement, not a test. The files are opened in turn, N rounds (default 15), so that a busy
// machine slows them alike; the first round is the coldest (nothing compiled yet). Prints one
// JSON line per file: {path, bytes, first_ms, median_ms, min_ms, cpu_median_ms}, the CPU time
// being this process's (user + system) over the open, less sensitive than the wall time to
// other processes on the machine.
//
// Used to compare format 1.6's adaptive coding (§6.14) with §6.1's zstd planes on the same
// sequence: tests/support/adaptive_files.py makes the adaptive copy of a file.

import { readFileSync } from 'node:fs';
import { openTkc } from '../../tuckercodec/web/tkc/decoder.js';

const args = process.argv.slice(2);
const at = args.indexOf('--runs');
const runs = at >= 0 ? Number(args.splice(at, 2)[1]) : 15;
const files = args.map((path) => ({ path, bytes: new Uint8Array(readFileSync(path)), wall: [], cpu: [] }));
for (let r = 0; r < runs; r++) {
  for (const file of files) {
    const cpu = process.cpuUsage();
    const started = performance.now();
    openTkc(file.bytes);
    file.wall.push(performance.now() - started);
    const used = process.cpuUsage(cpu);
    file.cpu.push((used.user + used.system) / 1000);
  }
}
const median = (values) => [...values].sort((a, b) => a - b)[values.length >> 1];
for (const { path, bytes, wall, cpu } of files) {
  const round = (ms) => Math.round(ms * 10) / 10;
  process.stdout.write(`${JSON.stringify({
    path, bytes: bytes.length, first_ms: round(wall[0]), median_ms: round(median(wall)),
    min_ms: round(Math.min(...wall)), cpu_median_ms: round(median(cpu)),
  })}\n`);
}
