"""A glTF through Blender and back (the `verify` round trip, issue 31): import with
io_scene_gltf2, export again as GLB with the exporter's defaults.
    python gltf_roundtrip.py IN.glb OUT.glb"""
import sys, bpy
bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.import_scene.gltf(filepath=sys.argv[1])
bpy.ops.export_scene.gltf(filepath=sys.argv[2], export_format="GLB")
