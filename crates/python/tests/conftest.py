"""What the rigport wheel's tests need: the corpus (`../shared/corpus` beside the
repository), the `rigport` CLI to compare with (`RIGPORT_BIN`), and for the optional checks
the bpy venv's Python (`RIGPORT_BLENDER_PYTHON`), a second Python (`RIGPORT_SECOND_PYTHON`)
and the wheel itself (`RIGPORT_WHEEL`). Each test skips with a message when what it needs
is absent, and fails instead when `CI` is set, as the Rust tests do (rigport-testkit).
"""

import os
import subprocess
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[3]
CORPUS = REPO.parent / "shared" / "corpus"


def require(what, value):
    """`value`, or a skip (a failure when CI is set) naming `what` when it is missing."""
    if not value:
        if os.environ.get("CI"):
            pytest.fail(f"{what} is missing and CI is set: this test must run in CI")
        pytest.skip(f"{what} is missing")
    return value


def corpus(rel):
    """A corpus file, or a skip."""
    path = CORPUS / rel
    return require(f"corpus file {path}", path.exists() and path)


def env_file(name):
    """The file an environment variable names, or a skip."""
    value = os.environ.get(name)
    return require(f"${name} (an existing file)", value and Path(value).exists() and Path(value))


@pytest.fixture(scope="session")
def cli():
    """Runs the `rigport` CLI (`RIGPORT_BIN`) with arguments; returns its completed
    process (raises when it fails)."""
    binary = env_file("RIGPORT_BIN")

    def run(*args, check=True):
        done = subprocess.run(
            [str(binary), *map(str, args)], capture_output=True, text=True, timeout=600
        )
        if check and done.returncode != 0:
            raise AssertionError(f"rigport {' '.join(map(str, args))}: exit {done.returncode}\n{done.stderr}")
        return done

    return run
