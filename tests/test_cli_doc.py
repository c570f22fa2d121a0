"""docs/cli.md, the command-line reference, is what ``tools/make_cli_doc.py`` writes from the commands'
own ``--help`` now: a new or changed option fails here until the page is written again
(``.venv/bin/python tools/make_cli_doc.py``), so that none goes undocumented."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import click

from armguard.cli import main

ROOT = Path(__file__).resolve().parents[1]


def _tool():
    spec = importlib.util.spec_from_file_location("make_cli_doc", ROOT / "tools" / "make_cli_doc.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _commands(group, prefix=("armguard",)):
    yield prefix, group
    for name, cmd in group.commands.items():
        if isinstance(cmd, click.Group):
            yield from _commands(cmd, (*prefix, name))
        else:
            yield (*prefix, name), cmd


def test_docs_cli_md_is_what_the_script_writes_now():
    page = (ROOT / "docs" / "cli.md").read_text(encoding="utf-8")
    assert page == _tool().render(), "docs/cli.md is out of date: run .venv/bin/python tools/make_cli_doc.py"


def test_every_command_and_option_has_its_place():
    """The page the script writes names every command (a section each) and every option of each, in that section."""
    page = _tool().render()
    for path, cmd in _commands(main):
        title = " ".join(path)
        head = f"`{title}`\n"
        assert f"## {head}" in page or f"### {head}" in page, title
        section = page.split(head, 1)[1].split("\n## ", 1)[0].split("\n### ", 1)[0]
        for p in cmd.params:
            if isinstance(p, click.Option) and not p.hidden:
                for opt in p.opts:
                    assert opt in section, (title, opt)


def test_the_readme_links_the_reference():
    assert "[docs/cli.md](docs/cli.md)" in (ROOT / "README.md").read_text(encoding="utf-8")


def test_the_options_the_review_found_undocumented_are_there():
    page = (ROOT / "docs" / "cli.md").read_text(encoding="utf-8")
    for opt in ("--version", "--config PATH", "-q, --quiet", "--rad", "--robot TEXT", "--stopping-distance FLOAT",
                "--method [certified|sampled]", "--frequency FLOAT", "--joint-step FLOAT", "--threshold FLOAT",
                "--scheduler TEXT", "--scene TEXT", "--out DIRECTORY", "--worst INTEGER RANGE", "--configs INTEGER RANGE",
                "--json", "--j3-resolution TEXT", "--max-depth INTEGER RANGE", "--cell TEXT", "--model TEXT"):
        assert f"- `{opt}`" in page, opt
