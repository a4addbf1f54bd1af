"""FBX fixtures made by Blender's own exporter (io_scene_fbx), for tests/cli/fbx_blender.rs.

    tools/.venv-blender/bin/python tools/blender/make_fbx.py OUT_DIR CASE [CASE ...]

Writes OUT_DIR/CASE.fbx (binary FBX 7.4, as Blender writes it) for each CASE:

  rig        a 4-bone chain with rolled, bent bones skinning a tube, every vertex on up to 4
             bones (more than 2 so "all influences" matters), one action keyed at every
             frame (30 fps, 1 s); FBX unit metres (UnitScaleFactor 100), +Y up
  cm_zup     the same rig exported as a centimetre (UnitScaleFactor 1), +Z up file
  two_stacks the rig with two actions: one AnimStack per action (bake_anim_use_all_actions)
  shapes     the rig's tube with two shape keys (BlendShapeChannels), their values keyed,
             on top of the skinning
  mixamo     a Mixamo-like character (tools/blender/mixamo.py): ~20k vertices on the 65
             `mixamorig:` bones, centimetres, +Y up, one clip
  mixamo_anim the same armature and clip, no mesh (an animation-only Mixamo download)
  mixamo_bench the character at Mixamo's download size for BENCHMARKS.md: ~28k vertices,
             a 15 s clip (about 2.9 MB)

What Blender's exporter cannot write, and so is not made here (fixtures/README.md):
pivots, pre/post rotation and inherit types (it writes every transform as Lcl T/R/S with
InheritType RSrs), and in-between shapes (one Shape per BlendShapeChannel).
Every key is exported (bake_anim_simplify_factor 0), so the keys are at every frame.
"""

import math
import os
import sys

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import mixamo  # noqa: E402

FPS = 30


def reset():
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.fps = FPS
    scene.render.fps_base = 1.0
    scene.frame_start = 0
    return scene


def armature(name, bones):
    """An armature object from [(name, head, tail, roll_deg, parent)] in metres."""
    data = bpy.data.armatures.new(name)
    obj = bpy.data.objects.new(name, data)
    bpy.context.scene.collection.objects.link(obj)
    bpy.context.view_layer.objects.active = obj
    bpy.ops.object.mode_set(mode="EDIT")
    for bname, head, tail, roll, parent in bones:
        b = data.edit_bones.new(bname)
        b.head, b.tail, b.roll = head, tail, math.radians(roll)
        if parent:
            b.parent = data.edit_bones[parent]
    bpy.ops.object.mode_set(mode="OBJECT")
    return obj


CHAIN = [
    ("root", (0, 0, 0), (0, 0, 0.3), 0, None),
    ("lower", (0, 0, 0.3), (0.05, 0, 0.8), 30, "root"),
    ("upper", (0.05, 0, 0.8), (0, 0.1, 1.3), -45, "lower"),
    ("tip", (0, 0.1, 1.3), (0, 0.1, 1.6), 90, "upper"),
]


def tube(name, rings=16, segments=12, radius=0.12, height=1.6):
    verts, faces = [], []
    for r in range(rings + 1):
        z = height * r / rings
        for s in range(segments):
            a = 2 * math.pi * s / segments
            verts.append((radius * math.cos(a), radius * math.sin(a), z))
    for r in range(rings):
        for s in range(segments):
            a, b = r * segments + s, r * segments + (s + 1) % segments
            faces.append((a, b, b + segments, a + segments))
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata(verts, [], faces)
    obj = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(obj)
    return obj


def skin(mesh_obj, arm_obj, bones, falloff=0.35):
    """Weights by distance to each bone's mid-point, every bone within reach kept (up to
    4 per vertex), then the armature modifier and parent."""
    mids = {b[0]: [(h + t) / 2 for h, t in zip(b[1], b[2])] for b in bones}
    groups = {n: mesh_obj.vertex_groups.new(name=n) for n in mids}
    for v in mesh_obj.data.vertices:
        w = {}
        for n, m in mids.items():
            d = math.dist(v.co, m)
            if d < falloff * 2:
                w[n] = max(1e-3, 1.0 - d / (falloff * 2))
        if not w:
            n = min(mids, key=lambda n: math.dist(v.co, mids[n]))
            w = {n: 1.0}
        total = sum(w.values())
        for n, x in w.items():
            groups[n].add([v.index], x / total, "REPLACE")
    mod = mesh_obj.modifiers.new("Armature", "ARMATURE")
    mod.object = arm_obj
    mesh_obj.parent = arm_obj


def key_action(arm_obj, name, amplitude_deg, frames=FPS, move=(0.0, 0.0, 0.0)):
    """An action bending every bone about a different axis, keyed at every frame."""
    action = bpy.data.actions.new(name)
    arm_obj.animation_data_create()
    arm_obj.animation_data.action = action
    axes = [(1, 0, 0), (0, 1, 0), (1, 0, 1), (0, 0, 1)]
    for f in range(frames + 1):
        t = f / frames
        for k, pb in enumerate(arm_obj.pose.bones):
            pb.rotation_mode = "XYZ"
            angle = math.radians(amplitude_deg) * math.sin(2 * math.pi * t + k)
            pb.rotation_euler = [a * angle for a in axes[k % len(axes)]]
            pb.keyframe_insert("rotation_euler", frame=f)
            if k == 0:
                pb.location = [m * math.sin(math.pi * t) for m in move]
                pb.keyframe_insert("location", frame=f)
    bpy.context.scene.frame_end = frames
    return action


def rig_scene(shapes=False):
    scene = reset()
    arm = armature("Armature", CHAIN)
    body = tube("Tube")
    if shapes:
        body.shape_key_add(name="Basis")
        for name, scale in (("Bulge", 1.6), ("Pinch", 0.5)):
            key = body.shape_key_add(name=name)
            for i, v in enumerate(body.data.vertices):
                x, y, z = v.co
                f = scale if 0.5 < z < 1.1 else 1.0
                key.data[i].co = (x * f, y * f, z)
        blocks = body.data.shape_keys.key_blocks
        for f, (a, b) in enumerate([(0, 0), (1, 0.2), (0.3, 1), (0, 0.5)]):
            blocks["Bulge"].value, blocks["Pinch"].value = a, b
            blocks["Bulge"].keyframe_insert("value", frame=f * 10)
            blocks["Pinch"].keyframe_insert("value", frame=f * 10)
    skin(body, arm, CHAIN)
    key_action(arm, "Bend", 35, move=(0.1, 0.0, 0.05))
    return scene, arm


def export(path, **options):
    settings = dict(
        use_selection=False,
        object_types={"ARMATURE", "MESH"},
        use_mesh_modifiers=False,
        add_leaf_bones=False,
        bake_anim=True,
        bake_anim_use_all_actions=False,
        bake_anim_use_nla_strips=False,
        bake_anim_simplify_factor=0.0,
        bake_anim_step=1.0,
        axis_forward="-Z",
        axis_up="Y",
    )
    settings.update(options)
    bpy.ops.export_scene.fbx(filepath=path, **settings)


def make(case, path):
    if case == "rig":
        rig_scene()
        export(path, apply_scale_options="FBX_SCALE_UNITS")
    elif case == "cm_zup":
        rig_scene()
        export(path, apply_scale_options="FBX_SCALE_NONE", axis_up="Z", axis_forward="Y")
    elif case == "two_stacks":
        _, arm = rig_scene()
        key_action(arm, "Sway", 60, frames=20, move=(0.0, 0.2, 0.0))
        export(path, apply_scale_options="FBX_SCALE_UNITS", bake_anim_use_all_actions=True)
    elif case == "shapes":
        rig_scene(shapes=True)
        export(path, apply_scale_options="FBX_SCALE_UNITS")
    elif case in ("mixamo", "mixamo_anim"):
        reset()
        mixamo.build(with_mesh=case == "mixamo")
        # Mixamo's files are centimetres, +Y up: Blender's default scaling writes the
        # metre scene as centimetres (UnitScaleFactor 1).
        types = {"ARMATURE", "MESH"} if case == "mixamo" else {"ARMATURE"}
        export(path, apply_scale_options="FBX_SCALE_NONE", object_types=types)
    elif case == "mixamo_bench":
        reset()
        mixamo.build(with_mesh=True, rings_big=35, frames=450)
        export(path, apply_scale_options="FBX_SCALE_NONE")
    else:
        raise SystemExit(f"make_fbx.py: unknown case {case!r}")


def main():
    out = sys.argv[1]
    os.makedirs(out, exist_ok=True)
    for case in sys.argv[2:]:
        make(case, os.path.join(out, case + ".fbx"))
        print(case, os.path.getsize(os.path.join(out, case + ".fbx")))


if __name__ == "__main__":
    main()
