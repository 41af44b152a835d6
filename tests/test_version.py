"""`fwid.__version__`, installed or from a source checkout on `PYTHONPATH`."""

import re
from importlib.metadata import PackageNotFoundError
from pathlib import Path

import fwid


def test_version_of_a_checkout_that_is_not_installed(monkeypatch):
    def not_installed(name):
        raise PackageNotFoundError(name)

    monkeypatch.setattr(fwid, "_version", not_installed)
    toml = (Path(fwid.__file__).resolve().parents[1] / "pyproject.toml").read_text()
    want = re.search(r'^version\s*=\s*"([^"]+)"', toml, re.M).group(1)
    assert fwid._own_version() == want == fwid.__version__
