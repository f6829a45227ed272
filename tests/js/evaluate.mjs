// three.js's GLTFLoader, in node, playing a glTF animation as a viewer would.
//
//   node evaluate.mjs FILE.glb|FILE.gltf --times T0,T1,... [--clip N] [--out POSITIONS.bin]
//   node evaluate.mjs FILE.glb --times - ...      (the times as a JSON array on stdin)
//
// Loads the file with GLTFLoader.parse (MeshoptDecoder registered, so EXT_meshopt_compression
// loads; KHR_mesh_quantization is native), plays animation clip N (default 0; none: the rest
// pose) through an AnimationMixer, and at each time t (seconds) evaluates every vertex of every
// mesh in world space exactly as three.js does on the CPU: mesh.getVertexPosition(i, v) (the
// morph target influences, normalized attributes de-normalized) then v.applyMatrix4(matrixWorld).
// Times past the clip's end hold its last value and times before 0 its first, as the glTF spec
// says (LoopOnce, clampWhenFinished).
//
// Prints one JSON object on stdout:
//   {"times": [...], "clip": {"index", "name", "duration"} | null, "warnings": [...],
//    "meshes": [{"name", "node", "mesh", "primitive", "vertexCount", "morphTargets",
//                "offset", "positions"?}]}
// node/mesh/primitive: the glTF indices three.js associates with the object (null if none).
// With --out, each mesh's positions are written there as float64 little endian, shape
// (len(times), vertexCount, 3), the meshes one after another, mesh["offset"] its first byte;
// without it, mesh["positions"] holds them as nested JSON lists. warnings: what three.js
// printed with console.warn or console.error while loading and playing (it warns rather than fails on much).
import { readFile, writeFile } from 'node:fs/promises';
import os from 'node:os';
import path from 'node:path';
import { AnimationMixer, Cache, LoaderUtils, LoopOnce, Vector3 } from 'three';
import { GLTFLoader } from 'three/examples/jsm/loaders/GLTFLoader.js';
import { MeshoptDecoder } from 'three/examples/jsm/libs/meshopt_decoder.module.js';

const warnings = [];
console.warn = console.error = (...args) => warnings.push(args.map(String).join(' '));

function usage(message) {
	process.stderr.write(`evaluate.mjs: ${message}\n`);
	process.stderr.write('usage: node evaluate.mjs FILE --times T0,T1,...|- [--clip N] [--out FILE]\n');
	process.exit(2);
}

function parseArgs(argv) {
	const args = { file: null, times: null, clip: 0, out: null };
	for (let i = 0; i < argv.length; i++) {
		const arg = argv[i];
		if (arg === '--times' || arg === '--clip' || arg === '--out') {
			if (i + 1 >= argv.length) usage(`${arg} needs a value`);
			args[arg.slice(2)] = argv[++i];
		} else if (args.file === null) {
			args.file = arg;
		} else {
			usage(`unexpected argument ${arg}`);
		}
	}
	if (args.file === null) usage('no file');
	if (args.times === null) usage('no --times');
	args.clip = Number(args.clip);
	if (!Number.isInteger(args.clip) || args.clip < 0) usage('--clip must be an index');
	return args;
}

async function readStdin() {
	const chunks = [];
	for await (const chunk of process.stdin) chunks.push(chunk);
	return Buffer.concat(chunks).toString('utf8');
}

async function parseTimes(text) {
	const times = text === '-' ? JSON.parse(await readStdin()) : text.split(',').map(Number);
	if (!Array.isArray(times) || times.length === 0 || !times.every(Number.isFinite)) {
		usage('the times must be a non-empty list of finite numbers');
	}
	return times;
}

// The JSON of a .gltf, or of a .glb's first chunk.
function documentOf(bytes, isGlb) {
	if (!isGlb) return JSON.parse(new TextDecoder().decode(bytes));
	const length = bytes.readUInt32LE(12);
	return JSON.parse(new TextDecoder().decode(bytes.subarray(20, 20 + length)));
}

// The buffers with a URI (a .gltf's .bin beside it, or a data: URI) are read here and handed to
// three's FileLoader through its cache: in node it would fetch() them, and node's fetch reads
// no file: URLs, and FileLoader's progress events need the browser's ProgressEvent.
async function cacheBuffers(file, document) {
	Cache.enabled = true;
	for (const buffer of document.buffers ?? []) {
		if (buffer.uri === undefined) continue;
		let data;
		if (buffer.uri.startsWith('data:')) {
			data = await (await fetch(buffer.uri)).arrayBuffer();
		} else {
			const bytes = await readFile(path.join(path.dirname(file), decodeURIComponent(buffer.uri)));
			data = bytes.buffer.slice(bytes.byteOffset, bytes.byteOffset + bytes.byteLength);
		}
		Cache.add(`file:${LoaderUtils.resolveURL(buffer.uri, '')}`, data);
	}
}

async function load(file) {
	const bytes = await readFile(file);
	const isGlb = bytes.length >= 20 && bytes.toString('latin1', 0, 4) === 'glTF';
	await cacheBuffers(file, documentOf(bytes, isGlb));
	const data = isGlb
		? bytes.buffer.slice(bytes.byteOffset, bytes.byteOffset + bytes.byteLength)
		: new TextDecoder().decode(bytes);
	const loader = new GLTFLoader();
	loader.setMeshoptDecoder(MeshoptDecoder);
	await MeshoptDecoder.ready;
	return loader.parseAsync(data, '');
}

function association(parser, object, key) {
	const entry = parser.associations.get(object);
	return entry && entry[key] !== undefined ? entry[key] : null;
}

// The glTF node a three.js mesh came from: itself, or (a primitive of a multi-primitive
// mesh, or a mesh under a node that also has children) its nearest ancestor that is a node.
function nodeIndex(parser, object) {
	for (let o = object; o; o = o.parent) {
		const node = association(parser, o, 'nodes');
		if (node !== null) return node;
	}
	return null;
}

async function main() {
	const args = parseArgs(process.argv.slice(2));
	const times = await parseTimes(args.times);
	const gltf = await load(args.file);
	const scene = gltf.scene;

	const meshes = [];
	scene.traverse((object) => {
		if (object.isMesh) meshes.push(object);
	});

	let clip = null;
	let action = null;
	const mixer = new AnimationMixer(scene);
	if (gltf.animations.length > args.clip) {
		clip = gltf.animations[args.clip];
		action = mixer.clipAction(clip);
		action.setLoop(LoopOnce, 1);
		action.clampWhenFinished = true;
	} else if (args.clip !== 0) {
		usage(`no animation clip ${args.clip}: the file has ${gltf.animations.length}`);
	}

	const counts = meshes.map((mesh) => mesh.geometry.attributes.position.count);
	const out = counts.map((count) => new Float64Array(times.length * count * 3));
	const v = new Vector3();
	times.forEach((t, ti) => {
		if (action !== null) {
			// reset: a LoopOnce action that reached its end is paused and would stay there
			action.reset();
			action.play();
			mixer.setTime(t);
		}
		scene.updateMatrixWorld(true);
		meshes.forEach((mesh, mi) => {
			const target = out[mi];
			const count = counts[mi];
			let k = ti * count * 3;
			for (let i = 0; i < count; i++) {
				mesh.getVertexPosition(i, v);
				v.applyMatrix4(mesh.matrixWorld);
				target[k++] = v.x;
				target[k++] = v.y;
				target[k++] = v.z;
			}
		});
	});

	const parser = gltf.parser;
	let offset = 0;
	const report = {
		times,
		clip: clip === null ? null : { index: args.clip, name: clip.name, duration: clip.duration },
		warnings,
		meshes: meshes.map((mesh, mi) => {
			const entry = {
				name: mesh.name,
				node: nodeIndex(parser, mesh),
				mesh: association(parser, mesh, 'meshes'),
				primitive: association(parser, mesh, 'primitives'),
				vertexCount: counts[mi],
				morphTargets: (mesh.geometry.morphAttributes.position ?? []).length,
				offset,
			};
			offset += out[mi].byteLength;
			if (args.out === null) {
				entry.positions = times.map((_, ti) => {
					const frame = [];
					for (let i = 0; i < counts[mi]; i++) {
						const k = (ti * counts[mi] + i) * 3;
						frame.push([out[mi][k], out[mi][k + 1], out[mi][k + 2]]);
					}
					return frame;
				});
			}
			return entry;
		}),
	};
	if (args.out !== null) {
		if (os.endianness() !== 'LE') throw new Error('the --out layout is little endian only');
		await writeFile(args.out, Buffer.concat(out.map((a) => Buffer.from(a.buffer))));
	}
	process.stdout.write(JSON.stringify(report) + '\n');
}

main().catch((error) => {
	process.stderr.write(`evaluate.mjs: ${error && error.stack ? error.stack : error}\n`);
	if (warnings.length) process.stderr.write(`three.js said: ${warnings.join(' | ')}\n`);
	process.exit(1);
});
