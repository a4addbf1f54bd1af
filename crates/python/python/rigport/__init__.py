"""rigport in Python: read character rigs and motion (glTF, USD, FBX, COLLADA, BVH,
ASF/AMC, Pinocchio, CSCI 520), evaluate and skin them into numpy arrays, and write glTF 2.0
and USD, with the same results as the ``rigport`` command line.

    >>> import rigport
    >>> asset = rigport.open("walk.bvh")
    >>> frames = asset.evaluate(fps=30)
    >>> frames.positions.shape          # (frames, vertices, 3)
    >>> asset.write("walk.glb")

Everything is implemented by the Rust crates (``rigport._rigport``); this module only
re-exports it.
"""

from ._rigport import (
    Asset,
    Clip,
    Frames,
    InputError,
    Mesh,
    OutputError,
    Report,
    RigportError,
    RigportWarning,
    UsageError,
    animate,
    bake,
    cloth,
    combine,
    convert,
    footlock,
    ik,
    inspect,
    open,
    render,
    retarget,
    retime,
    sequence,
    skin,
    verify,
)

__all__ = [
    "Asset",
    "Clip",
    "Frames",
    "InputError",
    "Mesh",
    "OutputError",
    "Report",
    "RigportError",
    "RigportWarning",
    "UsageError",
    "animate",
    "bake",
    "cloth",
    "combine",
    "convert",
    "footlock",
    "ik",
    "inspect",
    "open",
    "render",
    "retarget",
    "retime",
    "sequence",
    "skin",
    "verify",
]
