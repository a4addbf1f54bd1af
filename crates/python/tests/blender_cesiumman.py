"""rigport inside Blender (issue 32): run with the bpy venv's Python, rigport's wheel
installed in it.

    tools/.venv-blender/bin/python crates/python/tests/blender_cesiumman.py CesiumMan.glb FRAME

Opens the glTF with rigport, evaluates it at Blender frame FRAME, and builds a Blender mesh
from rigport's `positions` and `indices`; imports the same file with Blender's own glTF
importer and evaluates it at FRAME. Prints one JSON line: the largest distance from a vertex
of either mesh to the other mesh's nearest vertex, the bounding box diagonal and the vertex
counts, and how far the mesh moved since the clip's first frame. Both meshes are in Blender's world space (+Z up, metres): rigport's +Y-up model
space becomes Blender's by (x, y, z) -> (x, -z, y), as Blender's importer converts.
"""

import json
import sys

import bpy
import numpy as np
from mathutils import kdtree

import rigport


def blender_mesh(name, points, triangles):
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata(points.tolist(), [], triangles.tolist())
    mesh.validate()
    obj = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(obj)
    return obj


def world_points(obj):
    depsgraph = bpy.context.evaluated_depsgraph_get()
    ev = obj.evaluated_get(depsgraph)
    mesh = ev.to_mesh()
    co = np.empty(len(mesh.vertices) * 3, dtype=np.float64)
    mesh.vertices.foreach_get("co", co)
    ev.to_mesh_clear()
    m = np.array(ev.matrix_world, dtype=np.float64)
    return co.reshape(-1, 3) @ m[:3, :3].T + m[:3, 3]


def farthest(a, b):
    """The largest distance from a point of `a` to its nearest point of `b`."""
    tree = kdtree.KDTree(len(b))
    for i, p in enumerate(b):
        tree.insert(p, i)
    tree.balance()
    return max(tree.find(p)[2] for p in a)


def main():
    path, frame = sys.argv[1], int(sys.argv[2])
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    bpy.ops.import_scene.gltf(filepath=path)
    # The character's meshes (the importer also makes a bone-shape mesh, parented to
    # nothing and deformed by nothing).
    meshes = [
        o for o in scene.objects
        if o.type == "MESH" and any(m.type == "ARMATURE" for m in o.modifiers)
    ]
    actions = list(bpy.data.actions)
    # The importer keys the clip's first key time at the action's first frame.
    start = min(a.frame_range[0] for a in actions)
    fps = scene.render.fps / scene.render.fps_base
    scene.frame_set(frame)
    theirs = np.concatenate([world_points(o) for o in meshes])

    asset = rigport.open(path)
    clip = asset.clips[0]
    t = clip.times[0] + (frame - start) / fps
    frames = asset.evaluate(times=[t, clip.times[0]])
    ours, first = [], []
    for mesh, rows in zip(asset.meshes, frames.rows):
        p = frames.positions[0][rows].astype(np.float64)
        z_up = np.stack([p[:, 0], -p[:, 2], p[:, 1]], axis=1)
        obj = blender_mesh("rigport_" + mesh.name, z_up, mesh.indices)
        ours.append(world_points(obj))
        first.append(frames.positions[1][rows].astype(np.float64))
    ours = np.concatenate(ours)
    first = np.concatenate(first)
    first = np.stack([first[:, 0], -first[:, 2], first[:, 1]], axis=1)

    lo = np.minimum(theirs.min(0), ours.min(0))
    hi = np.maximum(theirs.max(0), ours.max(0))
    if "-v" in sys.argv:
        print("ours", ours.min(0), ours.max(0), "theirs", theirs.min(0), theirs.max(0), "start", start, fps)
    print(json.dumps({
        "deviation": max(farthest(ours, theirs), farthest(theirs, ours)),
        # How far frame 10 is from the clip's first frame, vertex by vertex.
        "moved": float(np.linalg.norm(ours - first, axis=1).max()),
        "diagonal": float(np.linalg.norm(hi - lo)),
        "vertices": [len(ours), len(theirs)],
        "time": t,
        "blender": bpy.app.version_string,
    }))


main()
