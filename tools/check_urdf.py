#!/usr/bin/env python
"""Lint a model: ``.venv/bin/python tools/check_urdf.py PATH`` (a .urdf, a sidecar .yaml or a built-in name).

The same as ``armguard check-urdf``; the logic is ``armguard.harness.check_model_files``.
"""

import sys

from armguard.cli import main

if __name__ == "__main__":
    sys.exit(main(["check-urdf", *sys.argv[1:]]))
