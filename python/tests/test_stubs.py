"""The type stubs list every keyword option the pipeline functions take."""

import importlib.util
import pathlib

import parallax

PYTHON_DIR = pathlib.Path(__file__).resolve().parents[1]


def test_committed_stubs_are_current():
    spec = importlib.util.spec_from_file_location("generate_stubs", PYTHON_DIR / "generate_stubs.py")
    generate_stubs = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(generate_stubs)
    committed = (PYTHON_DIR / "parallax" / "__init__.pyi").read_text()
    assert committed == generate_stubs.stubs(), (
        "python/parallax/__init__.pyi is stale: run "
        "PYTHONPATH=build/python python3 python/generate_stubs.py")


def test_every_public_name_has_a_stub():
    stub = (PYTHON_DIR / "parallax" / "__init__.pyi").read_text()
    public = [name for name in dir(parallax) if not name.startswith("_")]
    missing = [name for name in public
               if f"def {name}(" not in stub and f"class {name}" not in stub
               and f"{name}:" not in stub]
    assert not missing, missing
