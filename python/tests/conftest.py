"""Shared fixtures: the bundled bodies (fixtures/synth) and the `symcorr` command built from the
same checkout (for comparisons with the command line's outputs)."""

import json
import subprocess
from pathlib import Path

import pytest

import symcorr

REPO = Path(__file__).resolve().parents[2]
BODIES = REPO / "fixtures" / "synth" / "bodies"
SCAN = REPO / "fixtures" / "synth" / "scan"
RECORDING = REPO / "fixtures" / "synth" / "recording"


def mesh_path(name):
    return BODIES / "meshes" / f"{name}.ply"


def joints_path(name):
    return BODIES / "joints" / f"{name}.json"


def body(name):
    """(vertices, faces, joints) of a bundled body."""
    v, f = symcorr.read_mesh(mesh_path(name))
    return v, f, symcorr.read_joints(joints_path(name))


@pytest.fixture(scope="session")
def rest():
    return body("s0_rest")


@pytest.fixture(scope="session")
def tpose():
    return body("s1_t-pose")


@pytest.fixture(scope="session")
def cli():
    """Path of the `symcorr` binary of this checkout (cargo builds it if needed, dev profile)."""
    out = subprocess.run(
        ["cargo", "build", "-q", "-p", "symcorr", "--bin", "symcorr", "--message-format=json"],
        cwd=REPO, check=True, capture_output=True, text=True,
    ).stdout
    for line in out.splitlines():
        msg = json.loads(line)
        if msg.get("reason") == "compiler-artifact" and msg.get("executable") \
                and msg["target"]["name"] == "symcorr":
            return msg["executable"]
    raise RuntimeError("cargo build did not report the symcorr binary")
