"""Blender's FBX to glTF in one process (the peer in BENCHMARKS.md): import with io_scene_fbx,
export with io_scene_gltf2.   python fbx_to_glb.py IN.fbx OUT.glb"""
import sys, bpy
bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.import_scene.fbx(filepath=sys.argv[1])
bpy.ops.export_scene.gltf(filepath=sys.argv[2], export_format="GLB")
