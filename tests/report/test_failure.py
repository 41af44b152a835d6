"""The one clause a failed identification ends with: why, and the one next step."""

from fwid._advice import command_line
from fwid.report import failure_reason


def _report(**kw):
    block = {"fit": {"cost": 1.0}, "eigenvalues": [[1.2, 0.0], [-3.0, 0.0]],
             "metrics": {"estimation": {"q": {"r2": -2.5e7}}}}
    return {"model": "lon", **block, "closed_loop": {"a.csv": {"closed": True}}, **kw}


def test_the_failure_reason_names_one_step_never_the_method_that_failed():
    with command_line():
        oe = failure_reason(_report())
        ms = failure_reason(_report(method="multiple-shooting"))
        fe = failure_reason(_report(method="filter-error"))
        nan = failure_reason(_report(fit={"cost": None}, method="filter-error"))
    assert "unstable (eigenvalue +1.2 1/s)" in oe and "R2 down to <-1e3" in oe
    # output error on a closed loop: the closed loop's step, filter error, alone
    assert "closed loop: a.csv" in oe and oe.endswith("next: --method filter-error")
    assert oe.count("--method") == 1
    assert "closed loop" not in ms and ms.endswith("next: --method filter-error")
    assert fe.endswith("next: --method equation-error")
    assert nan.startswith("the simulation diverged") and nan.endswith("--method equation-error")


def test_a_diverged_simulation_says_when_and_where():
    q = {"r2": -1.5e41, "rms": 1.4e20, "diverged_at_s": 261.272, "diverged_in": "f.csv"}
    with command_line():
        text = failure_reason(_report(metrics={"estimation": {"q": q}}, closed_loop={},
                                      method="filter-error"))
    assert "diverged from the data at t = 261 s on f.csv (q beyond 100 times" in text
    assert "1.4e+20" not in text and text.endswith("next: --method equation-error")


def test_a_stall_of_equation_error_points_to_the_data():
    stalled = _report(eigenvalues=[[-1.0, 0.0]], closed_loop={}, method="equation-error")
    with command_line():
        text = failure_reason(stalled)
    assert text.startswith("the Gauss-Newton steps stalled") and "--fix NAME=VALUE" in text
