"""Every Python block of the README runs as written, in order, in a folder where the
README's first command has written `demo/flights`."""

import re
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

README = Path(__file__).resolve().parents[1] / "README.md"


def _blocks() -> list[str]:
    return re.findall(r"^```python\n(.*?)^```$", README.read_text(), flags=re.S | re.M)


def test_readme_python_blocks_run(tmp_path, monkeypatch):
    from fwid.synth import write_flights

    blocks = _blocks()
    assert len(blocks) >= 5
    write_flights(tmp_path / "demo" / "flights", n_flights=2, seed=0)
    monkeypatch.chdir(tmp_path)
    namespace: dict = {}
    for i, code in enumerate(blocks):
        try:
            exec(compile(code, f"README.md python block {i + 1}", "exec"), namespace)
        except Exception as e:  # name the block, for the README's author
            raise AssertionError(f"README python block {i + 1} fails: {e!r}\n{code}") from e
    assert namespace["result"].converged  # the grey-box example
    assert abs(namespace["result"].table()["Mq"]["value"] + 2.5) < 0.05
    assert namespace["ss"].states == ("q", "u", "w", "theta")
