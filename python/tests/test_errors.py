"""Bad input crosses into Python as the right exception with the command line's message; a
Ctrl-C stops a long call cleanly and the same call resumes."""

import os
import subprocess
import sys
import textwrap

import pytest

import parallax


def test_missing_files_raise_file_not_found(tmp_path, reconstruction_dir):
    with pytest.raises(FileNotFoundError, match=f"{tmp_path / 'none'}: image folder does not exist"):
        parallax.reconstruct(tmp_path / "none", tmp_path / "out")
    with pytest.raises(FileNotFoundError, match="database does not exist"):
        parallax.match(tmp_path / "missing.db")
    with pytest.raises(FileNotFoundError, match="model folder does not exist"):
        parallax.read_model(tmp_path / "no-model")
    with pytest.raises(FileNotFoundError, match="no-model: model folder does not exist"):
        parallax.map(reconstruction_dir[0] / "database.db", tmp_path, tmp_path / "out",
                     input_model=tmp_path / "no-model")
    with pytest.raises(FileNotFoundError, match="no such file or folder"):
        parallax.evaluate(parallax.Reconstruction(), tmp_path / "gt.txt")


def test_malformed_input_raises_value_error(scene_dir, tmp_path):
    bad_k = tmp_path / "K.txt"
    bad_k.write_text("1 2 3\n")
    with pytest.raises(ValueError, match=f"{bad_k}: expected a 3x3 matrix"):
        parallax.extract_features(scene_dir, tmp_path / "db.db", intrinsics=bad_k)
    (tmp_path / "empty").mkdir()
    with pytest.raises(ValueError, match="no COLMAP model here"):
        parallax.read_model(tmp_path / "empty")
    with pytest.raises(ValueError, match="unknown layout 'spiral'"):
        parallax.synthesize(tmp_path / "synth", layout="spiral")


def test_ctrl_c_stops_a_call_cleanly_and_the_rerun_resumes(tmp_path):
    """A child process starts extraction on 40 views, gets SIGINT after the first image, and
    raises KeyboardInterrupt; the database keeps the images done, and a rerun does the rest."""
    scene = tmp_path / "scene"
    parallax.synthesize(scene, views=40, image_size=(320, 240), seed=1)
    database = tmp_path / "database.db"
    script = textwrap.dedent(f"""
        import os, signal, sys
        import parallax
        parallax.set_log_level("warning")
        sent = []
        def progress(stage, done, total):
            if done >= 1 and not sent:
                sent.append(done)
                os.kill(os.getpid(), signal.SIGINT)
        try:
            parallax.extract_features({str(scene)!r}, {str(database)!r}, threads=1,
                                      progress=progress)
        except KeyboardInterrupt:
            print("interrupted")
            sys.exit(3)
        print("finished")
    """)
    child = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                           env=os.environ, timeout=300)
    assert child.returncode == 3, child.stdout + child.stderr
    assert "interrupted" in child.stdout
    rerun = parallax.extract_features(scene, database)
    assert 1 <= rerun.num_skipped < 40
    assert rerun.num_skipped + rerun.num_extracted == 40
