"""A Mixamo-like character built with bpy, for tools/blender/make_fbx.py.

Mixamo's skeleton: the 65 `mixamorig:` bones of its standard rig (hips, three spine bones,
neck, head, head-top end; shoulder, arm, forearm, hand and four bones per finger on each
side; up-leg, leg, foot, toe-base and toe end on each side), in a T-pose 1.75 m tall facing
-Y (Blender: +Z up). The mesh is one tube per bone (~20k vertices), each vertex on its bone
and, near the bone's head, on its parent. The clip ("mixamo.com", Mixamo's stack name) is 2 s
of marching in place at 30 fps: each foot rests on the ground for half the cycle, so foot
contacts exist, the arms swing and the hips bob.
"""

import math

import bpy
from mathutils import Matrix, Vector

P = "mixamorig:"
FINGERS = [("Thumb", -0.035, -0.01), ("Index", -0.02, 0.0), ("Middle", 0.0, 0.0),
           ("Ring", 0.015, 0.0), ("Pinky", 0.03, -0.005)]


def bones():
    """[(name, head, tail, parent)] in metres, parents first."""
    out = []

    def add(name, head, tail, parent):
        out.append((P + name, head, tail, P + parent if parent else None))

    spine = [("Hips", 0.95, 1.05), ("Spine", 1.05, 1.15), ("Spine1", 1.15, 1.27),
             ("Spine2", 1.27, 1.40), ("Neck", 1.40, 1.50), ("Head", 1.50, 1.68),
             ("HeadTop_End", 1.68, 1.75)]
    parent = None
    for name, z0, z1 in spine:
        add(name, (0, 0, z0), (0, 0, z1), parent)
        parent = name
    for side, sx in (("Left", 1), ("Right", -1)):
        x = lambda v: sx * v  # noqa: E731
        add(side + "Shoulder", (x(0.03), 0, 1.36), (x(0.15), 0, 1.38), "Spine2")
        add(side + "Arm", (x(0.15), 0, 1.38), (x(0.43), 0, 1.38), side + "Shoulder")
        add(side + "ForeArm", (x(0.43), 0, 1.38), (x(0.68), 0, 1.38), side + "Arm")
        add(side + "Hand", (x(0.68), 0, 1.38), (x(0.76), 0, 1.38), side + "ForeArm")
        for finger, dy, dz in FINGERS:
            prev = side + "Hand"
            for k in range(1, 5):
                x0 = 0.76 + 0.03 * (k - 1)
                name = f"{side}Hand{finger}{k}"
                add(name, (x(x0), dy, 1.38 + dz), (x(x0 + 0.03), dy, 1.38 + dz), prev)
                prev = name
        add(side + "UpLeg", (x(0.09), 0, 0.93), (x(0.09), 0, 0.50), "Hips")
        add(side + "Leg", (x(0.09), 0, 0.50), (x(0.09), 0, 0.08), side + "UpLeg")
        add(side + "Foot", (x(0.09), 0, 0.08), (x(0.09), -0.12, 0.02), side + "Leg")
        add(side + "ToeBase", (x(0.09), -0.12, 0.02), (x(0.09), -0.18, 0.0), side + "Foot")
        add(side + "ToeBase".replace("Base", "_End"), (x(0.09), -0.18, 0.0),
            (x(0.09), -0.22, 0.0), side + "ToeBase")
    assert len(out) == 65, len(out)
    return out


def radius_of(name):
    for part, r in (("Hand", 0.035), ("Hips", 0.15), ("Spine", 0.14), ("Neck", 0.05),
                    ("Head", 0.1), ("Shoulder", 0.05), ("ForeArm", 0.04), ("Arm", 0.05),
                    ("UpLeg", 0.08), ("Leg", 0.055), ("Foot", 0.045), ("Toe", 0.035)):
        if part in name:
            return r
    return 0.03


def build_mesh(arm_obj, table, rings_big=24):
    """One tube per bone (finger ends and head top have none), skinned to its bone and,
    near the head, to its parent."""
    verts, faces, weights = [], [], []
    for name, head, tail, parent in table:
        if name.endswith(("4", "_End")):
            continue
        finger = "Hand" in name and name[-1].isdigit()
        segments, rings = (8, 3) if finger else (32, rings_big)
        head, tail = Vector(head), Vector(tail)
        axis = tail - head
        rot = Vector((0, 0, 1)).rotation_difference(axis.normalized()).to_matrix().to_4x4()
        place = Matrix.Translation(head) @ rot
        r = radius_of(name)
        base = len(verts)
        for i in range(rings + 1):
            s = i / rings
            for j in range(segments):
                a = 2 * math.pi * j / segments
                verts.append(place @ Vector((r * math.cos(a), r * math.sin(a), s * axis.length)))
                own = 0.5 + 0.5 * min(1.0, s / 0.25) if parent else 1.0
                weights.append([(name, own)] + ([(parent, 1.0 - own)] if own < 1.0 else []))
        for i in range(rings):
            for j in range(segments):
                a, b = base + i * segments + j, base + i * segments + (j + 1) % segments
                faces.append((a, b, b + segments, a + segments))
    mesh = bpy.data.meshes.new("Body")
    mesh.from_pydata([tuple(v) for v in verts], [], faces)
    obj = bpy.data.objects.new("Body", mesh)
    bpy.context.scene.collection.objects.link(obj)
    groups = {n: obj.vertex_groups.new(name=n) for n, *_ in table}
    for v, ws in enumerate(weights):
        for n, w in ws:
            groups[n].add([v], w, "REPLACE")
    obj.modifiers.new("Armature", "ARMATURE").object = arm_obj
    obj.parent = arm_obj
    return obj


def key_clip(arm_obj, frames=60):
    action = bpy.data.actions.new("mixamo.com")
    arm_obj.animation_data_create()
    arm_obj.animation_data.action = action
    pose = arm_obj.pose.bones
    for pb in pose:
        pb.rotation_mode = "XYZ"
    for f in range(frames + 1):
        t = f / frames
        lift = {"Left": max(0.0, math.sin(2 * math.pi * t)),
                "Right": max(0.0, -math.sin(2 * math.pi * t))}
        for side, sx in (("Left", 1), ("Right", -1)):
            pose[P + side + "UpLeg"].rotation_euler = (-math.radians(50) * lift[side], 0, 0)
            pose[P + side + "Leg"].rotation_euler = (math.radians(90) * lift[side], 0, 0)
            pose[P + side + "Foot"].rotation_euler = (-math.radians(20) * lift[side], 0, 0)
            swing = math.radians(30) * math.sin(2 * math.pi * t) * sx
            pose[P + side + "Arm"].rotation_euler = (0, 0, math.radians(-60) * sx)
            pose[P + side + "ForeArm"].rotation_euler = (swing, 0, 0)
            for name in ("UpLeg", "Leg", "Foot", "Arm", "ForeArm"):
                pose[P + side + name].keyframe_insert("rotation_euler", frame=f)
        pose[P + "Spine1"].rotation_euler = (0, math.radians(8) * math.sin(2 * math.pi * t), 0)
        pose[P + "Spine1"].keyframe_insert("rotation_euler", frame=f)
        pose[P + "Head"].rotation_euler = (math.radians(10) * math.sin(4 * math.pi * t), 0, 0)
        pose[P + "Head"].keyframe_insert("rotation_euler", frame=f)
    bpy.context.scene.frame_end = frames


def build(with_mesh=True, rings_big=24, frames=60):
    table = bones()
    data = bpy.data.armatures.new("Armature")
    arm = bpy.data.objects.new("Armature", data)
    bpy.context.scene.collection.objects.link(arm)
    bpy.context.view_layer.objects.active = arm
    bpy.ops.object.mode_set(mode="EDIT")
    for name, head, tail, parent in table:
        b = data.edit_bones.new(name)
        b.head, b.tail = head, tail
        if parent:
            b.parent = data.edit_bones[parent]
            b.use_connect = False
    bpy.ops.object.mode_set(mode="OBJECT")
    if with_mesh:
        build_mesh(arm, table, rings_big)
    key_clip(arm, frames)
    return arm
