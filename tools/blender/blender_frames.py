"""What Blender's own FBX importer shows: every mesh's evaluated vertices, for
tests/cli/fbx_blender.rs.

    tools/.venv-blender/bin/python tools/blender/blender_frames.py FILE.fbx OUT.npz SPEC_JSON

SPEC_JSON: {"stack": NAME or null, "seconds": [t, ...]}: absolute FBX times in seconds
(a stack's clip starts at its own start time). The file is imported with io_scene_fbx's
defaults (units applied: Blender metres; the file's axes converted to Blender's +Z up;
every influence kept by the Armature modifier), except anim_offset 0, so FBX time t is
Blender frame t * fps. With a stack name, the actions of that stack ("OBJECT|STACK", as the
importer names them) are assigned to their objects first.

Writes OUT.npz: `names` (mesh object names, as FBX model names), and per mesh k
`points_k` (F x V x 3, +Y-up metres: Blender (x, y, z) -> (x, z, -y), in the order of the
mesh's vertices, which are the FBX control points in order) and `rest_k` (V x 3, the
points with no modifier and no shape key, object transform applied, +Y up metres).
"""

import json
import math
import sys

import bpy
import numpy as np


def y_up(a):
    return np.stack([a[:, 0], a[:, 2], -a[:, 1]], axis=1)


def world_points(obj, depsgraph):
    ev = obj.evaluated_get(depsgraph)
    mesh = ev.to_mesh()
    co = np.empty(len(mesh.vertices) * 3, dtype=np.float64)
    mesh.vertices.foreach_get("co", co)
    ev.to_mesh_clear()
    m = np.array(ev.matrix_world, dtype=np.float64)
    co = co.reshape(-1, 3) @ m[:3, :3].T + m[:3, 3]
    return y_up(co)


def assign_stack(stack):
    """Assigns to each object (and shape-key block) its action of `stack`: the importer
    names them "ID|STACK" (or "ID|STACK|LAYER"; the first layer's is kept)."""
    ids = list(bpy.data.objects) + [m.shape_keys for m in bpy.data.meshes if m.shape_keys]
    for target in ids:
        prefix = target.name + "|" + stack
        mine = [a for a in bpy.data.actions if a.name == prefix or a.name.startswith(prefix + "|")]
        # A camera's data and its object share a name: only the slot of the target's kind.
        mine = [a for a in mine if a.slots and a.slots[0].target_id_type == target.id_type]
        if not mine:
            continue
        target.animation_data_create()
        target.animation_data.action = mine[0]
        target.animation_data.action_slot = mine[0].slots[0]


def main():
    path, out, spec = sys.argv[1], sys.argv[2], json.loads(sys.argv[3])
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.import_scene.fbx(filepath=path, anim_offset=0.0)
    scene = bpy.context.scene
    if spec.get("stack"):
        assign_stack(spec["stack"])
    fps = scene.render.fps / scene.render.fps_base
    meshes = sorted((o for o in scene.objects if o.type == "MESH"), key=lambda o: o.name)
    arrays = {"names": np.array([o.name for o in meshes]), "fps": np.array(fps)}
    for k, obj in enumerate(meshes):
        # The rest: no modifier, no shape key (the basis), object transform at frame 0.
        co = np.empty(len(obj.data.vertices) * 3, dtype=np.float64)
        obj.data.vertices.foreach_get("co", co)
        m = np.array(obj.matrix_world, dtype=np.float64)
        arrays[f"rest_{k}"] = y_up(co.reshape(-1, 3) @ m[:3, :3].T + m[:3, 3])
    frames = {k: [] for k in range(len(meshes))}
    for t in spec["seconds"]:
        f = t * fps
        whole = math.floor(f + 1e-9)
        scene.frame_set(whole, subframe=max(0.0, f - whole))
        depsgraph = bpy.context.evaluated_depsgraph_get()
        for k, obj in enumerate(meshes):
            frames[k].append(world_points(obj, depsgraph))
    for k, f in frames.items():
        arrays[f"points_{k}"] = np.stack(f) if f else np.zeros((0, 0, 3))
    np.savez(out, **arrays)


if __name__ == "__main__":
    main()
