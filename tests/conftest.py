"""Suite-wide settings.

The hull cache (``armguard.model._hull_cache``) points at a temporary folder for the whole run
(``ARMGUARD_CACHE_DIR``, set before collection so that subprocesses inherit it too): no test
reads or writes the user's own cache (``~/.cache/armguard/hulls``).
"""

from __future__ import annotations

import os
import shutil
import tempfile

_SAVED: dict = {}


def pytest_configure(config):
    _SAVED["dir"] = os.environ.get("ARMGUARD_CACHE_DIR")
    _SAVED["tmp"] = tempfile.mkdtemp(prefix="armguard-test-cache-")
    os.environ["ARMGUARD_CACHE_DIR"] = _SAVED["tmp"]


def pytest_unconfigure(config):
    if _SAVED.get("dir") is None:
        os.environ.pop("ARMGUARD_CACHE_DIR", None)
    else:
        os.environ["ARMGUARD_CACHE_DIR"] = _SAVED["dir"]
    if _SAVED.get("tmp"):
        shutil.rmtree(_SAVED["tmp"], ignore_errors=True)
