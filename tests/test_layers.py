"""The layers contract (pyproject.toml, run by `make test` through lint-imports) and its guide agree.

lint-imports checks the imports; these tests check what it cannot: that every subpackage of
armguard has a layer (so that a new one is placed before it is used) and that
docs/architecture.md draws the same layers, in the same order, as the contract.
"""

from __future__ import annotations

import re
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SRC = ROOT / "src" / "armguard"


def _contracts() -> dict:
    cfg = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["tool"]["importlinter"]
    return {c["id"]: c for c in cfg["contracts"]}


def _layers() -> list[list[str]]:
    """The contract's layers, top first, each a list of its package names (optional ones unwrapped)."""
    return [[n.strip().strip("()") for n in re.split(r"[|:]", layer)] for layer in _contracts()["layers"]["layers"]]


def _children() -> set[str]:
    out = {p.name for p in SRC.iterdir() if p.is_dir() and (p / "__init__.py").is_file()}
    return out | {p.stem for p in SRC.glob("*.py") if p.stem != "__init__"}


def test_every_subpackage_and_module_of_armguard_has_a_layer():
    placed = {n for layer in _layers() for n in layer}
    assert _children() <= placed, f"not in the contract's layers: {sorted(_children() - placed)}"
    assert _contracts()["layers"]["exhaustive"] is True


def test_the_guide_draws_the_contracts_layers_in_order():
    text = (ROOT / "docs" / "architecture.md").read_text(encoding="utf-8")
    block = re.search(r"```\n( top .*?)```", text, re.S).group(1)
    drawn = []
    for line in block.splitlines():
        if not line.strip() or line.startswith(" outside") or line.startswith("         armguard_forbidden"):
            continue
        names = line[8:].split("  ")[0]  # after the "top"/"bottom" margin, before the caption
        drawn.append([n.strip().strip("()") for n in names.split("|")])
        if line.startswith(" bottom"):
            break
    assert drawn == _layers()


def test_the_framework_is_forbidden_every_plugin():
    plugins = sorted(p.name for p in (ROOT / "plugins").iterdir() if (p / "__init__.py").is_file())
    c = _contracts()["plugins"]
    assert c["type"] == "forbidden" and c["source_modules"] == ["armguard"]
    assert sorted(c["forbidden_modules"]) == plugins
