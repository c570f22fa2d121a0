"""The Python examples of the README and the guides run as written (the documentation is executable)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
README = ROOT / "README.md"
GUIDES = (ROOT / "docs" / "detector.md", ROOT / "docs" / "uncertainty.md", ROOT / "docs" / "terrain.md",
          ROOT / "docs" / "models.md", ROOT / "docs" / "clip.md", ROOT / "docs" / "trajectory-format.md",
          ROOT / "docs" / "program.md",
          ROOT / "docs" / "avoidance.md",
          ROOT / "docs" / "srdf.md",
          ROOT / "docs" / "console.md", ROOT / "docs" / "cspace.md", ROOT / "docs" / "paper-fidelity.md")
BLOCKS = re.findall(r"```python\n(.*?)```", README.read_text(encoding="utf-8"), re.S)
GUIDE_BLOCKS = [(g, code) for g in GUIDES for code in re.findall(r"```python\n(.*?)```", g.read_text(encoding="utf-8"), re.S)]


def test_readme_has_examples():
    assert len(BLOCKS) >= 4


@pytest.mark.parametrize("code", BLOCKS, ids=[f"block{i}" for i in range(len(BLOCKS))])
def test_readme_block_runs(code):
    exec(compile(code, str(README), "exec"), {"__name__": "__readme__"})


def test_guides_have_examples():
    for guide in GUIDES:
        assert any(g == guide for g, _ in GUIDE_BLOCKS), guide


@pytest.mark.parametrize("guide,code", GUIDE_BLOCKS, ids=[f"{g.stem}{i}" for i, (g, _) in enumerate(GUIDE_BLOCKS)])
def test_guide_block_runs(guide, code):
    exec(compile(code, str(guide), "exec"), {"__name__": "__guide__"})


def test_backends_guide_warm_start_block_runs():
    """docs/backends.md's warm-start example (the guide's other blocks need the example backend
    package installed: tests/test_conformance.py runs that package)."""
    text = (ROOT / "docs" / "backends.md").read_text(encoding="utf-8")
    section = text.split("### Along a path: warm starts (analytic)", 1)[1]
    code = re.findall(r"```python\n(.*?)```", section, re.S)[0]
    assert "warm_start" in code
    exec(compile(code, "docs/backends.md", "exec"), {"__name__": "__guide__"})


def test_backends_guide_margins_block_runs():
    """docs/backends.md's margins per pair and category example."""
    text = (ROOT / "docs" / "backends.md").read_text(encoding="utf-8")
    code = [c for c in re.findall(r"```python\n(.*?)```", text, re.S) if "pair_margins(model" in c]
    assert len(code) == 1
    exec(compile(code[0], "docs/backends.md", "exec"), {"__name__": "__guide__"})
