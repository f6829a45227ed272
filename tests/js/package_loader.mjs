// node package_loader.mjs REQUEST.json: run by tests/test_npm_package.py from an empty project
// into which the packed npm package and three were installed (it is copied there, so that the
// bare specifiers resolve as a user's would). Prints one JSON object of what TKCLoader did, for
// the Python test to compare with the Python decoder:
//
// - parse: the animation of REQUEST.file (mesh, index, frame count and rate), and for each of
//   REQUEST.frames, setFrame(t)'s position attribute (base64 float32 little-endian), normals,
//   bounding box and sphere; how many frames were decoded, to show they are decoded on demand;
// - update: the frames update(seconds) shows, looping and not;
// - load: load and loadAsync over HTTP from a server on 127.0.0.1 (setPath, setRequestHeader), the
//   LoadingManager's events, and onError for a missing file, for REQUEST.damaged and for a file
//   whose fetch abort() stops.

import { readFileSync } from 'node:fs';
import { createServer } from 'node:http';
import { BufferGeometry, LoadingManager, Mesh } from 'three';
import { TKCAnimation, TKCLoader, TkcError } from 'tuckercodec/three';

// three's FileLoader reports download progress with ProgressEvent, which browsers have and node
// does not: the smallest stand-in
globalThis.ProgressEvent ??= class ProgressEvent extends Event {
  constructor(type, { lengthComputable = false, loaded = 0, total = 0 } = {}) {
    super(type);
    Object.assign(this, { lengthComputable, loaded, total });
  }
};

// a load whose callback or manager event never comes fails here, not at the test's timeout
setTimeout(() => {
  process.stderr.write('package_loader.mjs: timed out after 10 s (a callback or manager event never came)\n');
  process.exit(2);
}, 10000).unref();

const request = JSON.parse(readFileSync(process.argv[2], 'utf8'));
const bytes = readFileSync(request.file);

/** @param {ArrayLike<number>} values */
const base64 = (values) => Buffer.from(new Uint8Array(values.buffer, values.byteOffset, values.byteLength)).toString('base64');
const bufferOf = (data) => data.buffer.slice(data.byteOffset, data.byteOffset + data.byteLength);

function parsed() {
  let animation = null;
  new TKCLoader().parse(bufferOf(bytes), (a) => { animation = a; });
  if (!(animation instanceof TKCAnimation)) throw new Error('parse did not call onLoad before returning');
  let decoded = 0;
  const frameFloat32 = animation.file.frameFloat32.bind(animation.file);
  animation.file.frameFloat32 = (t, out) => { decoded += 1; return frameFloat32(t, out); };
  const geometry = animation.mesh.geometry;
  const frames = {};
  for (const t of request.frames) {
    animation.setFrame(t);
    const box = geometry.boundingBox;
    const sphere = geometry.boundingSphere;
    frames[t] = {
      frame: animation.frame,
      positions: base64(geometry.getAttribute('position').array),
      normals: base64(geometry.getAttribute('normal').array),
      box: [...box.min.toArray(), ...box.max.toArray()],
      sphere: [...sphere.center.toArray(), sphere.radius],
    };
  }
  const errors = [];
  for (const t of [-1, animation.frameCount, 0.5]) {
    try { animation.setFrame(t); errors.push(null); } catch (error) { errors.push(`${error.name}: ${error.message}`); }
  }
  const result = {
    isMesh: animation.mesh instanceof Mesh,
    isBufferGeometry: geometry instanceof BufferGeometry,
    frameCount: animation.frameCount,
    frameRate: animation.frameRate,
    vertices: geometry.getAttribute('position').count,
    index: base64(geometry.getIndex().array),
    indexType: geometry.getIndex().array.constructor.name,
    frames,
    decodedBySetFrame: decoded,
    setFrameErrors: errors,
  };
  animation.dispose();
  return result;
}

function updated() {
  let animation = null;
  new TKCLoader().parse(new Uint8Array(bytes), (a) => { animation = a; });
  const period = 1 / animation.frameRate;
  let decoded = 0;
  const frameFloat32 = animation.file.frameFloat32.bind(animation.file);
  animation.file.frameFloat32 = (t, out) => { decoded += 1; return frameFloat32(t, out); };
  const shown = [];
  // a quarter frame at a time over the first frames, then one whole pass, then back past 0
  for (let i = 0; i < 10; i++) shown.push(animation.update(period / 4).frame);
  const decodedByQuarters = decoded;
  shown.push(animation.update(animation.duration).frame);
  shown.push(animation.update(-3 * period).frame);
  animation.setFrame(1);
  const afterSetFrame = animation.update(period / 2).frame;
  animation.loop = false;
  const clamped = animation.update(10 * animation.duration).frame;
  // a file with time codes (format 1.4): the frames either side of each frame's start
  animation.loop = true;
  const aroundStarts = [];
  for (let f = 1; f < animation.frameCount; f++) {
    animation.setFrame(0);
    const justBefore = animation.update(animation.frameTimes[f] - 1e-9).frame;
    animation.setFrame(0);
    aroundStarts.push([justBefore, animation.update(animation.frameTimes[f]).frame]);
  }
  // a step back from 0 smaller than the pass's rounding stays within [0, duration)
  animation.setFrame(0);
  const tinyBack = [animation.update(-1e-300).frame, animation.time < animation.duration];
  // the smallest valid frame rate: frame times and the pass are infinite, the time never is
  let tiny = null;
  new TKCLoader().parse(new Uint8Array(bytes), (a) => { tiny = a; });
  tiny.frameRate = 5e-324;
  for (let f = 0; f < tiny.frameCount; f++) tiny.frameTimes[f] = f / tiny.frameRate;
  const tinyRate = [];
  for (const step of [-1, -1, 1, 1e308, 1e308, -1e308, 0.5]) {
    tiny.update(step);
    tinyRate.push([tiny.frame, Number.isFinite(tiny.time)]);
  }
  return {
    shown, decodedByQuarters, afterSetFrame, clamped, duration: animation.duration,
    frameTimes: Array.from(animation.frameTimes), aroundStarts, tinyBack, tinyRate,
  };
}

async function loaded() {
  const damaged = readFileSync(request.damaged);
  const seen = [];
  let slowAsked = () => {};
  const server = createServer((req, res) => {
    seen.push({ url: req.url, header: req.headers['x-tkc-test'] ?? null });
    if (req.url === '/models/slow.tkc') { // half the file, and the rest never
      res.writeHead(200, { 'Content-Type': 'application/octet-stream', 'Content-Length': bytes.length });
      res.write(bytes.subarray(0, bytes.length >> 1));
      slowAsked();
      return;
    }
    const body = req.url === '/models/anim.tkc' ? bytes : req.url === '/models/damaged.tkc' ? damaged : null;
    if (body === null) { res.writeHead(404); res.end(); return; }
    res.writeHead(200, { 'Content-Type': 'application/octet-stream', 'Content-Length': body.length });
    res.end(body);
  });
  await new Promise((resolve) => server.listen(0, '127.0.0.1', resolve));
  const origin = `http://127.0.0.1:${server.address().port}`;
  // the manager's events, each url without the origin: TKCLoader's item is the name asked for,
  // its FileLoader's the whole path
  const events = [];
  let idle = () => {};
  const manager = new LoadingManager(
    () => { events.push('onLoad'); idle(); },
    (url) => events.push(`onProgress ${url.replace(origin, '')}`),
    (url) => events.push(`onError ${url.replace(origin, '')}`),
  );
  manager.onStart = (url) => events.push(`onStart ${url.replace(origin, '')}`);
  const loader = new TKCLoader(manager).setPath(`${origin}/models/`).setRequestHeader({ 'X-Tkc-Test': 'sent' });
  /** load(name), until both its callback and the manager's onLoad have come: [outcome, events] */
  const step = async (name) => {
    const quiet = new Promise((resolve) => { idle = resolve; });
    const outcome = await new Promise((resolve) => {
      loader.load(name, (animation) => { events.push('animation'); resolve(animation); }, undefined, (error) => {
        events.push('error');
        resolve({ tkcError: error instanceof TkcError, name: error.name, rule: error.rule ?? null, message: String(error.message) });
      });
    });
    await quiet;
    return [outcome, events.splice(0)];
  };
  const result = {};
  try {
    const [first, loadEvents] = await step('anim.tkc');
    result.eventsOfLoad = loadEvents;
    const quiet = new Promise((resolve) => { idle = resolve; });
    const animation = await loader.loadAsync('anim.tkc');
    result.frame0 = base64(animation.mesh.geometry.getAttribute('position').array);
    result.sameAsLoad = result.frame0 === base64(first.mesh.geometry.getAttribute('position').array);
    result.frame = animation.frame;
    await quiet;
    events.splice(0);
    [result.missing, result.eventsOfMissing] = await step('missing.tkc');
    [result.damaged, result.eventsOfDamaged] = await step('damaged.tkc');
    // abort(): a fetch under way ends in onError
    const asked = new Promise((resolve) => { slowAsked = resolve; });
    const aborted = step('slow.tkc');
    await asked;
    loader.abort();
    [result.aborted, result.eventsOfAborted] = await aborted;
    result.requests = seen;
  } finally {
    server.closeAllConnections();
    server.close();
  }
  return result;
}

process.stdout.write(JSON.stringify({ parse: parsed(), update: updated(), load: await loaded() }));
