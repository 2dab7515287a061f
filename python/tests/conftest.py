"""Shared fixtures: a small synthetic scene with exact cameras, reconstructed once."""

import os
import pathlib
import subprocess

import pytest

import parallax

# A ring of 20 views 18 degrees apart: every image registers, in seconds per run.
SCENE_VIEWS = 20
SCENE_SIZE = (640, 480)


@pytest.fixture(scope="session", autouse=True)
def quiet_core():
    parallax.set_log_level("warning")


@pytest.fixture(scope="session")
def scene_dir(tmp_path_factory):
    """A synthetic ring of views: images, synth_par.txt, K.txt, gt/."""
    directory = tmp_path_factory.mktemp("scene")
    parallax.synthesize(directory, views=SCENE_VIEWS, image_size=SCENE_SIZE, seed=3)
    return directory


@pytest.fixture(scope="session")
def reconstruction_dir(tmp_path_factory, scene_dir):
    """parallax.reconstruct on the scene, with the known K and the ground truth."""
    output = tmp_path_factory.mktemp("reconstruction")
    result = parallax.reconstruct(
        scene_dir, output, intrinsics=scene_dir / "K.txt", ground_truth=scene_dir / "synth_par.txt",
        seed=5, ba_threads=1)
    return output, result


@pytest.fixture(scope="session")
def cli():
    """Runs the `parallax` binary of the same build."""
    binary = os.environ.get("PARALLAX_BINARY")
    if not binary or not pathlib.Path(binary).exists():
        pytest.skip("PARALLAX_BINARY is not set to the parallax binary")

    def run(*args):
        return subprocess.run([binary, *map(str, args)], capture_output=True, text=True, check=False)

    return run
