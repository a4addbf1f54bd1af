"""The rigport wheel against the CLI on the real corpus (issue 32): `open` + `evaluate`
equal `rigport eval`'s `.npz` bit for bit, `write` and the command functions write the CLI's
bytes, every error class carries its attributes, warnings reach Python's `warnings`, and
the frames reach numpy without a copy."""

import json
import warnings

import numpy as np
import pytest

import rigport
from conftest import REPO, corpus

PINOCCHIO = "1_pinocchio/berkeley_cs184__severus-snape_mobius-ants/human_model1/"
BVH = "4_bvh/cmu_cgspeed__nobuyuki83_delfem2/walk.bvh"
GLTF = "5_gltf/khronos_samples__nobuyuki83_delfem2/CesiumMan.glb"
USD = "6_usd/openusd_usdskel__PixarAnimationStudios/testUsdSkelBakeSkinning/dqs.usda"

# Per-frame arrays: the `.npz` gives them a frame axis only for a clip.
PER_FRAME = ("positions", "joint_world", "skin_matrices")


def pinocchio():
    folder = corpus(PINOCCHIO)
    return [folder / "Model1.obj", folder / "skeleton.out", folder / "attachment.out"]


def same_bits(ours, theirs, what):
    """Equal bit for bit: same dtype family, same shape, same bytes."""
    ours, theirs = np.asarray(ours), np.asarray(theirs)
    assert ours.shape == theirs.shape, f"{what}: shape {ours.shape} != {theirs.shape}"
    if theirs.dtype.kind == "U":
        assert ours.tolist() == theirs.tolist(), what
        return
    assert ours.dtype == theirs.dtype, f"{what}: dtype {ours.dtype} != {theirs.dtype}"
    if ours.tobytes() != theirs.tobytes():
        bad = np.flatnonzero(ours.ravel().view(np.uint8) != theirs.ravel().view(np.uint8))
        pytest.fail(f"{what}: {bad.size} bytes differ, first at byte {bad[0]}")


def assert_frames_equal_npz(frames, npz, clip):
    """`frames` (from `evaluate` or `pose`) against `rigport eval`'s `.npz`."""
    data = np.load(npz)
    for name in PER_FRAME:
        ours = getattr(frames, name)
        same_bits(ours if clip else ours[0], data[name], name)
    if clip:
        same_bits(frames.times, data["times"], "times")
        assert frames.clip is not None
    same_bits(frames.rest_positions, data["rest_positions"], "rest_positions")
    joints, weights = frames.influences
    same_bits(joints, data["influence_joints"], "influence_joints")
    same_bits(weights, data["influence_weights"], "influence_weights")
    assert frames.joint_names == data["joint_names"].tolist()
    assert [frames.skinning] == data["skinning"].tolist()


@pytest.mark.parametrize(
    "name, files, kwargs, flags",
    [
        ("bvh", lambda: [corpus(BVH)], {"fps": 24.0}, ["--fps", "24"]),
        ("gltf", lambda: [corpus(GLTF)], {}, []),
        ("gltf-dqs", lambda: [corpus(GLTF)], {"skinning": "dqs", "max_influences": 2},
         ["--skinning", "dqs", "--max-influences", "2"]),
        ("usd", lambda: [corpus(USD)], {}, []),
    ],
)
def test_evaluate_equals_eval_npz(tmp_path, cli, name, files, kwargs, flags):
    files = files()
    npz = tmp_path / f"{name}.npz"
    cli("eval", *files, *flags, "-o", npz)
    frames = rigport.open(*files).evaluate(**kwargs)
    assert len(frames) > 1, "a clip of several frames"
    assert_frames_equal_npz(frames, npz, clip=True)


def test_pinocchio_rest_and_pose_equal_eval_npz(tmp_path, cli):
    files = pinocchio()
    asset = rigport.open(*files)
    assert asset.clips == [] and len(asset.joints) == 18
    # Rest pose: no clip.
    npz = tmp_path / "rest.npz"
    cli("eval", *files, "-o", npz)
    assert_frames_equal_npz(asset.evaluate(), npz, clip=False)
    # A pose: the same dictionary as a POSE.json.
    pose = {"bone_1": {"euler_deg": [0, 0, 30]}, "bone_5": {"quat": [0, 0.3827, 0, 0.9239]}}
    pose_file = tmp_path / "pose.json"
    pose_file.write_text(json.dumps(pose))
    npz = tmp_path / "pose.npz"
    cli("eval", *files, "--pose", pose_file, "-o", npz)
    posed = asset.pose(pose)
    assert_frames_equal_npz(posed, npz, clip=False)
    moved = np.abs(posed.positions - asset.evaluate().positions).max()
    assert moved > 1e-3, "the pose moves the mesh"


def test_evaluate_at_given_times(tmp_path):
    asset = rigport.open(corpus(BVH))
    clip = asset.clips[0]
    assert clip.duration > 0 and len(clip.times) > 2
    times = [clip.times[0], clip.times[1], clip.times[5]]
    picked = asset.evaluate(times=times)
    every = asset.evaluate()
    same_bits(picked.times, np.array(times, dtype=np.float32), "times")
    same_bits(picked.positions, every.positions[[0, 1, 5]], "positions at key times")


@pytest.mark.parametrize(
    "name, files, out, kwargs, flags",
    [
        ("bvh-glb", lambda: [corpus(BVH)], "walk.glb", {}, []),
        ("gltf-usda", lambda: [corpus(GLTF)], "man.usda",
         {"up_axis": "Z", "meters_per_unit": 0.01, "skinning": "dqs"},
         ["--up-axis", "z", "--meters-per-unit", "0.01", "--skinning", "dqs"]),
        ("pinocchio-glb", pinocchio, "human.glb", {"max_influences": 2},
         ["--max-influences", "2"]),
        ("usd-usdz", lambda: [corpus(USD)], "arm.usdz", {}, []),
        ("bvh-in-place", lambda: [corpus(BVH)], "walk.gltf", {"root_motion": "in-place"},
         ["--root-motion", "in-place"]),
        ("gltf-meshopt", lambda: [corpus(GLTF)], "man.glb", {"reduce": True, "compress": "meshopt"},
         ["--reduce-tolerance", "--compress", "meshopt"]),
        ("bvh-reduced", lambda: [corpus(BVH)], "walk.glb", {"reduce_tolerance": 0.05},
         ["--reduce-tolerance", "0.05"]),
        ("bvh-cubic", lambda: [corpus(BVH)], "walk.glb", {"reduce": True, "reduce_cubic": True},
         ["--reduce-tolerance", "--reduce-cubic"]),
    ],
)
def test_write_equals_convert(tmp_path, cli, name, files, out, kwargs, flags):
    files = files()
    theirs = tmp_path / "cli" / out
    ours = tmp_path / "py" / out
    theirs.parent.mkdir()
    ours.parent.mkdir()
    cli("convert", *files, *flags, "-o", theirs)
    report = rigport.open(*files).write(ours, **kwargs)
    assert report.log and report.log[0].startswith("wrote ")
    assert ours.read_bytes() == theirs.read_bytes()
    if out.endswith(".gltf"):
        assert ours.with_suffix(".bin").read_bytes() == theirs.with_suffix(".bin").read_bytes()


def test_commands_equal_cli(tmp_path, cli):
    bvh = corpus(BVH)
    # retime: the clip at half speed.
    cli("retime", bvh, "--speed", "0.5", "-o", tmp_path / "cli.glb")
    rigport.retime(bvh, tmp_path / "py.glb", speed=0.5)
    assert (tmp_path / "py.glb").read_bytes() == (tmp_path / "cli.glb").read_bytes()
    # convert as a function, given an opened asset.
    cli("convert", bvh, "--max-influences", "1", "-o", tmp_path / "cli.usda")
    rigport.convert(rigport.open(bvh), tmp_path / "py.usda", max_influences=1)
    assert (tmp_path / "py.usda").read_bytes() == (tmp_path / "cli.usda").read_bytes()
    # inspect's JSON listing.
    listed = json.loads(rigport.inspect(bvh, json=True).output)
    assert listed == json.loads(cli("inspect", bvh, "--json").stdout)
    assert listed[0]["joints"]


def test_arrays_are_views_of_rust_buffers():
    frames = rigport.open(corpus(GLTF)).evaluate()
    positions = frames.positions
    # The array does not own its memory: its base is the Rust buffer's keeper.
    assert not positions.flags.owndata
    assert type(positions.base).__name__ == "PySliceContainer"
    # Every access is the same array over the same memory: nothing copied per access.
    assert frames.positions is positions
    address = positions.__array_interface__["data"][0]
    assert frames.positions.__array_interface__["data"][0] == address
    assert positions.flags.c_contiguous and positions.dtype == np.float32
    for name in ("joint_world", "skin_matrices", "times"):
        assert type(getattr(frames, name).base).__name__ == "PySliceContainer", name
    # Kept alive by the array alone.
    del frames
    assert np.isfinite(positions).all()


def test_asset_data(tmp_path):
    asset = rigport.open(*pinocchio())
    parents = asset.parents
    assert parents.dtype == np.int32 and parents[0] == -1
    assert all(p < i for i, p in enumerate(parents))
    assert asset.rest_local.shape == (18, 4, 4)
    np.testing.assert_array_equal(asset.rest_local[:, 3], np.tile([0, 0, 0, 1], (18, 1)))
    (mesh,) = asset.meshes
    assert mesh.positions.shape[1] == 3 and mesh.indices.shape[1] == 3
    assert mesh.indices.max() < len(mesh.positions)
    joints, weights = mesh.influences
    assert joints.shape == weights.shape == (len(mesh.positions), joints.shape[1])
    np.testing.assert_allclose(weights.sum(axis=1), 1.0, atol=1e-5)
    assert asset.up_axis == "Y" and asset.meters_per_unit is None
    # A mesh's own vertices at rest, through `rows`, are the evaluated rest positions.
    rest = asset.evaluate()
    # (rest skinning rounds: within a few ulps)
    np.testing.assert_allclose(rest.positions[0][rest.rows[0]], mesh.positions, atol=1e-5)
    # The mesh's influences are the dump's, row for row.
    dumped_joints, dumped_weights = rest.influences
    same_bits(dumped_joints[rest.rows[0]], joints, "influence joints")
    same_bits(dumped_weights[rest.rows[0]], weights, "influence weights")
    gltf = rigport.open(corpus(GLTF))
    assert gltf.meters_per_unit == 1.0 and gltf.clips[0].name


def test_input_error_has_location(tmp_path):
    bad = tmp_path / "bad.bvh"
    bad.write_text("HIERARCHY\nROOT hips\n{\n  OFSET 0 0 0\n}\n")
    with pytest.raises(rigport.InputError) as caught:
        rigport.open(bad)
    e = caught.value
    assert e.path == str(bad)
    assert e.line == 4
    assert e.location.startswith(f"{bad}:4")
    assert str(e).startswith(e.location)
    assert isinstance(e, rigport.RigportError)
    # A pose naming no joint of the rig: the dictionary's JSON path.
    with pytest.raises(rigport.InputError) as caught:
        rigport.open(corpus(BVH)).pose({"no_such_joint": {"quat": [0, 0, 0, 1]}})
    assert caught.value.location == "pose: at /no_such_joint"
    assert caught.value.line is None


def test_usage_and_output_errors(tmp_path):
    asset = rigport.open(corpus(BVH))
    with pytest.raises(rigport.UsageError, match=r"\.usd"):
        asset.write(tmp_path / "walk.usd")
    with pytest.raises(rigport.UsageError, match="skinning"):
        asset.evaluate(skinning="linear")
    with pytest.raises(rigport.UsageError, match="not both"):
        asset.evaluate(times=[0.1], fps=30.0)
    with pytest.raises(rigport.InputError, match="sample time NaN"):
        asset.evaluate(times=[float("nan")])
    with pytest.raises(rigport.UsageError, match="input_units"):
        rigport.open(corpus(BVH), input_units="furlongs")
    with pytest.raises(rigport.UsageError, match="one of"):
        rigport.retime(corpus(BVH), tmp_path / "a.glb", speed=2.0, reverse=True)
    missing = tmp_path / "no" / "such" / "folder" / "walk.glb"
    with pytest.raises(rigport.OutputError) as caught:
        asset.write(missing)
    assert caught.value.path == str(missing)
    assert not missing.exists()


def test_warnings_go_through_python(tmp_path):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        asset = rigport.open(corpus(GLTF))
    codes = [w.message.code for w in caught if issubclass(w.category, rigport.RigportWarning)]
    assert "W001" in codes, codes
    assert asset.warnings and asset.warnings[0].startswith("warning[W001]")
    # A filter that turns warnings into errors refuses a lossy write (the CLI's
    # deny-warnings): the warning is raised and nothing is written.
    out = tmp_path / "two.glb"
    with warnings.catch_warnings():
        warnings.simplefilter("error", rigport.RigportWarning)
        with pytest.raises(rigport.RigportWarning) as raised:
            asset.write(out, max_influences=1)
    assert raised.value.code == "W002", raised.value
    assert not out.exists()


def test_evaluate_releases_the_gil():
    """While one thread evaluates, another runs Python: the longest pause the other thread
    sees is a small part of the evaluation (holding the GIL would pause it throughout)."""
    import threading
    import time

    asset = rigport.open(corpus(GLTF))
    start = time.perf_counter()
    asset.evaluate(fps=60.0)
    alone = time.perf_counter() - start
    assert alone > 0.05, f"the evaluation is too short to tell ({alone:.3f} s)"
    worker = threading.Thread(target=asset.evaluate, kwargs={"fps": 60.0})
    ticks = [time.perf_counter()]
    worker.start()
    while worker.is_alive():
        ticks.append(time.perf_counter())
    worker.join()
    longest = max(b - a for a, b in zip(ticks, ticks[1:]))
    assert longest < 0.5 * alone, f"paused {longest:.3f} s of a {alone:.3f} s evaluation"


@pytest.mark.parametrize(
    "command, source, kwargs, flags, out",
    [
        ("footlock", BVH, {"pin_first": True}, ["--pin-first"], "locked.glb"),
        ("sequence", BVH, {"crossfade": 2, "loop": True}, ["--crossfade", "2", "--loop"], "seq.glb"),
        ("bake", GLTF, {"fps": 10.0, "skinning": "dqs"}, ["--fps", "10", "--skinning", "dqs"], "baked.glb"),
        ("render", GLTF, {"size": "64x48", "frames": "0..3", "view": "three-quarter"},
         ["--size", "64x48", "--frames", "0..3", "--view", "three-quarter"], "man.gif"),
    ],
)
def test_command_functions_write_the_cli_bytes(tmp_path, cli, command, source, kwargs, flags, out):
    source = corpus(source)
    # An opened asset carries its input options (centimetres for the BVH, which states no
    # unit) to the command.
    units = {"input_units": "cm"} if source.suffix == ".bvh" else {}
    asset = rigport.open(source, **units)
    unit_flags = ["--input-units", "cm"] if units else []
    cli(command, source, *unit_flags, *flags, "-o", tmp_path / f"cli-{out}")
    report = getattr(rigport, command)(asset, tmp_path / f"py-{out}", **kwargs)
    assert isinstance(report, rigport.Report)
    assert (tmp_path / f"py-{out}").read_bytes() == (tmp_path / f"cli-{out}").read_bytes()


def test_verify_passes_on_a_written_copy(tmp_path):
    gltf = corpus(GLTF)
    copy = tmp_path / "copy.usda"
    rigport.open(gltf).write(copy)
    verdict = rigport.verify(gltf, copy, at_keys=True)
    assert verdict.passed is True, verdict.summary
    moved = tmp_path / "moved.glb"
    rigport.retime(gltf, moved, speed=2.0)
    assert rigport.verify(gltf, moved, at_keys=True).passed is False


ARM_WITH_CLOTH = "6_usd/ustc_cg_24_hw10__USTC-CG/arm_with_cloth.usda"
AMC_SKELETON = "3_acclaim_asf_amc/usc_csci520_mocapPlayer__shreyabhaumik/07-walk.asf"
AMC_MOTION = "3_acclaim_asf_amc/usc_csci520_mocapPlayer__shreyabhaumik/07_05-walk.amc"
BRANCH = REPO / "fixtures" / "pinocchio"


def test_rig_commands_write_the_cli_bytes(tmp_path, cli):
    """retarget, combine, ik, cloth and skin: the function with keyword options writes the
    bytes the CLI writes with the same flags."""
    rig = pinocchio()
    bvh = corpus(BVH)
    asf, amc = corpus(AMC_SKELETON), corpus(AMC_MOTION)
    handles = REPO / "fixtures" / "ik" / "pinocchio_one_hand_reach.json"
    runs = [
        ("retarget.glb", ["retarget", bvh, "--onto", *rig, "--plant-feet"],
         lambda out: rigport.retarget(bvh, rig, out, plant_feet=True)),
        # combine's rig is its first input: the rig's folder.
        ("combine.glb", ["combine", rig[0].parent, asf, amc, "--fps", "30"],
         lambda out: rigport.combine([rig[0].parent, asf, amc], out, fps=30.0)),
        ("ik.usda", ["ik", *rig, "--handles", handles, "--solver", "fabrik"],
         lambda out: rigport.ik(rig, handles, out, solver="fabrik")),
        ("cloth.glb", ["cloth", corpus(ARM_WITH_CLOTH), "--garment", "Grid", "--seconds", "0.5"],
         lambda out: rigport.cloth(corpus(ARM_WITH_CLOTH), "Grid", out, seconds=0.5)),
        ("attachment.out", ["skin", BRANCH / "branch.obj", BRANCH / "branch_skeleton.out"],
         lambda out: rigport.skin([BRANCH / "branch.obj", BRANCH / "branch_skeleton.out"], out)),
    ]
    for out, flags, call in runs:
        theirs, ours = tmp_path / f"cli-{out}", tmp_path / f"py-{out}"
        cli(*flags, "-o", theirs)
        report = call(ours)
        assert isinstance(report, rigport.Report), out
        assert any(line.startswith("wrote ") for line in report.log), (out, report.log)
        assert ours.read_bytes() == theirs.read_bytes(), out
