"""The wheel itself (issue 32): one `cp39-abi3` file that imports and runs under a second
Python minor version, and inside Blender's Python (bpy), where a mesh built from rigport's
frames equals what Blender's own glTF importer shows."""

import ast
import inspect as pyinspect
import json
import os
import subprocess
import sys
import zipfile
from pathlib import Path

import rigport
from conftest import corpus, env_file, require

HERE = Path(__file__).resolve().parent
STUB = HERE.parent / "python" / "rigport" / "_rigport.pyi"
BVH = "4_bvh/cmu_cgspeed__nobuyuki83_delfem2/walk.bvh"
CESIUM_MAN = "5_gltf/khronos_samples__nobuyuki83_delfem2/CesiumMan.glb"


def test_wheel_is_abi3_and_imports_under_another_python(tmp_path):
    wheel = env_file("RIGPORT_WHEEL")
    # name-version-python tag-abi tag-platform.whl
    assert wheel.name.split("-")[2:4] == ["cp39", "abi3"], wheel.name
    other = env_file("RIGPORT_SECOND_PYTHON")
    unpacked = tmp_path / "wheel"
    with zipfile.ZipFile(wheel) as z:
        z.extractall(unpacked)
    script = (
        "import json, sys, rigport\n"
        "listed = json.loads(rigport.inspect(sys.argv[1], json=True).output)\n"
        "print(json.dumps([list(sys.version_info[:2]), len(listed[0]['joints']), rigport.__file__]))\n"
    )
    done = subprocess.run(
        [str(other), "-c", script, str(corpus(BVH))],
        env={**os.environ, "PYTHONPATH": str(unpacked)},
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert done.returncode == 0, done.stderr
    version, joints, where = json.loads(done.stdout.strip().splitlines()[-1])
    assert version[0] == 3 and version[1] != sys.version_info[1], (version, sys.version_info)
    assert version[1] >= 9
    assert joints == len(rigport.open(corpus(BVH)).joints)
    assert where.startswith(str(unpacked)), where
    # And this interpreter runs the same file (the one pip installed from it).
    assert Path(rigport.__file__).parent.joinpath("py.typed").exists()


def test_blender_mesh_at_frame_10_matches_blenders_gltf_importer():
    blender = env_file("RIGPORT_BLENDER_PYTHON")
    man = corpus(CESIUM_MAN)
    done = subprocess.run(
        [str(blender), str(HERE / "blender_cesiumman.py"), str(man), "10"],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert done.returncode == 0, done.stderr[-3000:]
    result = json.loads(done.stdout.strip().splitlines()[-1])
    assert result["vertices"][0] == result["vertices"][1] > 3000, result
    # Frame 10 is a pose, not the rest: the clip has moved the mesh by far more than the
    # tolerance (else the comparison would prove nothing).
    assert result["moved"] > 0.01 * result["diagonal"], result
    assert result["deviation"] <= 1e-5 * result["diagonal"], result


def test_stub_lists_the_module():
    """The `.pyi` names every public name of the module, with the same parameters."""
    tree = ast.parse(STUB.read_text())
    stubbed = {}
    for node in tree.body:
        if isinstance(node, ast.FunctionDef):
            a = node.args
            params = [p.arg for p in a.posonlyargs + a.args + a.kwonlyargs]
            stubbed[node.name] = params
        elif isinstance(node, ast.ClassDef):
            stubbed[node.name] = None
    for name in rigport.__all__:
        assert name in stubbed, f"{name} is not in {STUB.name}"
        thing = getattr(rigport, name)
        if stubbed[name] is not None:
            real = [
                p.name
                for p in pyinspect.signature(thing).parameters.values()
                if p.kind not in (p.VAR_POSITIONAL, p.VAR_KEYWORD)
            ]
            assert real == stubbed[name], f"{name}: {real} != {stubbed[name]}"
        assert thing.__doc__, f"{name} has no docstring"
