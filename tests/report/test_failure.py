"""The one clause a failed identification ends with."""


def test_the_failure_reason_names_another_method_than_the_one_that_failed():
    from fwid._advice import command_line
    from fwid.report import failure_reason

    block = {"fit": {"cost": 1.0}, "eigenvalues": [[1.2, 0.0], [-3.0, 0.0]],
             "metrics": {"estimation": {"q": {"r2": -2.5e7}}}}
    report = {"model": "lon", **block, "closed_loop": {"a.csv": {"closed": True}}}
    with command_line():
        oe = failure_reason(report)
        ms = failure_reason({**report, "method": "multiple-shooting"})
        nan = failure_reason({**report, "fit": {"cost": None}})
    assert "unstable (eigenvalue +1.2 1/s)" in oe and "R2 down to <-1e3" in oe
    assert "--method multiple-shooting" in oe and "closed loop: a.csv" in oe
    assert "--method multiple-shooting" not in ms and "--method filter-error" in ms
    assert nan.startswith("the simulation diverged")
