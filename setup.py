"""The build's one extra step (everything else is in pyproject.toml): the checkout's top-level data folders.

The built-in models (``urdf/``) and the recorded reference data (``reference/``) are edited at
the top of the checkout (docs/models.md); a wheel carries a copy of each as package data,
``armguard/_data/urdf`` and ``armguard/_data/reference``, which ``armguard._resources`` finds
through importlib.resources.  An editable install copies nothing: it reads the checkout's folders.
The sdist carries the folders too (MANIFEST.in), so a wheel built from it has them.
"""

import shutil
from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py

ROOT = Path(__file__).resolve().parent
DATA_FOLDERS = ("urdf", "reference")


class BuildPyWithData(build_py):
    """``build_py``, then ``urdf/`` and ``reference/`` copied to ``<build_lib>/armguard/_data/``."""

    def run(self):
        super().run()
        if getattr(self, "editable_mode", False):
            return
        dest = Path(self.build_lib) / "armguard" / "_data"
        for name in DATA_FOLDERS:
            src = ROOT / name
            if not src.is_dir():
                raise SystemExit(f"armguard build: {src} is missing (the sdist must carry it: MANIFEST.in)")
            shutil.rmtree(dest / name, ignore_errors=True)  # no stale files from an earlier build
            shutil.copytree(src, dest / name, ignore=shutil.ignore_patterns("__pycache__", "*.py[co]", ".*"))


setup(cmdclass={"build_py": BuildPyWithData})
