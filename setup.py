"""pip install of the Python package `parallax`, offline, with Debian's build tools.

    python3 -m venv --system-site-packages .venv && . .venv/bin/activate
    python3 -m pip install .

The extension is built by the project's CMake (the same build as README's test command, in
build/ unless PARALLAX_BUILD_DIR says otherwise, so an existing build is reused) and copied
into the package. Everything comes from Debian packages (scripts/install-deps.sh); there is no
pyproject.toml on purpose, so that pip uses the setuptools and wheel it finds instead of
downloading them into an isolated build environment.
"""

import os
import pathlib
import shutil
import subprocess

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

ROOT = pathlib.Path(__file__).resolve().parent


class CMakeBuild(build_ext):
    """Builds the extension target with CMake and copies it where setuptools wants it."""

    def build_extension(self, ext):
        build_dir = pathlib.Path(os.environ.get("PARALLAX_BUILD_DIR", ROOT / "build"))
        subprocess.check_call(["cmake", "-S", str(ROOT), "-B", str(build_dir), "-G", "Ninja",
                               "-DCMAKE_BUILD_TYPE=Release"])
        subprocess.check_call(["cmake", "--build", str(build_dir), "--target", "parallax_python"])
        built = sorted((build_dir / "python" / "parallax").glob("_parallax*.so"))
        if not built:
            raise RuntimeError(f"{build_dir}: the build made no _parallax extension "
                               "(are pybind11-dev and python3-dev installed?)")
        target = pathlib.Path(self.get_ext_fullpath(ext.name))
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(built[0], target)


setup(
    name="parallax-sfm",
    version="0.1.0",
    description="Incremental Structure from Motion: calibrated cameras and a sparse point "
                "cloud from unordered photos",
    packages=["parallax"],
    package_dir={"parallax": "python/parallax"},
    package_data={"parallax": ["py.typed", "*.pyi"]},
    ext_modules=[Extension("parallax._parallax", sources=[])],
    cmdclass={"build_ext": CMakeBuild},
    python_requires=">=3.9",
    install_requires=["numpy"],
)
