#!/usr/bin/env python
"""Lint a model: ``.venv/bin/python tools/check_urdf.py PATH`` (a .urdf, a sidecar .yaml or a built-in name).

The same as ``armguard check-urdf``; the logic is ``armguard.harness.check_model_files``.
"""

import sys

from armguard.cli import run_as_script

if __name__ == "__main__":
    sys.exit(run_as_script("check-urdf"))
