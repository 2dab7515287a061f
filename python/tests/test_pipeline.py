"""The pipeline from Python, end to end on a synthetic scene with exact cameras."""

import filecmp
import json

import numpy as np
import pytest

import parallax

from conftest import SCENE_VIEWS


def test_steps_one_by_one_reconstruct_the_scene(scene_dir, tmp_path):
    database = tmp_path / "database.db"
    counts = []
    extraction = parallax.extract_features(
        scene_dir, database, intrinsics=scene_dir / "K.txt",
        progress=lambda stage, done, total: counts.append((stage, done, total)))
    assert extraction.num_images_found == SCENE_VIEWS
    assert extraction.num_extracted == SCENE_VIEWS
    assert extraction.mean_num_keypoints > 500
    # Progress reached this thread, in order, up to the total.
    assert counts and counts[-1] == ("features", SCENE_VIEWS, SCENE_VIEWS)
    assert [done for _, done, _ in counts] == sorted(done for _, done, _ in counts)

    again = parallax.extract_features(scene_dir, database, intrinsics=scene_dir / "K.txt")
    assert again.num_extracted == 0 and again.num_skipped == SCENE_VIEWS

    matches = parallax.match(database, pairs="exhaustive", seed=5)
    num_pairs = SCENE_VIEWS * (SCENE_VIEWS - 1) // 2
    assert matches.num_pairs == num_pairs
    assert matches.num_verified >= 2 * SCENE_VIEWS
    assert matches.summary()["pairs_considered"] == num_pairs

    models = parallax.map(database, scene_dir, tmp_path / "out", seed=5)
    assert len(models) == 1
    model = models[0]
    assert model.num_reg_images() == SCENE_VIEWS
    assert model.num_points3D() > 500
    assert (tmp_path / "out" / "sparse" / "0" / "images.bin").exists()
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["images_registered"] == SCENE_VIEWS

    # The model extended (as COLMAP's mapper --input_path): every image keeps its pose.
    extended = parallax.map(database, scene_dir, tmp_path / "out2", seed=5,
                            input_model=tmp_path / "out" / "sparse" / "0")
    assert extended[0].num_reg_images() == SCENE_VIEWS
    kept = json.loads((tmp_path / "out2" / "summary.json").read_text())["mapper"]["input_model"]
    assert kept == {"images_kept": SCENE_VIEWS, "images_missing": []}

    metrics = parallax.evaluate(model, scene_dir / "synth_par.txt")
    assert metrics["images_registered_in_gt"] == SCENE_VIEWS
    assert metrics["rotation_error_deg"]["median"] < 0.2
    assert metrics["center_error_relative"]["median"] < 0.005


def test_reconstruct_evaluates_and_reports(reconstruction_dir):
    output, result = reconstruction_dir
    assert len(result.models) == 1
    assert result.models[0].num_reg_images() == SCENE_VIEWS
    assert result.summary["images_registered"] == SCENE_VIEWS
    per_image = result.summary["images"]
    assert all(image["reprojection_error_after_ba_px"] < 1.0 for image in per_image)
    assert result.evaluation["rotation_error_deg"]["median"] < 0.2
    report = parallax.write_report(output)
    assert report.name == "report.html" and report.stat().st_size > 10000


def test_python_and_cli_make_the_same_model(scene_dir, reconstruction_dir, cli, tmp_path):
    output, _ = reconstruction_dir
    run = cli("reconstruct", "--images", scene_dir, "--output", tmp_path, "--intrinsics",
              scene_dir / "K.txt", "--seed", 5, "--ba-threads", 1, "--quiet")
    assert run.returncode == 0, run.stderr
    for name in ("cameras.bin", "images.bin", "points3D.bin"):
        assert filecmp.cmp(output / "sparse" / "0" / name, tmp_path / "sparse" / "0" / name,
                           shallow=False), name


def test_keyword_options_are_the_command_line_flags(tmp_path):
    with pytest.raises(TypeError, match=r"match\(\) got an unexpected keyword argument 'ratoi'"):
        parallax.match(tmp_path / "none.db", ratoi=0.7)
    with pytest.raises(ValueError, match="--ratio"):
        parallax.match(tmp_path / "none.db", ratio=2.0)
    with pytest.raises(ValueError, match="--pairs"):
        parallax.match(tmp_path / "none.db", pairs="everything")
    with pytest.raises(TypeError, match="preemptive takes True or False"):
        parallax.match(tmp_path / "none.db", preemptive=3)
    # Valid flags get as far as the database, which is missing.
    with pytest.raises(FileNotFoundError, match="database does not exist"):
        parallax.match(tmp_path / "none.db", ratio=0.7, preemptive=False, max_error=2)
    names = {option["name"] for option in parallax._parallax._keyword_options("match")}
    assert {"pairs", "ratio", "max_error", "preemptive", "retrieval_neighbors"} <= names
    assert "max_error (float, default 4" in parallax.match.__doc__
    assert "sift_contrast (float" in parallax.reconstruct.__doc__


def test_camera_params_as_a_list(scene_dir, tmp_path):
    K = np.loadtxt(scene_dir / "K.txt")
    result = parallax.extract_features(
        scene_dir, tmp_path / "db.db", camera_model="PINHOLE",
        camera_params=[K[0, 0], K[1, 1], K[0, 2], K[1, 2]], max_features=500)
    assert result.num_extracted == SCENE_VIEWS
    with pytest.raises(ValueError, match="--camera-params: 3 values"):
        parallax.extract_features(scene_dir, tmp_path / "db2.db", camera_model="PINHOLE",
                                  camera_params=[500, 240, 180])


def test_paper_figures_example_runs(scene_dir, tmp_path):
    """examples/paper_figures.py on the synthetic ring: it must produce both figures."""
    import os
    import pathlib
    import subprocess
    import sys
    script = pathlib.Path(__file__).resolve().parents[2] / "examples" / "paper_figures.py"
    run = subprocess.run([sys.executable, str(script), "--images", str(scene_dir), "--output",
                          str(tmp_path)], capture_output=True, text=True, env=os.environ,
                         timeout=600)
    assert run.returncode == 0, run.stdout + run.stderr
    assert f"registered {SCENE_VIEWS}/{SCENE_VIEWS} images" in run.stdout
    for name in ("reprojection_errors.png", "trajectory.png"):
        assert (tmp_path / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_calibrate_on_the_chessboard_photos(tmp_path):
    """The paper's checkerboard calibration from Python (the shared data set; skipped without)."""
    import os
    import pathlib
    data = pathlib.Path(os.environ.get("PARALLAX_DATA", pathlib.Path(__file__).resolve().parents[3]
                                       / "shared" / "data")) / "checkerboard" / "images"
    if not data.is_dir():
        pytest.skip(f"{data}: no checkerboard photos")
    calibration = parallax.calibrate(data, (8, 6), output=tmp_path / "camera.json")
    # 12 photos of the calibrated size 1280 x 960; the others are reported as another size.
    assert calibration["num_used_images"] == 12
    assert (calibration["width"], calibration["height"]) == (1280, 960)
    assert calibration["rms_error_px"] < 0.6
    statuses = {image["status"] for image in calibration["images"]}
    assert "used" in statuses and len(calibration["images"]) == 28
    assert calibration["camera"].model == "OPENCV"
    K = calibration["K"]
    assert K[0, 0] > 0 and abs(K[0, 0] - K[1, 1]) / K[0, 0] < 0.02
    assert 0.3 < K[0, 2] / calibration["width"] < 0.7
    assert json.loads((tmp_path / "camera.json").read_text())
    with pytest.raises(FileNotFoundError, match="image folder does not exist"):
        parallax.calibrate(tmp_path / "none", (8, 6))
