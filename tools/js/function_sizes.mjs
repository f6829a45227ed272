// node function_sizes.mjs [FILE...]: the function-size rule of tests/test_layout.py, for our
// JavaScript. No function over FUNCTION_LINES (120) lines, and at most LONG_FUNCTIONS_ALLOWED (2)
// over LONG_FUNCTION_LINES (80): what a reader must hold at once is a function, not a module.
// Without arguments it checks every file we wrote (ourFiles: tuckercodec/web's tkc/, three/ and
// viewer/, this folder's scripts and tests/js's, never the vendored web/vendor); with arguments,
// those files alone. It prints every violation and exits 1 on any; .ci/run runs it after tsc.
//
// Files are parsed by the TypeScript compiler that package.json pins. TypeScript 7 parses in its
// native tsgo process, which its API drives: one short-lived project over the files (a tsconfig
// in a temporary folder, imports not followed), and the syntax trees read back from it.

import { mkdtempSync, readdirSync, rmSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { dirname, join, relative, resolve } from 'node:path';
import { fileURLToPath } from 'node:url';
import { SyntaxKind, skipTrivia } from 'typescript/unstable/ast';
import { API } from 'typescript/unstable/sync';

export const FUNCTION_LINES = 120;
export const LONG_FUNCTION_LINES = 80;
export const LONG_FUNCTIONS_ALLOWED = 2;

const HERE = dirname(fileURLToPath(import.meta.url));
const ROOT = resolve(HERE, '..', '..');

/** The node kinds that are functions: declarations, expressions, arrows, methods, accessors. */
const FUNCTION_KINDS = new Set([
  SyntaxKind.FunctionDeclaration,
  SyntaxKind.FunctionExpression,
  SyntaxKind.ArrowFunction,
  SyntaxKind.MethodDeclaration,
  SyntaxKind.Constructor,
  SyntaxKind.GetAccessor,
  SyntaxKind.SetAccessor,
]);

/**
 * Every JavaScript file of ours the rule applies to, as absolute paths, sorted. tools/js/web
 * holds links to the same folders (tsc's view of them) and is not read twice.
 * @returns {string[]}
 */
export function ourFiles() {
  const folders = [
    ['tuckercodec/web/tkc', /\.js$/],
    ['tuckercodec/web/three', /\.js$/],
    ['tuckercodec/web/viewer', /\.js$/],
    ['tools/js', /\.m?js$/],
    ['tests/js', /\.m?js$/],
  ];
  const files = [];
  for (const [folder, pattern] of folders) {
    for (const name of readdirSync(join(ROOT, folder)).sort()) {
      if (pattern.test(name)) files.push(join(ROOT, folder, name));
    }
  }
  return files;
}

/**
 * A name for a function: its own, or that of what it is given to (a variable, a property, an
 * assignment's target), or `<arrow>`/`<function>` with its line when it has none.
 * @param {any} node
 * @param {number} line
 * @returns {string}
 */
function functionName(node, line) {
  if (node.kind === SyntaxKind.Constructor) return 'constructor';
  const named = node.name ?? namedBy(node.parent);
  if (named && named.text !== undefined) return named.text;
  return `<${node.kind === SyntaxKind.ArrowFunction ? 'arrow' : 'function'}@${line}>`;
}

/** The name node of the declaration, property or assignment that holds a function, if any. */
function namedBy(parent) {
  if (!parent) return undefined;
  switch (parent.kind) {
    case SyntaxKind.VariableDeclaration:
    case SyntaxKind.PropertyAssignment:
    case SyntaxKind.PropertyDeclaration:
      return parent.name;
    case SyntaxKind.BinaryExpression: // x.y = function () {...}: named y
      return parent.left.name ?? parent.left;
    default:
      return undefined;
  }
}

/**
 * The line number (1-based) of a position in a text.
 * @param {number[]} lineStarts the position where each line begins
 * @param {number} position
 */
function lineOf(lineStarts, position) {
  let low = 0;
  let high = lineStarts.length - 1;
  while (low < high) {
    const middle = (low + high + 1) >> 1;
    if (lineStarts[middle] <= position) low = middle;
    else high = middle - 1;
  }
  return low + 1;
}

/**
 * The line span of every function in one parsed file, nested ones included (each counted alone
 * and inside the function around it). A function's lines run from its first token (`function`,
 * `async`, a method's name, an arrow's parameters) to its last (the body's `}`, or an arrow's
 * expression): the JSDoc above it is not counted, as a Python function's decorators are not,
 * while the comments, blank lines and nested functions inside it are.
 * @param {any} sourceFile the TypeScript syntax tree
 * @param {string} file the name to report it by
 * @returns {{lines: number, where: string, start: number, end: number}[]}
 */
export function spansOf(sourceFile, file) {
  const text = sourceFile.text;
  const lineStarts = [0];
  for (let i = 0; i < text.length; i++) if (text.charCodeAt(i) === 10) lineStarts.push(i + 1);
  const spans = [];
  const scope = [];
  const visit = (node) => {
    let entered = false;
    if (FUNCTION_KINDS.has(node.kind)) {
      const start = lineOf(lineStarts, skipTrivia(text, node.pos));
      const end = lineOf(lineStarts, node.end - 1);
      scope.push(functionName(node, start));
      spans.push({ lines: end - start + 1, where: `${file}:${scope.join('.')}`, start, end });
      entered = true;
    } else if (node.kind === SyntaxKind.ClassDeclaration || node.kind === SyntaxKind.ClassExpression) {
      scope.push(node.name?.text ?? '<class>');
      entered = true;
    }
    node.forEachChild(visit);
    if (entered) scope.pop();
  };
  visit(sourceFile);
  return spans;
}

/**
 * Parses the files with TypeScript and returns every function's span (spansOf), in file order.
 * @param {string[]} files paths
 * @returns {{lines: number, where: string, start: number, end: number}[]}
 */
export function functionSpans(files) {
  const absolute = files.map((f) => resolve(f));
  const folder = mkdtempSync(join(tmpdir(), 'function-sizes-'));
  const config = join(folder, 'tsconfig.json');
  // a project of these files alone: JavaScript allowed, imports and libraries not read
  const compilerOptions = { allowJs: true, noEmit: true, noResolve: true, noLib: true, types: [] };
  writeFileSync(config, JSON.stringify({ compilerOptions, files: absolute }));
  const api = new API({ cwd: folder });
  try {
    const project = api.updateSnapshot({ openProjects: [config] }).getProject(config);
    if (!project) throw new Error('TypeScript opened no project over the files');
    const spans = [];
    for (const path of absolute) {
      const sourceFile = project.program.getSourceFile(path);
      if (!sourceFile) throw new Error(`TypeScript did not parse ${path}`);
      const shown = path.startsWith(ROOT + '/') ? relative(ROOT, path) : path;
      spans.push(...spansOf(sourceFile, shown));
    }
    return spans;
  } finally {
    api.close();
    rmSync(folder, { recursive: true, force: true });
  }
}

/**
 * What breaks the rule: every function over FUNCTION_LINES, and the functions over
 * LONG_FUNCTION_LINES when there are more than LONG_FUNCTIONS_ALLOWED of them. Empty if none.
 * @param {{lines: number, where: string}[]} spans
 * @returns {string[]}
 */
export function violations(spans) {
  const listed = [...spans].sort((a, b) => b.lines - a.lines);
  const shown = (s) => `${s.where} (${s.lines} lines)`;
  const problems = [];
  const overCap = listed.filter((s) => s.lines > FUNCTION_LINES);
  if (overCap.length > 0) {
    problems.push(`functions longer than ${FUNCTION_LINES} lines, split them: ${overCap.map(shown).join(', ')}`);
  }
  const long = listed.filter((s) => s.lines > LONG_FUNCTION_LINES);
  if (long.length > LONG_FUNCTIONS_ALLOWED) {
    problems.push(
      `${long.length} functions longer than ${LONG_FUNCTION_LINES} lines, at most ` +
        `${LONG_FUNCTIONS_ALLOWED} may be: ${long.map(shown).join(', ')}`,
    );
  }
  return problems;
}

/** The command: check the files named, or ours; print the longest and any violation. */
function main(args) {
  const files = args.length > 0 ? args : ourFiles();
  const spans = functionSpans(files);
  const problems = violations(spans);
  const longest = [...spans].sort((a, b) => b.lines - a.lines).slice(0, 3);
  console.log(
    `function sizes: ${spans.length} functions in ${files.length} files; the longest: ` +
      longest.map((s) => `${s.where} (${s.lines})`).join(', '),
  );
  for (const problem of problems) console.error(`error: ${problem}`);
  return problems.length > 0 ? 1 : 0;
}

if (process.argv[1] && resolve(process.argv[1]) === fileURLToPath(import.meta.url)) {
  process.exitCode = main(process.argv.slice(2));
}
