"""The library's PNG writers (a verification report's plot, ``armguard compare``'s plots, a forbidden-
values map's slice) draw on ``matplotlib.figure.Figure`` itself, never through pyplot: in a user's
process they leave the backend and the open figures as they were.  They once called
``matplotlib.use("Agg")``, which switched a session's backend under it (its ``plt.show()`` then
showed nothing)."""

from __future__ import annotations

import subprocess
import sys

_SCRIPT = """
import sys
import matplotlib
matplotlib.use("svg")  # a user's backend, not Agg
import matplotlib.pyplot as plt
plt.figure(); plt.plot([1, 2, 3])
import warnings; warnings.simplefilter("ignore")
from pathlib import Path
from armguard import load_scene, verify
from armguard.harness import run_compare
from click.testing import CliRunner
from armguard.cli import main
out = Path(sys.argv[1])
scene = load_scene("hermes")
written = [verify(scene, next(iter(scene.trajectories.values()))).plot(out / "report.png")]
run_compare("hermes", ("analytic", "coal"), n_configs=20, trajectories=(), out_dir=out / "compare")
written += sorted((out / "compare").glob("*.png"))
r = CliRunner().invoke(main, ["cspace", "build", "hermes", "--resolution", "30deg", "--max-depth", "0",
                              "--out", str(out / "hermes.agmap")])
assert r.exit_code == 0, r.output
r = CliRunner().invoke(main, ["cspace", "plot", str(out / "hermes.agmap"), "--q2", "30", "--out", str(out / "slice.png")])
assert r.exit_code == 0, r.output
written.append(out / "slice.png")
print(matplotlib.get_backend(), plt.get_fignums(), len(written), all(p.stat().st_size > 1000 for p in written))
"""


def test_plots_leave_the_backend_and_figures_alone(tmp_path):
    proc = subprocess.run([sys.executable, "-c", _SCRIPT, str(tmp_path)], capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr[-3000:]
    backend, fignums, n, sizes_ok = proc.stdout.split()
    assert backend == "svg" and fignums == "[1]", proc.stdout  # the user's backend and their one figure
    assert int(n) >= 4 and sizes_ok == "True", proc.stdout  # the report, compare's plots, the slice: all written
