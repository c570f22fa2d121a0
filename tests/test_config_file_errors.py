"""An option of armguard.toml's [backend] table that the backend refuses is named with the file it
came from, by ``armguard.checker`` and by the Detector (``armguard check``) alike (the Detector's
error named no file: "analytic: unknown options ['nme']")."""

from __future__ import annotations

import pytest
from click.testing import CliRunner

import armguard
from armguard._errors import BackendError
from armguard.cli import main


def test_a_typo_in_armguard_toml_is_named_with_the_file(tmp_path, monkeypatch):
    (tmp_path / "armguard.toml").write_text('[backend]\nnme = "coal"\n')
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("ARMGUARD_BACKEND", raising=False)
    monkeypatch.delenv("ARMGUARD_CONFIG", raising=False)
    model = armguard.load_model("puma560")
    for build in (lambda: armguard.checker(model), lambda: armguard.Detector(model)):
        with pytest.raises(BackendError) as err:
            build()
        assert str(err.value).startswith(f"{tmp_path / 'armguard.toml'}: [backend]: ") and "'nme'" in str(err.value)
    r = CliRunner().invoke(main, ["-q", "check", "puma560"])
    assert r.exit_code != 0 and "armguard.toml: [backend]" in r.output and "'nme'" in r.output
    with pytest.raises(BackendError) as err:  # an option given in code is the caller's own: no file named
        armguard.Detector(model, backend="analytic", backend_options={"nme": 1})
    assert "armguard.toml" not in str(err.value)


@pytest.mark.parametrize("content, said", [(b"\xff\xfe[backend]\n", "not UTF-8 text"),
                                           (b"x = " + b"[" * 20000 + b"]" * 20000 + b"\n", "nested too deeply")])
def test_an_unreadable_armguard_toml_is_named_not_an_internal_error(tmp_path, monkeypatch, content, said):
    """A Latin-1 or deeply nested armguard.toml was an internal error (exit 4, UnicodeDecodeError or
    RecursionError) naming no file, and broke every command run in its folder."""
    from armguard.cli import ExitCode

    (tmp_path / "armguard.toml").write_bytes(content)
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("ARMGUARD_BACKEND", raising=False)
    monkeypatch.delenv("ARMGUARD_CONFIG", raising=False)
    with pytest.raises(BackendError, match=f"armguard.toml: not valid TOML: {said}"):
        armguard.checker(armguard.load_model("puma560"))
    r = CliRunner().invoke(main, ["-q", "check", "puma560"])
    assert r.exit_code == ExitCode.INPUT and "armguard.toml: not valid TOML" in r.output, r.output
