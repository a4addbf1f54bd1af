"""Blender's automatic weights (bone heat) for a Pinocchio mesh and skeleton, the peer of
rigport's `rigport_deform::weights::bone_heat` (issue 33; crates/deform/tests/weights_corpus.rs
scores both against Pinocchio's own attachment.out).

    tools/.venv-blender/bin/python tools/blender/auto_weights.py MESH.obj SKELETON.out OUT.txt [MESH SKELETON OUT ...]

Several triples run in one Blender session (one start-up); each starts from an empty scene.

- The mesh is built from the OBJ's `v` and `f` lines with `from_pydata`, not Blender's OBJ
  importer (which splits and reorders vertices): Blender vertex i is OBJ `v` line i, as a
  row of Pinocchio's attachment.out is. Coordinates are kept as they are (no axis change:
  heat does not depend on the axes); the mesh and skeleton share them, as Pinocchio writes
  them.
- The armature has the bones rigport and Pinocchio weight: one bone `bone_<k>` per joint
  k >= 1 of skeleton.out (`index x y z parent`), from its parent's position (head) to its
  own (tail), parented to `bone_<parent>` when the parent is not the root; not connected.
- `parent_set(type='ARMATURE_AUTO')` with the mesh selected and the armature active, as
  Ctrl+P > With Automatic Weights; only this call is timed.

OUT.txt: `# seconds S` (the wall time of the parenting), `# warning TEXT` for each warning
Blender reported (e.g. "Bone Heat Weighting: failed to find solution for one or more
bones": the vertices of such a bone get no weight from it), `# zero_length BONE` for a bone
Blender dropped, then one line per OBJ vertex with J - 1 weights, column k for `bone_<k+1>`
(attachment.out's layout), as Blender stored them (not normalized; Blender's Armature
modifier divides by the row's sum when it deforms; a row of zeros is a vertex left at rest).
"""

import os
import sys
import tempfile
import time

import bpy


def read_obj(path):
    verts, faces = [], []
    with open(path, encoding="utf-8", errors="replace") as f:
        for line in f:
            parts = line.split()
            if not parts:
                continue
            if parts[0] == "v":
                verts.append(tuple(float(x) for x in parts[1:4]))
            elif parts[0] == "f":
                face = []
                for token in parts[1:]:
                    i = int(token.split("/")[0])
                    face.append(i - 1 if i > 0 else len(verts) + i)
                faces.append(face)
    return verts, faces


def read_skeleton(path):
    positions, parents = [], []
    with open(path, encoding="utf-8-sig") as f:
        for line in f:
            parts = line.split()
            if len(parts) != 5:
                continue
            positions.append(tuple(float(x) for x in parts[1:4]))
            parent = int(parts[4])
            # pynocchio's SMPL files write the root as its own parent (rigport reads it as
            # the root, with a warning).
            parents.append(None if parent < 0 or len(parents) == 0 else parent)
    return positions, parents


class Reports:
    """Blender prints an operator's reports to stdout (fd 1) in background mode: capture
    that file descriptor around the call."""

    def __enter__(self):
        sys.stdout.flush()
        self.file = tempfile.TemporaryFile(mode="w+b")
        self.saved = os.dup(1)
        os.dup2(self.file.fileno(), 1)
        return self

    def __exit__(self, *exc):
        sys.stdout.flush()
        os.dup2(self.saved, 1)
        os.close(self.saved)
        self.file.seek(0)
        self.text = self.file.read().decode("utf-8", "replace")
        self.file.close()
        # Echo what was captured (stderr, so OUT parsing never sees it).
        sys.stderr.write(self.text if self.text.endswith("\n") or not self.text else self.text + "\n")


def weigh(mesh_path, skeleton_path, out_path):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    verts, faces = read_obj(mesh_path)
    positions, parents = read_skeleton(skeleton_path)

    mesh = bpy.data.meshes.new("mesh")
    mesh.from_pydata(verts, [], faces)
    mesh.update()
    assert len(mesh.vertices) == len(verts), "from_pydata keeps every vertex"
    mesh_obj = bpy.data.objects.new("mesh", mesh)
    scene.collection.objects.link(mesh_obj)

    arm = bpy.data.armatures.new("skeleton")
    arm_obj = bpy.data.objects.new("skeleton", arm)
    scene.collection.objects.link(arm_obj)
    bpy.context.view_layer.objects.active = arm_obj
    bpy.ops.object.mode_set(mode="EDIT")
    edit = {}
    for k in range(1, len(positions)):
        b = arm.edit_bones.new(f"bone_{k}")
        b.head = positions[parents[k]]
        b.tail = positions[k]
        b.use_deform = True
        edit[k] = b
    for k, b in edit.items():
        if parents[k] not in (None, 0):
            b.parent = edit[parents[k]]
            b.use_connect = False
    bpy.ops.object.mode_set(mode="OBJECT")
    names = [f"bone_{k}" for k in range(1, len(positions))]
    dropped = [n for n in names if n not in arm.bones]

    bpy.ops.object.select_all(action="DESELECT")
    mesh_obj.select_set(True)
    arm_obj.select_set(True)
    bpy.context.view_layer.objects.active = arm_obj
    with Reports() as reports:
        start = time.perf_counter()
        result = bpy.ops.object.parent_set(type="ARMATURE_AUTO")
        seconds = time.perf_counter() - start
    warnings = [
        line.split(":", 1)[1].strip() if line.lower().startswith("warning") else line.strip()
        for line in reports.text.splitlines()
        if "warning" in line.lower() or "failed" in line.lower()
    ]
    if "FINISHED" not in result:
        warnings.append(f"parent_set returned {sorted(result)}")

    column = {n: c for c, n in enumerate(names)}
    group_column = {g.index: column[g.name] for g in mesh_obj.vertex_groups if g.name in column}
    with open(out_path, "w", encoding="utf-8") as out:
        out.write(f"# seconds {seconds:.6f}\n")
        for w in warnings:
            out.write(f"# warning {w}\n")
        for n in dropped:
            out.write(f"# zero_length {n}\n")
        row = [0.0] * len(names)
        for v in mesh.vertices:
            for c in range(len(row)):
                row[c] = 0.0
            for g in v.groups:
                c = group_column.get(g.group)
                if c is not None:
                    row[c] = g.weight
            out.write(" ".join(f"{w:.6g}" for w in row))
            out.write("\n")
    print(f"{mesh_path}: {len(verts)} vertices, {len(names)} bones, {seconds:.3f} s, warnings {warnings}")


def main():
    args = sys.argv[1:]
    if not args or len(args) % 3:
        sys.exit(__doc__)
    for i in range(0, len(args), 3):
        weigh(*args[i : i + 3])


if __name__ == "__main__":
    main()
