#!/usr/bin/env python
"""The backend harness: ``.venv/bin/python tools/compare.py MODEL --backends analytic,coal [...]``.

The same as ``armguard compare`` (``--help`` lists the options); the logic is ``armguard.harness``.
"""

import sys

from armguard.cli import run_as_script

if __name__ == "__main__":
    sys.exit(run_as_script("compare"))
