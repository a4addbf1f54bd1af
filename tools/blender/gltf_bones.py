"""How far apart Blender's glTF importer plays two files of one clip: every pose bone's
head and points 3 cm along its local X and Z axes, world space, at every frame; for
tests/cli/compact.rs.

    tools/.venv-blender/bin/python tools/blender/gltf_bones.py REFERENCE.glb CANDIDATE.glb FPS

Each file is imported with io_scene_gltf2's defaults into an empty scene running at FPS
frames a second, so a key at t seconds lands on frame t * FPS: with the clip's own rate,
Blender's frames are its source frames. Bones are paired by name, frames by number, over
the frames of the reference's action. Prints JSON: {"compared": bone-frames, "max":
metres, "worst": {"bone": name, "frame": n}}.
"""

import json
import sys

import bpy
import mathutils

DISTANCE = 0.03


def bone_points(path, fps):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.context.scene.render.fps = fps
    bpy.context.scene.render.fps_base = 1.0
    bpy.ops.import_scene.gltf(filepath=path)
    armature = next(o for o in bpy.data.objects if o.type == "ARMATURE")
    action = armature.animation_data.action
    first, last = (int(round(f)) for f in action.frame_range)
    offsets = [mathutils.Vector(v) for v in ((0, 0, 0), (DISTANCE, 0, 0), (0, 0, DISTANCE))]
    points = {}
    for frame in range(first, last + 1):
        bpy.context.scene.frame_set(frame)
        for bone in armature.pose.bones:
            m = armature.matrix_world @ bone.matrix
            points[(frame, bone.name)] = [m @ v for v in offsets]
    return points


def main():
    reference, candidate, fps = sys.argv[-3], sys.argv[-2], int(sys.argv[-1])
    a = bone_points(reference, fps)
    b = bone_points(candidate, fps)
    worst, at, compared = 0.0, None, 0
    for key, pa in a.items():
        pb = b.get(key)
        if pb is None:
            continue
        compared += 1
        d = max((x - y).length for x, y in zip(pa, pb))
        if d > worst:
            worst, at = d, key
    print(json.dumps({
        "compared": compared,
        "max": worst,
        "worst": {"frame": at[0], "bone": at[1]} if at else None,
    }))


main()
