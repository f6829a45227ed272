// The Khronos glTF-Validator on files the project wrote.
//
//   node validate.mjs FILE...
//
// Prints one JSON array on stdout, one entry per file, in order:
//   {"uri", "validatorVersion", "numErrors", "numWarnings", "numInfos", "numHints",
//    "messages": [{"code", "message", "pointer", "severity"}], "info": {...}}
// severity is the validator's number: 0 error, 1 warning, 2 information, 3 hint.
// A file the validator refuses outright (unreadable, neither glTF nor GLB) gets {"uri", "fatal"}.
// Exits 0 whatever the reports say: the Python side asserts on them. Exits 2 on bad arguments.
import { readFile } from 'node:fs/promises';
import path from 'node:path';
import validator from 'gltf-validator';

async function validateOne(file) {
	let bytes;
	try {
		bytes = await readFile(file);
	} catch (error) {
		return { uri: file, fatal: `cannot read: ${error.message}` };
	}
	const folder = path.dirname(file);
	try {
		const report = await validator.validateBytes(new Uint8Array(bytes), {
			uri: path.basename(file),
			maxIssues: 0, // every issue, not the first 100
			writeTimestamp: false,
			// a .gltf's external .bin (and any other relative resource) beside it
			externalResourceFunction: (uri) =>
				readFile(path.join(folder, decodeURIComponent(uri))).then(
					(data) => new Uint8Array(data),
					(error) => Promise.reject(error.message),
				),
		});
		const issues = report.issues;
		return {
			uri: file,
			validatorVersion: report.validatorVersion,
			numErrors: issues.numErrors,
			numWarnings: issues.numWarnings,
			numInfos: issues.numInfos,
			numHints: issues.numHints,
			messages: issues.messages.map(({ code, message, pointer, severity }) => ({
				code,
				message,
				pointer: pointer ?? null,
				severity,
			})),
			info: report.info ?? null,
		};
	} catch (error) {
		return { uri: file, fatal: String(error) };
	}
}

const files = process.argv.slice(2);
if (files.length === 0) {
	console.error('usage: node validate.mjs FILE...');
	process.exit(2);
}
const reports = [];
for (const file of files) reports.push(await validateOne(file));
process.stdout.write(JSON.stringify(reports) + '\n');
