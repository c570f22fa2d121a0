#!/usr/bin/env python
"""Regenerate ``reference/models/<name>.json`` + ``.npz`` (coal's answers at the fixed configurations).

Usage: ``.venv/bin/python tools/make_reference.py [NAME ...]`` (default: every model of ``urdf/``
plus panda, ur5 and iiwa).  The logic is ``armguard.harness._reference.make_reference``.
"""

import sys

from armguard.harness import reference_model_names
from armguard.harness._reference import make_reference


def main(argv) -> int:
    names = argv or list(reference_model_names())
    for name in names:
        jp, npz = make_reference(name)
        print(f"{name}: wrote {jp} and {npz}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
