#!/usr/bin/env node
// What three.js's own FBX and COLLADA loaders show for a source file: load an `.fbx` with
// three's FBXLoader or a `.dae`/`.zae` with its ColladaLoader (npm `three`, pinned in
// tools/package.json), play a clip with three's AnimationMixer and write the world-space
// position of every vertex of every mesh as three computes it on the CPU
// (Mesh.getVertexPosition: morph targets, then SkinnedMesh.applyBoneTransform with the four
// influences the loader kept), times the mesh's world matrix: the same code path
// tools/three_eval.mjs takes for a glb, so the two can be compared vertex by vertex.
//
//   node tools/three_source_eval.mjs FILE.(fbx|dae|zae) [--clip-index I]
//        [--times T0,T1,...] [--offset S] [--normalize-skin-weights] [--reapply-z-up]
//        --npy OUT.npy [--rest-npy REST.npy]
//
// Positions are in the loader's own world frame: FBXLoader rotates a file whose
// GlobalSettings.UpAxis is 2 by -90 degrees about X and keeps the file's unit;
// ColladaLoader rotates a Z_UP file the same way and scales the scene by `<unit meter>`.
// The caller converts to its own frame (tests/cli/fbx_fidelity.rs says which conversion).
//
// --times are clip times; the loader is played at T + S (--offset, default 0), since the
// loaders keep the source's absolute key times (a COLLADA `<animation_clip>` starting at
// 0.04 s has its first key at 0.04 s) where a converted clip starts at 0. --rest-npy writes
// the positions of the scene as loaded, before any clip plays (the same vertices).
// --normalize-skin-weights scales each vertex's kept weights to sum 1 with three's own
// SkinnedMesh.normalizeSkinWeights (FBXLoader drops influences past 4 without it).
// --reapply-z-up puts FBXLoader's Z-up correction back above the root after each frame a
// clip plays. When a file's only top-level node is a Group, FBXLoader returns that node as
// the scene and sets its rotation to the correction (-90 degrees about X), so a clip that
// animates the node's rotation overwrites the correction: the played scene stands in the
// file's own Z-up frame while the scene as loaded stands in three's Y-up. It is an error
// to give the flag where that is not what happened.
//
// stdout: one JSON object:
//   {"file", "loader", "up_axis", "clips": [{"name", "duration", "start", "key_times"}], "clip",
//    "times", "meshes": [{"name", "skinned", "vertex_count", "offset", "morph_targets"}]}
// "up_axis" is a COLLADA document's `<up_axis>` (null for FBX); "start" is a COLLADA clip's `start` (null for FBX, or the whole timeline), "key_times"
// the union of the clip's track times (loader time). The positions file is a little-endian
// float32 .npy of shape (times, total vertices, 3).
//
// No image is decoded and nothing is fetched: texture loading is stubbed (skinning, morphs
// and animation are what is compared). COLLADA needs a DOM: @xmldom/xmldom's DOMParser.
//
// Exit status: 0 on success, 1 when three cannot load the file or the clip is missing,
// 2 on a usage error.

import { readFile, writeFile } from 'node:fs/promises';
import process from 'node:process';

import { DOMParser, Node } from '@xmldom/xmldom';
import * as THREE from 'three';
import { FBXLoader } from 'three/examples/jsm/loaders/FBXLoader.js';
import { ColladaLoader } from 'three/examples/jsm/loaders/ColladaLoader.js';
import { TGALoader } from 'three/examples/jsm/loaders/TGALoader.js';
import { unzipSync, strFromU8 } from 'three/examples/jsm/libs/fflate.module.js';

import { npy } from './npy.mjs';

const USAGE = `usage: node tools/three_source_eval.mjs FILE.(fbx|dae|zae) [--clip-index I]
       [--times T0,T1,...] [--offset S] [--normalize-skin-weights] [--reapply-z-up]
       --npy OUT.npy [--rest-npy REST.npy]`;

function usage(msg) {
  process.stderr.write(`three_source_eval: ${msg}\n${USAGE}\n`);
  process.exit(2);
}

function parseArgs(argv) {
  const opts = { file: null, clipIndex: null, times: [0], offset: 0, npy: null, restNpy: null, normalize: false, reapplyZUp: false };
  for (let i = 0; i < argv.length; i++) {
    const a = argv[i];
    const value = () => {
      if (i + 1 >= argv.length) usage(`${a} needs a value`);
      return argv[++i];
    };
    if (a === '--clip-index') opts.clipIndex = Number.parseInt(value(), 10);
    else if (a === '--times') opts.times = value().split(',').map(Number);
    else if (a === '--offset') opts.offset = Number(value());
    else if (a === '--npy') opts.npy = value();
    else if (a === '--rest-npy') opts.restNpy = value();
    else if (a === '--normalize-skin-weights') opts.normalize = true;
    else if (a === '--reapply-z-up') opts.reapplyZUp = true;
    else if (a === '-h' || a === '--help') {
      process.stdout.write(`${USAGE}\n`);
      process.exit(0);
    } else if (a.startsWith('-')) usage(`unknown option ${a}`);
    else if (opts.file === null) opts.file = a;
    else usage(`more than one file: ${a}`);
  }
  if (opts.file === null) usage('no file given');
  if (opts.npy === null) usage('--npy is required');
  if (opts.times.some((t) => !Number.isFinite(t))) usage('--times takes numbers');
  if (!Number.isFinite(opts.offset)) usage('--offset takes a number');
  return opts;
}

// ---------------------------------------------------------------- Node shims
// ColladaParser calls `new DOMParser()` and reads `Node.TEXT_NODE`; ColladaComposer's
// kinematics look elements up with `querySelector('[attr="value"]')`, which xmldom lacks.
globalThis.DOMParser ??= DOMParser;
globalThis.Node ??= Node;
function querySelector(selector) {
  const m = /^\[(\w+)="([^"]*)"\]$/.exec(selector);
  if (!m) throw new Error(`querySelector shim: unsupported selector ${selector}`);
  const stack = [...this.childNodes];
  while (stack.length) {
    const n = stack.shift();
    if (n.nodeType === 1 && n.getAttribute(m[1]) === m[2]) return n;
    if (n.childNodes) stack.unshift(...n.childNodes);
  }
  return null;
}
for (const proto of [new DOMParser().parseFromString('<a/>', 'application/xml').documentElement]) {
  Object.getPrototypeOf(proto).querySelector ??= querySelector;
}
// three's FileLoader reports progress with a ProgressEvent, which Node lacks.
globalThis.ProgressEvent ??= class ProgressEvent extends Event {
  constructor(type, init = {}) {
    super(type);
    Object.assign(this, init);
  }
};
// FBXLoader sizes a camera's aspect from the browser window.
globalThis.window ??= { innerWidth: 1, innerHeight: 1 };
// No image is decoded: every texture load returns an empty texture at once.
const stubTexture = function stubTexture(url, onLoad) {
  const texture = new THREE.Texture();
  texture.userData.rigport = { url: typeof url === 'string' && url.startsWith('data:') ? 'data:' : url };
  if (onLoad) queueMicrotask(() => onLoad(texture));
  return texture;
};
THREE.TextureLoader.prototype.load = stubTexture;
TGALoader.prototype.load = stubTexture;

// ------------------------------------------------------------------ loading
// A `.zae`'s root document: the one `manifest.xml` names, else its only `.dae`.
function zaeRoot(bytes) {
  const files = unzipSync(new Uint8Array(bytes));
  let root = null;
  if (files['manifest.xml']) {
    const m = /<dae_root>\s*\.?\/?([^<]+?)\s*<\/dae_root>/.exec(strFromU8(files['manifest.xml']));
    if (m) root = decodeURIComponent(m[1]);
  }
  if (root === null) {
    const daes = Object.keys(files).filter((n) => n.toLowerCase().endsWith('.dae'));
    if (daes.length !== 1) throw new Error(`${daes.length} .dae files in the package and no manifest`);
    root = daes[0];
  }
  if (!files[root]) throw new Error(`the package has no ${root}`);
  return strFromU8(files[root]);
}

async function load(file) {
  const bytes = await readFile(file);
  const lower = file.toLowerCase();
  if (lower.endsWith('.fbx')) {
    const buffer = bytes.buffer.slice(bytes.byteOffset, bytes.byteOffset + bytes.byteLength);
    const scene = new FBXLoader().parse(buffer, '');
    return { loader: 'FBXLoader', scene, clips: scene.animations, starts: [], upAxis: null };
  }
  const text = lower.endsWith('.zae') ? zaeRoot(bytes) : bytes.toString('utf8');
  const result = new ColladaLoader().parse(text, '');
  if (result === null) throw new Error('ColladaLoader could not parse the file');
  const starts = Object.values(result.library.clips ?? {}).map((c) => c.start);
  const upAxis = /<up_axis>\s*(\w+)\s*<\/up_axis>/.exec(text)?.[1] ?? 'Y_UP';
  return { loader: 'ColladaLoader', scene: result.scene, clips: result.scene.animations, starts, upAxis };
}

function keyTimes(clip) {
  const times = new Set();
  for (const track of clip.tracks) for (const t of track.times) times.add(t);
  return [...times].sort((a, b) => a - b);
}

// Every mesh's vertices in world space, appended to `out` at `base` (floats).
function writePositions(meshes, out, base) {
  const v = new THREE.Vector3();
  let k = base;
  for (const mesh of meshes) {
    const count = mesh.geometry.attributes.position.count;
    for (let i = 0; i < count; i++) {
      mesh.getVertexPosition(i, v);
      v.applyMatrix4(mesh.matrixWorld);
      out[k++] = v.x;
      out[k++] = v.y;
      out[k++] = v.z;
    }
  }
}

async function main() {
  const opts = parseArgs(process.argv.slice(2));
  // The loaders' warnings (Z-up, > 4 influences) go to stderr, not into the JSON.
  console.warn = (...args) => process.stderr.write(`${args.join(' ')}\n`);
  console.log = console.warn;
  console.info = console.warn;
  console.debug = console.warn;
  const { loader, scene, clips, starts, upAxis } = await load(opts.file);

  let clip = null;
  if (opts.clipIndex !== null) {
    clip = clips[opts.clipIndex] ?? null;
    if (!clip) throw new Error(`no clip ${opts.clipIndex} (${clips.length} clips)`);
  }

  const meshes = [];
  scene.traverse((object) => {
    if (object.isMesh) meshes.push(object);
  });
  if (opts.normalize) {
    for (const mesh of meshes) if (mesh.isSkinnedMesh) mesh.normalizeSkinWeights();
  }
  let offset = 0;
  const info = meshes.map((mesh) => {
    const count = mesh.geometry.attributes.position.count;
    const entry = {
      name: mesh.name,
      skinned: Boolean(mesh.isSkinnedMesh),
      vertex_count: count,
      offset,
      morph_targets: mesh.geometry.morphAttributes.position?.length ?? 0,
    };
    offset += count;
    return entry;
  });

  scene.updateMatrixWorld(true);
  if (opts.restNpy) {
    const rest = new Float32Array(offset * 3);
    writePositions(meshes, rest, 0);
    await writeFile(opts.restNpy, npy(rest, [1, offset, 3]));
  }

  // The correction FBXLoader set on the root (see --reapply-z-up), checked to be so.
  let zUp = null;
  if (opts.reapplyZUp && clip) {
    const correction = new THREE.Quaternion().setFromAxisAngle(new THREE.Vector3(1, 0, 0), -Math.PI / 2);
    const own = `${THREE.PropertyBinding.sanitizeNodeName(scene.name)}.quaternion`;
    if (loader !== 'FBXLoader' || scene.quaternion.angleTo(correction) > 1e-9 || !clip.tracks.some((t) => t.name === own)) {
      throw new Error('--reapply-z-up: the root holds no Z-up correction that the clip overwrites');
    }
    zUp = correction;
  }

  const mixer = new THREE.AnimationMixer(scene);
  if (clip) {
    const action = mixer.clipAction(clip);
    action.setLoop(THREE.LoopOnce, 1);
    action.clampWhenFinished = true;
    action.play();
  }
  const out = new Float32Array(opts.times.length * offset * 3);
  opts.times.forEach((t, f) => {
    if (clip) mixer.setTime(t + opts.offset);
    if (zUp) scene.quaternion.premultiply(zUp);
    scene.updateMatrixWorld(true);
    writePositions(meshes, out, f * offset * 3);
  });
  await writeFile(opts.npy, npy(out, [opts.times.length, offset, 3]));

  const result = {
    file: opts.file,
    loader,
    up_axis: upAxis,
    clips: clips.map((c, i) => ({
      name: c.name,
      duration: c.duration,
      start: starts[i] ?? null,
      key_times: keyTimes(c),
    })),
    clip: clip ? clip.name : null,
    times: opts.times,
    meshes: info,
  };
  process.stdout.write(`${JSON.stringify(result)}\n`);
}

main().catch((error) => {
  process.stderr.write(`three_source_eval: ${error?.stack ?? error}\n`);
  process.exit(1);
});
