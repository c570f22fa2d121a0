"""A public robot in the operator console, end to end in a real browser: ``armguard console ur5``
(example-robot-data's UR5 with its SRDF and its meshes) loads, reports the status the Detector
gives at home, and turns red when a typed joint value folds the arm into itself.

Skipped when example-robot-data is not installed (it is in the test extras) or chromium is missing
(a failure under CI, as ``test_console_browser.py``).
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from test_console_browser import (CHROMIUM, CHROMIUM_ARGS, OUT, _input_for, _open, _status, _type, _wait_status,
                                  console_running, screenshot)

import armguard
from armguard.model import known_models

pytestmark = pytest.mark.browser

ELBOW_FOLDED_DEG = -180.0
"""ur5's elbow_joint here (the other joints at 0) drives the upper arm into wrist 1 (-78 mm)."""


def test_a_public_robot_in_the_console():
    if "ur5" not in {m.name for m in known_models() if m.available}:
        pytest.skip("ur5's package (example-robot-data) is not installed")
    from playwright.sync_api import sync_playwright

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = armguard.load_model("ur5")
    det = armguard.Detector(model, threshold=0.05)  # the console's default threshold
    home = det.check(np.zeros(model.nq)).status.value
    q = np.zeros(model.nq)
    q[list(model.pin_model.names).index("elbow_joint") - 1] = np.radians(ELBOW_FOLDED_DEG)
    folded = det.check(q)
    assert folded.status.value == "collision"  # the premise, from the Detector itself
    with console_running("ur5") as url, sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
        try:
            page = _open(browser, url)
            assert _status(page) == home  # warning: wrist 2 and the tool link 19.8 mm apart
            _type(_input_for(page, "elbow_joint (deg)"), f"{ELBOW_FOLDED_DEG:g}")
            _wait_status(page, "collision")
            text = page.inner_text("#armguard-status")
            assert "upper_arm_link" in text and "wrist_1_link" in text, text
            OUT.mkdir(exist_ok=True)
            shot = OUT / "console-ur5.png"
            screenshot(page, path=str(shot))
            assert shot.stat().st_size > 10_000  # the meshes drawn, not an empty canvas
        finally:
            browser.close()
