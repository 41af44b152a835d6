"""`fwid simulate --raw fwid|motive` (docs/reference/formats.md): the files of each form, the raw
options passed on, and bad raw options refused with exit 2 and nothing written."""

import json

import pytest

from fwid.cli import main


def test_raw_forms_write_their_files(tmp_path, capsys):
    out = tmp_path / "m"
    assert main(["simulate", str(out), "--raw", "motive", "--flights", "1", "--duration", "2",
                 "--clock-offset", "12.5", "--onboard-rate", "100", "--position-noise", "1",
                 "--rate", "250"]) == 0
    assert sorted(p.name for p in out.iterdir()) == ["lon_0.csv", "lon_0.onboard.csv", "truth",
                                                     "vehicle.json"]
    assert sorted(p.name for p in (out / "truth").iterdir()) == ["lon_0.csv", "lon_0.json",
                                                                "vehicle.json"]
    assert (out / "lon_0.csv").read_text().startswith("Format Version,1.23,Take Name,lon_0,")
    raw = json.loads((out / "truth" / "lon_0.json").read_text())["truth"]["raw"]
    assert raw["clock_offset_s"] == 12.5 and raw["onboard_rate"] == 100.0 and raw["rate"] == 250.0
    assert raw["position_noise_m"] == pytest.approx(1e-3)
    assert "motive form" in capsys.readouterr().out
    out = tmp_path / "f"
    assert main(["simulate", str(out), "--raw", "--flights", "1", "--duration", "2",
                 "--axis", "lat"]) == 0  # --raw alone: the fwid form
    assert sorted(p.name for p in out.iterdir()) == ["lat_0.csv", "truth", "vehicle.json"]
    assert (out / "lat_0.csv").read_text().startswith("t,x,y,z,qw,qx,qy,qz,de,dr,f\n")


@pytest.mark.parametrize("args,words", [
    (["--rate", "100"], "--raw"),
    (["--raw", "motive", "--rate", "5"], "50-2000"),
    (["--raw", "fwid", "--dropouts", "0.5"], "--dropouts"),
    (["--raw", "fwid", "--position-noise", "-1"], ">= 0"),
])
def test_bad_raw_options_exit_2(tmp_path, capsys, args, words):
    assert main(["simulate", str(tmp_path / "x"), *args]) == 2
    err = capsys.readouterr().err
    assert words in err and "Traceback" not in err
    assert not (tmp_path / "x").exists()
