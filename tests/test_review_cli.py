"""CLI failures are one clear line and exit status 3 (ExitCode.INPUT), never a traceback.

Found in review: ``armguard verify ... --report PATH`` / ``--plot PATH`` where PATH cannot be
written (its parent is a file) ended in a Python traceback after the verification had run.
"""

from __future__ import annotations

import pytest
from click.testing import CliRunner

from armguard.cli import main


@pytest.mark.parametrize("option", ["--report", "--plot"], ids=["report", "plot"])
def test_verify_unwritable_output_is_one_line_exit_3(tmp_path, option):
    blocker = tmp_path / "not_a_dir"
    blocker.write_text("a file where a folder is expected", encoding="utf-8")
    target = blocker / ("out.json" if option == "--report" else "out.png")
    res = CliRunner().invoke(main, ["verify", "puma560", "pick_and_place", option, str(target)])
    assert res.exit_code == 3, res.output  # ExitCode.INPUT
    assert res.exception is None or isinstance(res.exception, SystemExit)
    assert "Traceback" not in res.output
    last = [ln for ln in res.output.splitlines() if ln.strip()][-1]
    assert last.startswith("error:") and str(target) in last
    # refused before the work (check_writable): nothing is computed that the failed write would lose
    assert "verdict" not in res.output and "SAFE" not in res.output and "COLLISION" not in res.output
