"""`fwid simulate --prefix`: training and test sets written into one folder by separate
calls never collide."""

import pytest

from fwid.cli import main


def test_prefix_keeps_sets_apart(tmp_path, capsys):
    out = tmp_path / "all"
    for prefix, seed in (("train", 1), ("test", 2)):
        assert main(["simulate", str(out), "--flights", "2", "--seed", str(seed),
                     "--prefix", prefix, "--duration", "2"]) == 0
    names = sorted(p.name for p in out.glob("*.csv"))
    assert names == ["test_0.csv", "test_1.csv", "train_0.csv", "train_1.csv"]
    assert (out / "train_0.json").exists() and (out / "vehicle.json").exists()
    # different seeds, different flights: nothing overwritten
    assert (out / "train_0.csv").read_text() != (out / "test_0.csv").read_text()
    assert "train_0.csv .. train_1.csv" in capsys.readouterr().out


@pytest.mark.parametrize("bad", ["../x", "a/b", ".hidden", ""])
def test_bad_prefix_exits_2_and_writes_nothing(tmp_path, capsys, bad):
    with pytest.raises(SystemExit) as info:
        main(["simulate", str(tmp_path / "x"), "--prefix", bad])
    assert info.value.code == 2
    assert "prefix" in capsys.readouterr().err
    assert not (tmp_path / "x").exists()


def test_simulate_form_is_passed_on_and_checked(tmp_path, capsys):
    """`--form` picks the effect's form (written in the sidecar's truth); a form the effect
    does not have exits 2 with the choices, and writes nothing."""
    import json

    from fwid.cli import main

    assert main(["simulate", str(tmp_path / "a"), "--flights", "1", "--duration", "1.5",
                 "--effect", "actuator-dynamics", "--form", "delay"]) == 0
    truth = json.loads((tmp_path / "a" / "lon_0.json").read_text())["truth"]
    assert "delay" in json.dumps(truth)
    capsys.readouterr()
    assert main(["simulate", str(tmp_path / "b"), "--effect", "actuator-dynamics",
                 "--form", "wobble"]) == 2
    err = capsys.readouterr().err
    assert "wobble" in err and "rate-limit" in err
    assert not (tmp_path / "b").exists()
