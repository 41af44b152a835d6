"""`fwid identify --fix NAME=VALUE --noise auto|full|diagonal`: the options the advice names
reach the fit, and a malformed one is refused in one line."""

import json

import pytest

from fwid.cli import main


def test_fix_holds_the_parameters_and_noise_picks_r(flight, tmp_path, capsys):
    out = tmp_path / "fixed"
    rc = main(["identify", str(flight), "--model", "lon", "--fix", "Xq=0", "--fix", "Zq=-1e-3",
               "--noise", "diagonal", "--out", str(out), "--figures", "none", "--quiet"])
    assert rc == 0, capsys.readouterr().err
    report = json.loads((out / "report.json").read_text())
    assert "Xq" not in report["parameters"] and "Zq" not in report["parameters"]
    assert "Mq" in report["parameters"] and report["fit"]["noise"] == "diagonal"
    assert report["parameters"]["Mq"]["identifiable"] is True
    csv = (out / "parameters.csv").read_text().splitlines()
    assert csv[0].endswith(",identifiable") and all(r.endswith(",true") for r in csv[1:])


@pytest.mark.parametrize("argv, says", [
    (["--fix", "Mq"], "--fix Mq: not NAME=VALUE with a number for VALUE; write e.g. --fix Xw=0"),
    (["--fix", "Mq=small"], "--fix Mq=small: not NAME=VALUE"),
    (["--fix", "Foo=1"], "--fix Foo: not a free parameter of the lon model; the free ones are "
                         "Xq, Xu, Xw, Xde, Zq, Zu, Zw, Zde, Mq, Mu, Mw, Mde, bq, bu, bw, btheta"),
    (["--model", "flap", "--noise", "full"], "--noise applies to --model lon or lat, not flap"),
    (["--model", "flap", "--fix", "Mq=0"], "--fix applies to --model lon or lat, not flap"),
])
def test_malformed_fix_and_noise_are_refused_in_one_line(flight, capsys, argv, says):
    model = [] if "--model" in argv else ["--model", "lon"]
    rc = main(["identify", str(flight), *model, *argv, "--quiet"])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1 and says in err[0], err


def test_an_unknown_noise_model_is_a_usage_error(flight, capsys):
    with pytest.raises(SystemExit) as e:
        main(["identify", str(flight), "--model", "lon", "--noise", "block"])
    assert e.value.code == 2 and "invalid choice: 'block'" in capsys.readouterr().err
