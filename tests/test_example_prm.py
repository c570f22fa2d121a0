"""examples/prm_edges.py: a roadmap with certified edges beside the same roadmap with sampled edges.

The sampled roadmap holds edges through a 2 mm plate; none of the certified roadmap's CLEAR edges has a
sample in contact at a step of 0.002 rad (100 times finer than the example's), the edges it finds in
collision have a configuration in contact (the exact yes/no check agrees), and the path is SAFE."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np

import armguard
from armguard.verify import EdgeStatus, VerificationStatus

EXAMPLE = Path(__file__).resolve().parent.parent / "examples" / "prm_edges.py"


def test_the_certified_roadmap_has_no_edge_through_a_plate(tmp_path, capsys):
    spec = importlib.util.spec_from_file_location("prm_edges", EXAMPLE)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    out = mod.main(n_nodes=60, seed=0, plot=str(tmp_path / "prm.png"))
    model = armguard.model.model_of(mod.build_scene())
    checker = armguard.checker(model)
    nodes, edges, cert = out["nodes"], out["edges"], out["certified"]
    Q0, Q1 = nodes[edges[:, 0]], nodes[edges[:, 1]]
    for i in np.flatnonzero(cert.clear):
        n = int(np.ceil(np.max(np.abs(Q1[i] - Q0[i])) / 0.002)) + 1
        S = Q0[i] + np.linspace(0.0, 1.0, n)[:, None] * (Q1[i] - Q0[i])
        assert not checker.collides(model.pin_q(S)).any(), i
    hit = np.flatnonzero(cert.code == EdgeStatus.COLLISION)
    assert len(hit) and checker.collides(model.pin_q(cert.q[hit])).all()
    assert len(out["through"]) > 0  # the sampled roadmap's edges through a plate
    assert out["report"].status is VerificationStatus.SAFE and len(out["path"]) >= 2
    assert (tmp_path / "prm.png").stat().st_size > 10_000
    assert "pass through a plate" in capsys.readouterr().out
