#!/usr/bin/env python
"""Write a scene (a built-in name or a YAML scene file) as urdf/<system>/ files (docs/models.md).

    python tools/dh_to_urdf.py hermes --out urdf/hermes/
    python tools/dh_to_urdf.py path/to/cell.yaml --out urdf/cell/ --name cell

The logic is armguard.model.export.export_scene; this script only parses the arguments.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("scene", help="a built-in scene name (ranger, hermes, ...) or a .yaml scene file")
    parser.add_argument("--out", required=True, type=Path, help="the folder to write (created if missing)")
    parser.add_argument("--name", default=None, help="file stem and robot name (default: the scene's name)")
    args = parser.parse_args(argv)

    import armguard
    from armguard.model.export import export_scene
    from armguard.models import builtin_path

    source = builtin_path(args.scene) or Path(args.scene)
    if not source.is_file():
        parser.error(f"{args.scene!r} is neither a built-in scene nor a scene file")
    try:
        scene = armguard.load_scene(str(source))
        paths = export_scene(scene, args.out, name=args.name, source=source)
    except armguard.ArmguardError as exc:  # a file refused: its message, located, not a traceback
        print(f"error: {exc}", file=sys.stderr)
        return 3
    for key in ("urdf", "srdf", "yaml"):
        print(paths[key])
    print(f"{len(paths['meshes'])} meshes in {args.out / 'meshes'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
