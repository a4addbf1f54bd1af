#!/usr/bin/env node
// What three.js shows for a glTF file: load it with three's own GLTFLoader
// (npm `three`, pinned in tools/package.json), play a clip with three's
// AnimationMixer, and print the world-space position of every vertex of every
// mesh as three computes it on the CPU (Mesh.getVertexPosition: morph targets,
// then SkinnedMesh.applyBoneTransform: the first four influences, JOINTS_0 /
// WEIGHTS_0, exactly what three's skinning shader uses), times the mesh's world
// matrix.
//
//   node tools/three_eval.mjs FILE.(glb|gltf) [--clip NAME | --clip-index I]
//        [--times T0,T1,... | --fps F] [--npy OUT.npy] [--rest-npy REST.npy]
//
// Without --clip/--clip-index no clip plays (the scene as loaded: rest pose and
// default morph weights). --times takes seconds; --fps F samples the clip from 0
// to its duration at F frames per second (both ends included); the default is
// time 0. Clips play once and clamp at their end (LoopOnce +
// clampWhenFinished), so the last time shows the last key, not the first.
//
// stdout: one JSON object:
//   {"file", "clips": [names], "clip", "times": [...],
//    "meshes": [{"name", "node", "mesh", "primitive", "skinned", "vertex_count",
//                "offset", "morph_targets", "material": {"name", "color": [r,g,b,a],
//                "map": null | {"texture", "image", "mime_type", "texcoord"}}}],
//    "positions": [[x,y,z, ...] per time]}      (omitted with --npy)
// meshes are in scene traversal order; "offset" is the mesh's first vertex in
// the concatenated vertex list. With --npy OUT the positions go to OUT as a
// little-endian float32 array of shape (times, total vertices, 3). --rest-npy REST writes
// the scene as loaded, before any clip plays (shape (1, total vertices, 3)).
//
// Textures are not decoded (Node has no image decoder): a loader plugin stands
// in for each texture and records which image and MIME type the material's map
// is bound to, so a test can check that three binds the texture.
//
// Exit status: 0 on success, 1 when three cannot load the file or the clip is
// missing, 2 on a usage error.

import { readFile, writeFile } from 'node:fs/promises';
import path from 'node:path';
import process from 'node:process';

import * as THREE from 'three';
import { GLTFLoader } from 'three/examples/jsm/loaders/GLTFLoader.js';
import { MeshoptDecoder } from 'three/examples/jsm/libs/meshopt_decoder.module.js';

import { npy } from './npy.mjs';

const USAGE = `usage: node tools/three_eval.mjs FILE.(glb|gltf) [--clip NAME | --clip-index I]
       [--times T0,T1,... | --fps F] [--npy OUT.npy] [--rest-npy REST.npy]`;

function usage(msg) {
  process.stderr.write(`three_eval: ${msg}\n${USAGE}\n`);
  process.exit(2);
}

function parseArgs(argv) {
  const opts = { file: null, clip: null, clipIndex: null, times: null, fps: null, npy: null, restNpy: null };
  for (let i = 0; i < argv.length; i++) {
    const a = argv[i];
    const value = () => {
      if (i + 1 >= argv.length) usage(`${a} needs a value`);
      return argv[++i];
    };
    if (a === '--clip') opts.clip = value();
    else if (a === '--clip-index') opts.clipIndex = Number.parseInt(value(), 10);
    else if (a === '--times') opts.times = value().split(',').map(Number);
    else if (a === '--fps') opts.fps = Number(value());
    else if (a === '--npy') opts.npy = value();
    else if (a === '--rest-npy') opts.restNpy = value();
    else if (a === '-h' || a === '--help') {
      process.stdout.write(`${USAGE}\n`);
      process.exit(0);
    } else if (a.startsWith('-')) usage(`unknown option ${a}`);
    else if (opts.file === null) opts.file = a;
    else usage(`more than one file: ${a}`);
  }
  if (opts.file === null) usage('no file given');
  if (opts.times && opts.times.some((t) => !Number.isFinite(t))) usage('--times takes numbers');
  if (opts.fps !== null && !(opts.fps > 0)) usage('--fps takes a positive number');
  if (opts.times && opts.fps !== null) usage('give --times or --fps, not both');
  return opts;
}

// A .gltf's external buffers, inlined as data URIs (Node's fetch reads no file: URLs).
async function inlineBuffers(file, bytes) {
  const json = JSON.parse(new TextDecoder().decode(bytes));
  for (const buffer of json.buffers ?? []) {
    if (buffer.uri && !buffer.uri.startsWith('data:')) {
      const data = await readFile(path.join(path.dirname(file), decodeURIComponent(buffer.uri)));
      buffer.uri = `data:application/octet-stream;base64,${data.toString('base64')}`;
    }
  }
  return JSON.stringify(json);
}

// Stands in for three's texture loading: a Texture that names its image.
function textureRecorder(parser) {
  return {
    name: 'rigport_texture_recorder',
    loadTexture(textureIndex) {
      const json = parser.json;
      const def = json.textures[textureIndex];
      const texture = new THREE.Texture();
      const image = def.source;
      texture.userData.rigport = {
        texture: textureIndex,
        image: image ?? null,
        mime_type: image === undefined ? null : json.images[image].mimeType ?? null,
        uri: image === undefined ? null : json.images[image].uri ?? null,
      };
      texture.flipY = false;
      return Promise.resolve(texture);
    },
  };
}

function materialOf(mesh) {
  const m = Array.isArray(mesh.material) ? mesh.material[0] : mesh.material;
  if (!m) return null;
  const map = m.map ? { ...m.map.userData.rigport, texcoord: m.map.channel ?? 0 } : null;
  const color = m.color ? [m.color.r, m.color.g, m.color.b, m.opacity ?? 1] : null;
  return { name: m.name ?? '', color, map };
}

// Node has no ProgressEvent; three's FileLoader reports progress with one.
globalThis.ProgressEvent ??= class ProgressEvent extends Event {
  constructor(type, init = {}) {
    super(type);
    Object.assign(this, init);
  }
};

async function main() {
  const opts = parseArgs(process.argv.slice(2));
  const bytes = await readFile(opts.file);
  const data = opts.file.toLowerCase().endsWith('.gltf')
    ? await inlineBuffers(opts.file, bytes)
    : bytes.buffer.slice(bytes.byteOffset, bytes.byteOffset + bytes.byteLength);

  const loader = new GLTFLoader();
  loader.register(textureRecorder);
  // EXT_meshopt_compression files (rigport's --compress meshopt) decode as three's apps do.
  await MeshoptDecoder.ready;
  loader.setMeshoptDecoder(MeshoptDecoder);
  const gltf = await loader.parseAsync(data, '');
  const scene = gltf.scene;
  const clips = gltf.animations;

  let clip = null;
  if (opts.clip !== null) {
    clip = clips.find((c) => c.name === opts.clip) ?? null;
    if (!clip) throw new Error(`no clip named ${JSON.stringify(opts.clip)} (clips: ${clips.map((c) => c.name).join(', ')})`);
  } else if (opts.clipIndex !== null) {
    clip = clips[opts.clipIndex] ?? null;
    if (!clip) throw new Error(`no clip ${opts.clipIndex} (${clips.length} clips)`);
  }

  let times = opts.times ?? [0];
  if (opts.fps !== null) {
    const duration = clip ? clip.duration : 0;
    const n = Math.floor(duration * opts.fps + 1e-9);
    times = Array.from({ length: n + 1 }, (_, i) => i / opts.fps);
    if (duration - times[n] > 1e-9) times.push(duration);
  }

  const meshes = [];
  scene.traverse((object) => {
    if (object.isMesh) meshes.push(object);
  });
  let offset = 0;
  const info = meshes.map((mesh) => {
    const assoc = gltf.parser.associations.get(mesh) ?? {};
    let nodeObject = mesh;
    while (nodeObject && gltf.parser.associations.get(nodeObject)?.nodes === undefined) {
      nodeObject = nodeObject.parent;
    }
    const count = mesh.geometry.attributes.position.count;
    const entry = {
      name: mesh.name,
      node: nodeObject ? gltf.parser.associations.get(nodeObject).nodes : null,
      mesh: assoc.meshes ?? null,
      primitive: assoc.primitives ?? null,
      skinned: Boolean(mesh.isSkinnedMesh),
      vertex_count: count,
      offset,
      morph_targets: mesh.geometry.morphAttributes.position?.length ?? 0,
      material: materialOf(mesh),
    };
    offset += count;
    return entry;
  });

  const mixer = new THREE.AnimationMixer(scene);
  if (clip) {
    const action = mixer.clipAction(clip);
    action.setLoop(THREE.LoopOnce, 1);
    action.clampWhenFinished = true;
    action.play();
  }

  const v = new THREE.Vector3();
  // Every mesh's world-space vertices at the current pose into `out` from float `base`.
  const positionsInto = (out, base) => {
    for (const [k, mesh] of meshes.entries()) {
      const at = base + info[k].offset * 3;
      for (let i = 0; i < info[k].vertex_count; i++) {
        mesh.getVertexPosition(i, v);
        v.applyMatrix4(mesh.matrixWorld);
        out[at + 3 * i] = v.x;
        out[at + 3 * i + 1] = v.y;
        out[at + 3 * i + 2] = v.z;
      }
    }
  };
  if (opts.restNpy) {
    scene.updateMatrixWorld(true);
    const rest = new Float32Array(offset * 3);
    positionsInto(rest, 0);
    await writeFile(opts.restNpy, npy(rest, [1, offset, 3]));
  }
  const out = new Float32Array(times.length * offset * 3);
  times.forEach((t, f) => {
    if (clip) mixer.setTime(t);
    scene.updateMatrixWorld(true);
    positionsInto(out, f * offset * 3);
  });

  const result = {
    file: opts.file,
    clips: clips.map((c) => c.name),
    clip: clip ? clip.name : null,
    times,
    meshes: info,
  };
  if (opts.npy) {
    await writeFile(opts.npy, npy(out, [times.length, offset, 3]));
  } else {
    result.positions = times.map((_, f) => Array.from(out.subarray(f * offset * 3, (f + 1) * offset * 3)));
  }
  process.stdout.write(`${JSON.stringify(result)}\n`);
}

main().catch((error) => {
  process.stderr.write(`three_eval: ${error?.message ?? error}\n`);
  process.exit(1);
});
