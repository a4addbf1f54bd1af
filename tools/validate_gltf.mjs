#!/usr/bin/env node
// Run the Khronos glTF-Validator (npm package gltf-validator, pinned in
// tools/package.json) on one or more .glb/.gltf files.
//
//   node tools/validate_gltf.mjs FILE... [--json]
//
// Text mode prints, per file:
//   FILE: N errors, N warnings, N infos, N hints
//     error CODE /json/pointer: message
//     warning CODE /json/pointer: message
// (infos and hints are counted but only listed with --all).
//
// --json prints one JSON object per file, one per line:
//   {"file":..., "errors":N, "warnings":N, "infos":N, "hints":N,
//    "messages":[{"code","severity","pointer","message"}], ...}
// severity is "error" | "warning" | "info" | "hint"; pointer is the JSON
// pointer, or null for byte-level GLB issues (then "offset" is the byte offset).
//
// External resources (.bin, images) are read relative to the file's folder.
//
// Exit status: 0 when every file has 0 errors and 0 warnings, 1 when any file
// has an error or a warning, 2 on a usage error or when a file can't be
// read (the file itself, or an external .bin/image it refers to: the
// validator's IO_ERROR); 2 wins over 1. Files that are not glTF at all (bad
// JSON, broken GLB header) are validator errors, so they give 1.

import { readFile } from 'node:fs/promises';
import path from 'node:path';
import process from 'node:process';

const USAGE = `usage: node tools/validate_gltf.mjs [--json] [--all] FILE...
  --json   one JSON object per file on stdout (JSON Lines)
  --all    in text mode, also list info and hint messages
exit: 0 = no errors and no warnings, 1 = errors or warnings, 2 = usage/IO error`;

const SEVERITY = ['error', 'warning', 'info', 'hint'];

function usage(msg) {
  if (msg) process.stderr.write(`validate_gltf: ${msg}\n`);
  process.stderr.write(`${USAGE}\n`);
  process.exit(2);
}

let json = false;
let all = false;
const files = [];
let onlyFiles = false;
for (const arg of process.argv.slice(2)) {
  if (onlyFiles) files.push(arg);
  else if (arg === '--') onlyFiles = true;
  else if (arg === '--json') json = true;
  else if (arg === '--all') all = true;
  else if (arg === '-h' || arg === '--help') {
    process.stdout.write(`${USAGE}\n`);
    process.exit(0);
  } else if (arg.startsWith('-') && arg !== '-') usage(`unknown option ${arg}`);
  else files.push(arg);
}
if (files.length === 0) usage('no input files');

let validator;
try {
  // tools/node_modules is resolved relative to this script, whatever the cwd.
  const mod = await import('gltf-validator');
  validator = mod.default ?? mod;
} catch (e) {
  process.stderr.write(
    `validate_gltf: cannot load the npm package gltf-validator (${e.message}).\n` +
      'Run `bash tools/setup.sh` first (it runs `npm ci` in tools/).\n',
  );
  process.exit(2);
}

function formatFromName(file) {
  const ext = path.extname(file).toLowerCase();
  if (ext === '.glb' || ext === '.vrm') return 'glb';
  if (ext === '.gltf') return 'gltf';
  return undefined; // let the validator sniff the first byte
}

async function validateOne(file) {
  const full = path.resolve(file);
  const data = await readFile(full); // throws on IO error: handled by caller
  const dir = path.dirname(full);
  const report = await validator.validateBytes(new Uint8Array(data), {
    uri: path.basename(full),
    format: formatFromName(full),
    maxIssues: 0, // unlimited
    writeTimestamp: false,
    externalResourceFunction: (uri) =>
      readFile(path.resolve(dir, decodeURIComponent(uri))).then(
        (buf) => new Uint8Array(buf),
        (err) => Promise.reject(err.message ?? String(err)),
      ),
  });
  return report;
}

function summarize(file, report) {
  const issues = report.issues ?? {};
  const messages = (issues.messages ?? []).map((m) => {
    const out = {
      code: m.code,
      severity: SEVERITY[m.severity] ?? String(m.severity),
      pointer: m.pointer ?? null,
      message: m.message,
    };
    if (m.offset !== undefined) out.offset = m.offset;
    return out;
  });
  return {
    file,
    errors: issues.numErrors ?? 0,
    warnings: issues.numWarnings ?? 0,
    infos: issues.numInfos ?? 0,
    hints: issues.numHints ?? 0,
    truncated: Boolean(issues.truncated),
    validator: report.validatorVersion ?? null,
    messages,
  };
}

let worst = 0;
for (const file of files) {
  let report;
  try {
    report = await validateOne(file);
  } catch (e) {
    const msg = e instanceof Error ? e.message : String(e);
    worst = 2;
    if (json) process.stdout.write(`${JSON.stringify({ file, error: msg })}\n`);
    process.stderr.write(`${file}: cannot validate: ${msg}\n`);
    continue;
  }
  const s = summarize(file, report);
  if (s.errors > 0 || s.warnings > 0) worst = Math.max(worst, 1);
  // A .bin/image the asset refers to could not be read: the file was not fully
  // validated, which is an IO error (exit 2), not just an invalid asset.
  if (s.messages.some((m) => m.code === 'IO_ERROR')) worst = 2;
  if (json) {
    process.stdout.write(`${JSON.stringify(s)}\n`);
    continue;
  }
  const lines = [
    // Fixed wording (always plural) so scripts can match it with one regex.
    `${file}: ${s.errors} errors, ${s.warnings} warnings, ${s.infos} infos, ${s.hints} hints`,
  ];
  for (const m of s.messages) {
    if (!all && m.severity !== 'error' && m.severity !== 'warning') continue;
    let where = m.pointer ?? (m.offset !== undefined ? `@byte ${m.offset}` : '-');
    if (where === '') where = '(document)'; // JSON pointer "" = whole document
    lines.push(`  ${m.severity} ${m.code} ${where}: ${m.message}`);
  }
  if (s.truncated) lines.push('  (validator truncated the message list)');
  process.stdout.write(`${lines.join('\n')}\n`);
}
process.exit(worst);
