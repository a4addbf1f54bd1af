#!/usr/bin/env node
// How far a compacted glTF's motion is from a reference, as three.js plays both: load
// REFERENCE and CANDIDATE with three's own GLTFLoader (with its meshopt decoder, so
// EXT_meshopt_compression files load), play clip 0 of each with an AnimationMixer at every
// key time of the reference's clip (the union of its samplers' inputs: the source frames),
// and compare, node by node (by name, else in scene order when both files have the same
// nodes), the world position of every node that is not a mesh and of three virtual points at DISTANCE on its local x, y and z axes (ACL's error
// metric: virtual vertices at a shell distance from each bone; 3 cm by default, in the
// file's unit, metres for glTF).
//
//   node tools/three_joints.mjs REFERENCE.glb CANDIDATE.glb [--distance D]
//
// Nodes of the reference the candidate lacks (gltfpack removes nodes nothing uses) are
// left out and counted as "missing".
//
// stdout: one JSON object:
//   {"times": N, "nodes": M, "missing": K, "joint_max": ..., "point_max": ..., "max": ..., "mean": ...,
//    "worst": {"node": name, "time": t}}
// joint_max is the largest node position error, point_max that of the virtual points,
// max the larger, mean the mean over nodes and times of each node's largest point error.
//
// Exit status: 0 on success, 1 when a file does not load or the scenes differ, 2 on a
// usage error.

import { readFile } from 'node:fs/promises';
import process from 'node:process';

import * as THREE from 'three';
import { GLTFLoader } from 'three/examples/jsm/loaders/GLTFLoader.js';
import { MeshoptDecoder } from 'three/examples/jsm/libs/meshopt_decoder.module.js';

const USAGE = 'usage: node tools/three_joints.mjs REFERENCE.glb CANDIDATE.glb [--distance D]';

function usage(msg) {
  process.stderr.write(`three_joints: ${msg}\n${USAGE}\n`);
  process.exit(2);
}

function parseArgs(argv) {
  const opts = { files: [], distance: 0.03 };
  for (let i = 0; i < argv.length; i++) {
    const a = argv[i];
    if (a === '--distance') {
      if (i + 1 >= argv.length) usage('--distance needs a value');
      opts.distance = Number(argv[++i]);
      if (!(opts.distance >= 0)) usage('--distance takes a number >= 0');
    } else if (a.startsWith('-')) usage(`unknown option ${a}`);
    else opts.files.push(a);
  }
  if (opts.files.length !== 2) usage('give two files');
  return opts;
}

// Node has no ProgressEvent; three's FileLoader reports progress with one.
globalThis.ProgressEvent ??= class ProgressEvent extends Event {
  constructor(type, init = {}) {
    super(type);
    Object.assign(this, init);
  }
};

async function load(file) {
  const bytes = await readFile(file);
  const loader = new GLTFLoader();
  loader.setMeshoptDecoder(MeshoptDecoder);
  const gltf = await loader.parseAsync(
    bytes.buffer.slice(bytes.byteOffset, bytes.byteOffset + bytes.byteLength),
    '',
  );
  const clip = gltf.animations[0];
  if (!clip) throw new Error(`${file}: no clip`);
  const mixer = new THREE.AnimationMixer(gltf.scene);
  const action = mixer.clipAction(clip);
  action.setLoop(THREE.LoopOnce, 1);
  action.clampWhenFinished = true;
  action.play();
  const nodes = [];
  gltf.scene.traverse((object) => {
    if (object !== gltf.scene && !object.isMesh) nodes.push(object);
  });
  return { gltf, clip, mixer, nodes };
}

// The union of the clip's key times (three keeps each track's times as loaded).
function keyTimes(clip) {
  const all = new Set();
  for (const track of clip.tracks) for (const t of track.times) all.add(t);
  return [...all].sort((a, b) => a - b);
}

// World positions of each node and its three virtual points, flat.
function pointsOf(scene, nodes, distance, out) {
  scene.updateMatrixWorld(true);
  const v = new THREE.Vector3();
  const axes = [
    [0, 0, 0],
    [distance, 0, 0],
    [0, distance, 0],
    [0, 0, distance],
  ];
  let k = 0;
  for (const node of nodes) {
    for (const [x, y, z] of axes) {
      v.set(x, y, z).applyMatrix4(node.matrixWorld);
      out[k++] = v.x;
      out[k++] = v.y;
      out[k++] = v.z;
    }
  }
}

async function main() {
  const opts = parseArgs(process.argv.slice(2));
  await MeshoptDecoder.ready;
  const [a, b] = await Promise.all(opts.files.map(load));
  const referenceCount = a.nodes.length;
  // Pairs by name when names are unique, else by scene order.
  const unique = (nodes) => new Set(nodes.map((x) => x.name)).size === nodes.length;
  let pairs;
  if (unique(a.nodes) && unique(b.nodes)) {
    const byName = new Map(b.nodes.map((x) => [x.name, x]));
    pairs = a.nodes.filter((x) => byName.has(x.name)).map((x) => [x, byName.get(x.name)]);
  } else if (a.nodes.length === b.nodes.length) {
    pairs = a.nodes.map((x, k) => [x, b.nodes[k]]);
  } else {
    throw new Error(`${a.nodes.length} nodes against ${b.nodes.length}, names not unique`);
  }
  a.nodes = pairs.map(([x]) => x);
  b.nodes = pairs.map(([, y]) => y);
  const times = keyTimes(a.clip);
  const n = a.nodes.length;
  const pa = new Float64Array(n * 12);
  const pb = new Float64Array(n * 12);
  let jointMax = 0;
  let pointMax = 0;
  let sum = 0;
  let worst = { node: null, time: null, error: -1 };
  for (const t of times) {
    a.mixer.setTime(t);
    b.mixer.setTime(t);
    pointsOf(a.gltf.scene, a.nodes, opts.distance, pa);
    pointsOf(b.gltf.scene, b.nodes, opts.distance, pb);
    for (let j = 0; j < n; j++) {
      let nodeWorst = 0;
      for (let p = 0; p < 4; p++) {
        const at = j * 12 + p * 3;
        const d = Math.hypot(pa[at] - pb[at], pa[at + 1] - pb[at + 1], pa[at + 2] - pb[at + 2]);
        if (p === 0) jointMax = Math.max(jointMax, d);
        else pointMax = Math.max(pointMax, d);
        nodeWorst = Math.max(nodeWorst, d);
      }
      sum += nodeWorst;
      if (nodeWorst > worst.error) worst = { node: a.nodes[j].name, time: t, error: nodeWorst };
    }
  }
  const result = {
    times: times.length,
    nodes: n,
    missing: referenceCount - n,
    joint_max: jointMax,
    point_max: pointMax,
    max: Math.max(jointMax, pointMax),
    mean: sum / Math.max(1, times.length * n),
    worst: { node: worst.node, time: worst.time },
  };
  process.stdout.write(`${JSON.stringify(result)}\n`);
}

main().catch((error) => {
  process.stderr.write(`three_joints: ${error?.message ?? error}\n`);
  process.exit(1);
});
