// node --expose-gc --import ./three_from_vendor.mjs memory.mjs JOB.json: what a file costs the
// JavaScript decoder, or TKCLoader, in time and memory. Run by tests/test_js_memory.py, one
// job a process (so that the process's peak resident memory is the job's).
//
// JOB: {path, via: "decoder" | "loader", options?, frames: "first" | "every", loops?}.
// "decoder" opens the file with openTkc(bytes, options); "loader" parses it with a TKCLoader
// given setDecoderOptions(options) when there are options. Then frame 0 alone ("first"), or
// every frame in order, `loops` times over ("every"), as a looping page plays them.
// Prints {accepted, rule?, message?, seconds, maxRssMiB, retained: [after frame 0, then after
// each loop: MiB of buffers and heap after full collections], segmentsKept}.

import { readFileSync } from 'node:fs';
import { openTkc, TkcError } from '../../tuckercodec/web/tkc/decoder.js';

const job = JSON.parse(readFileSync(process.argv[2], 'utf8'));
const bytes = new Uint8Array(readFileSync(job.path));
const MiB = 2 ** 20;

/**
 * The process's peak resident memory in MiB: Linux's VmHWM, which starts afresh at exec (the
 * maxRSS of getrusage is carried over from the parent, a Python test that may have built a large
 * file), else maxRSS.
 */
function peakResident() {
  try {
    const line = readFileSync('/proc/self/status', 'utf8').match(/^VmHWM:\s+(\d+) kB/m);
    if (line) return Number(line[1]) / 1024;
  } catch {
    // not Linux
  }
  return process.resourceUsage().maxRSS / 1024;
}

/**
 * Memory outside the heap (ArrayBuffers and WebAssembly memories: `external`) and the heap in use
 * after full collections, in MiB. Buffers are freed on another thread after a collection: a few
 * collections a few milliseconds apart let them go.
 */
async function retained() {
  for (let i = 0; i < 3; i++) {
    globalThis.gc?.();
    await new Promise((resolve) => setTimeout(resolve, 20));
  }
  const usage = process.memoryUsage();
  return (usage.external + usage.heapUsed) / MiB;
}

async function open() {
  if (job.via === 'loader') {
    const { TKCLoader } = await import('../../tuckercodec/web/three/TKCLoader.js');
    const loader = new TKCLoader();
    if (job.options) loader.setDecoderOptions(job.options);
    const animation = await loader.parseAsync(bytes);
    return { file: animation.file, show: (/** @type {number} */ t) => animation.setFrame(t) };
  }
  const file = openTkc(bytes, job.options ?? {});
  const out = new Float32Array(3 * file.vertices);
  return { file, show: (/** @type {number} */ t) => file.frameFloat32(t, out) };
}

const began = performance.now();
const result = { accepted: true, retained: [], segmentsKept: null };
try {
  const { file, show } = await open();
  show(0);
  result.retained.push(await retained());
  if (job.frames === 'first') {
    show(0);
  } else {
    for (let loop = 0; loop < (job.loops ?? 1); loop++) {
      for (let t = 0; t < file.frames; t++) show(t);
      result.retained.push(await retained());
    }
  }
  result.segmentsKept = file._decoded.size ?? file._decoded.filter((d) => d !== null).length;
} catch (error) {
  if (!(error instanceof TkcError)) throw error;
  Object.assign(result, { accepted: false, rule: error.rule, message: String(error.message) });
}
result.seconds = (performance.now() - began) / 1000;
result.maxRssMiB = peakResident();
process.stdout.write(JSON.stringify(result));
