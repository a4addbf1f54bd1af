"""Type stubs of rigport's extension module (`rigport._rigport`, re-exported by `rigport`)."""

import os
from typing import Literal, Optional, Sequence, Union

import numpy as np
import numpy.typing as npt

PathLike = Union[str, "os.PathLike[str]"]
#: A command's input: an opened asset (its files, read again with its options), a path,
#: or several paths (read as the CLI reads its inputs).
Inputs = Union["Asset", PathLike, Sequence[PathLike]]
Skinning = Literal["lbs", "dqs"]
RootMotion = Literal["keep", "in-place", "extract"]

class RigportError(Exception):
    """The base of rigport's errors; `str(e)` is the message the CLI prints."""

class InputError(RigportError):
    """An input cannot be read or does not make what was asked (the CLI's exit code 1)."""

    path: Optional[str]
    """The file, when known."""
    line: Optional[int]
    """Its 1-based line, when known."""
    location: Optional[str]
    """The place as printed: `walk.bvh:12:5`, `a.gltf: at /skins/0`, `pose: at /hips`."""

class UsageError(RigportError):
    """The request cannot be carried out as given (the CLI's exit code 2)."""

class OutputError(RigportError):
    """An output cannot be written (the CLI's exit code 3)."""

    path: str
    """The output."""

class RigportWarning(UserWarning):
    """Something lossy or repaired, given to `warnings.warn`. A filter that makes it an
    error refuses a write (nothing is written), as the CLI's deny-warnings does."""

    code: str
    """Its stable code: `W001`..."""
    name: str
    """Its kebab-case name: `weights-renormalized`..."""

class Clip:
    """One clip of an asset."""

    name: str
    duration: float
    """Seconds."""
    times: list[float]
    """The key times in seconds, sorted: the frames `evaluate` samples by default."""

class Mesh:
    """One mesh of an asset, at rest, in the source's unit."""

    index: int
    name: str
    @property
    def positions(self) -> npt.NDArray[np.float32]:
        """V x 3."""
    @property
    def indices(self) -> npt.NDArray[np.uint32]:
        """T x 3 triangles into `positions`."""
    @property
    def normals(self) -> Optional[npt.NDArray[np.float32]]:
        """V x 3, or None."""
    @property
    def uvs(self) -> Optional[npt.NDArray[np.float32]]:
        """V x 2, or None."""
    @property
    def influences(self) -> tuple[npt.NDArray[np.int32], npt.NDArray[np.float32]]:
        """(joints, weights), V x K each, joints indexing `Asset.joints`, zero-padded."""
    @property
    def source_vertex(self) -> npt.NDArray[np.uint32]:
        """Each vertex's vertex in the source file (V)."""

class Frames:
    """Evaluated frames: `rigport eval`'s `.npz` arrays, bit for bit, always with the frame
    axis. The arrays are views of Rust buffers (not copied)."""

    joint_names: list[str]
    skinning: Skinning
    clip: Optional[str]
    """The clip sampled, None for a pose."""
    @property
    def times(self) -> npt.NDArray[np.float32]:
        """F seconds."""
    @property
    def positions(self) -> npt.NDArray[np.float32]:
        """F x V x 3 skinned positions, model space, source vertex order."""
    @property
    def joint_world(self) -> npt.NDArray[np.float32]:
        """F x J x 4 x 4 model-space joint matrices (`M @ [x, y, z, 1]`)."""
    @property
    def skin_matrices(self) -> npt.NDArray[np.float32]:
        """F x J x 4 x 4: `joint_world` times the inverse bind matrices."""
    @property
    def rest_positions(self) -> npt.NDArray[np.float32]:
        """V x 3."""
    @property
    def influences(self) -> tuple[npt.NDArray[np.int32], npt.NDArray[np.float32]]:
        """(joints, weights) skinned, V x K each, zero-padded."""
    @property
    def rows(self) -> list[npt.NDArray[np.uint32]]:
        """Per mesh, per vertex of `Mesh.positions`: its row in `positions`;
        `positions[f][rows[m]]` is mesh m posed, to index with `Mesh.indices`."""
    def __len__(self) -> int: ...

class Report:
    """What a command did: the lines the CLI prints."""

    log: list[str]
    summary: Optional[str]
    output: Optional[str]
    """The command's product when it is text (a JSON report, `inspect`'s listing)."""
    notices: list[str]
    warnings: list[str]
    notes: list[str]
    passed: Optional[bool]
    """`verify`'s verdict; None for other commands."""

class Asset:
    """A rig read as `rigport` reads it. Open one with `rigport.open`."""

    @property
    def joints(self) -> list[str]:
        """Joint names, parents first."""
    @property
    def parents(self) -> npt.NDArray[np.int32]:
        """J parent indices, -1 for a root."""
    @property
    def rest_local(self) -> npt.NDArray[np.float32]:
        """J x 4 x 4 rest transforms relative to the parent (`M @ [x, y, z, 1]`)."""
    @property
    def meshes(self) -> list[Mesh]: ...
    @property
    def clips(self) -> list[Clip]: ...
    @property
    def meters_per_unit(self) -> Optional[float]:
        """Metres per unit the source states, or None."""
    @property
    def up_axis(self) -> Literal["Y", "Z"]: ...
    @property
    def label(self) -> str: ...
    @property
    def warnings(self) -> list[str]:
        """The import's warnings, as printed (`warning[W001]: ...`)."""
    @property
    def notes(self) -> list[str]: ...
    def evaluate(
        self,
        clip: Optional[str] = None,
        times: Optional[Sequence[float]] = None,
        fps: Optional[float] = None,
        skinning: Optional[Skinning] = None,
        max_influences: Optional[int] = None,
    ) -> Frames:
        """Samples a clip (default: the first; none: the rest pose) at `times`, at `fps`,
        or at its key times, and skins every frame, as `rigport eval`."""
    def pose(
        self,
        pose: dict[str, dict[str, object]],
        skinning: Optional[Skinning] = None,
        max_influences: Optional[int] = None,
    ) -> Frames:
        """One frame posed by a POSE dictionary: joint -> {"quat": [x, y, z, w]} or
        {"euler_deg": [x, y, z], "order": "xyz"}, in the joint's rest frame."""
    def write(
        self,
        path: PathLike,
        *,
        max_influences: Optional[int] = None,
        influences_fit: Optional[Literal["truncate", "refit"]] = None,
        reduce_tolerance: Optional[float] = None,
        reduce: bool = False,
        reduce_cubic: bool = False,
        compress: Optional[Literal["none", "meshopt"]] = None,
        skinning: Optional[Skinning] = None,
        up_axis: Optional[Literal["Y", "Z", "y", "z"]] = None,
        meters_per_unit: Optional[float] = None,
        root_motion: RootMotion = "keep",
        root_yaw: bool = False,
        root_window: Optional[float] = None,
        json: bool = False,
    ) -> Report:
        """Writes .glb, .gltf, .usda, .usdc or .usdz (by extension): `rigport convert`'s
        bytes. `reduce` (or a `reduce_tolerance`) reduces the keys (`reduce_cubic`: also
        into CUBICSPLINE tracks, core glTF only); `compress="meshopt"` compresses a glTF;
        with `json`, `Report.output` is the reduction's JSON report."""

def open(
    *paths: PathLike,
    mesh: Optional[PathLike] = None,
    skeleton: Optional[PathLike] = None,
    attachment: Optional[PathLike] = None,
    motion: Sequence[PathLike] = (),
    amc_fps: Optional[float] = None,
    bone_mesh: bool = True,
    weights: Optional[Literal["auto"]] = None,
    input_units: Optional[str] = None,
    force_units: bool = False,
    max_memory: Optional[int] = None,
) -> Asset:
    """Opens any input the CLI reads, detected the same way, with its input options."""

# The commands: the CLI's options as keyword arguments. `**options` are `Asset.write`'s
# (root motion where the command has it).
def convert(input: Inputs, output: PathLike, *, json: bool = False, **options: object) -> Report: ...
def inspect(input: Inputs, *, json: bool = False) -> Report: ...
def animate(input: Inputs, keys: PathLike, output: PathLike, **options: object) -> Report: ...
def sequence(
    input: Inputs,
    output: PathLike,
    *,
    crossfade: int = 0,
    loop: bool = False,
    fps: Optional[float] = None,
    **options: object,
) -> Report: ...
def retime(
    input: Inputs,
    output: PathLike,
    *,
    frames: Optional[int] = None,
    fps: Optional[float] = None,
    speed: Optional[float] = None,
    warp: Optional[str] = None,
    reverse: bool = False,
    trim: Optional[str] = None,
    clip: Optional[str] = None,
    **options: object,
) -> Report: ...
def bake(
    input: Inputs,
    output: PathLike,
    *,
    skinning: Optional[Skinning] = None,
    clip: Optional[str] = None,
    fps: Optional[float] = None,
    threshold: Optional[float] = None,
    correctives: Optional[int] = None,
    max_influences: int = 4,
) -> Report: ...
def retarget(
    input: Inputs,
    onto: Inputs,
    output: PathLike,
    *,
    map: Optional[PathLike] = None,
    clip: Optional[str] = None,
    plant_feet: bool = False,
    match_hands: bool = False,
    allow_partial: bool = False,
    json: bool = False,
    **options: object,
) -> Report: ...
def combine(
    inputs: Inputs,
    output: PathLike,
    *,
    names: Sequence[tuple[str, str]] = (),
    map: Optional[PathLike] = None,
    plant_feet: bool = False,
    fps: Optional[float] = None,
    json: bool = False,
    **options: object,
) -> Report: ...
def ik(
    input: Inputs,
    handles: PathLike,
    output: PathLike,
    *,
    solver: Literal["dls", "pinv", "transpose", "ccd", "fabrik"] = "dls",
    fps: Optional[float] = None,
    tolerance: Optional[float] = None,
    max_iterations: int = 100,
    lambda_: Optional[float] = None,
    substep: Optional[float] = None,
    free_root: bool = False,
    json: bool = False,
    **options: object,
) -> Report: ...
def footlock(
    input: Inputs,
    output: PathLike,
    *,
    clip: Optional[str] = None,
    feet: Sequence[str] = (),
    height: Optional[float] = None,
    speed: Optional[float] = None,
    blend: Optional[float] = None,
    pin_first: bool = False,
    max_stretch: Optional[float] = None,
    soft: Optional[float] = None,
    max_knee_speed: Optional[float] = None,
    json: bool = False,
    **options: object,
) -> Report: ...
def cloth(
    input: Inputs,
    garment: str,
    output: PathLike,
    *,
    clip: Optional[str] = None,
    pin_vertices: Sequence[int] = (),
    pin_below: Optional[float] = None,
    pin_above: Optional[float] = None,
    fps: Optional[float] = None,
    seconds: Optional[float] = None,
    substeps: Optional[int] = None,
    thickness: Optional[float] = None,
    preroll: Optional[float] = None,
    collide_all: bool = False,
    allow_unstable: bool = False,
    json: bool = False,
    targets: Optional[int] = None,
) -> Report: ...
def render(
    input: Inputs,
    output: PathLike,
    *,
    clip: Optional[str] = None,
    fps: Optional[float] = None,
    frames: Optional[str] = None,
    size: str = "512x512",
    view: Literal["front", "side", "top", "three-quarter"] = "front",
    camera: Literal["ortho", "perspective"] = "ortho",
    handles: Optional[PathLike] = None,
    skinning: Optional[Literal["lbs", "dqs", "both"]] = None,
    skeleton: bool = True,
    frame_counter: bool = True,
) -> Report: ...
def skin(
    input: Inputs,
    output: PathLike,
    *,
    skeleton_offset: Optional[tuple[float, float, float]] = None,
    skeleton_scale: Optional[float] = None,
    **options: object,
) -> Report:
    """Automatic weights (bone heat) for a mesh and a skeleton; `.out` writes a Pinocchio
    `attachment.out`, anything else the rig as `convert` writes it."""

def verify(
    reference: PathLike,
    candidate: PathLike,
    *,
    motion: Sequence[PathLike] = (),
    clip: Optional[str] = None,
    all_clips: bool = False,
    fps: Optional[float] = None,
    at_keys: bool = False,
    tol: Optional[float] = None,
    json: bool = False,
    picture: Optional[PathLike] = None,
) -> Report:
    """Whether `candidate` moves as `reference` does, within `tol`: `Report.passed`."""
