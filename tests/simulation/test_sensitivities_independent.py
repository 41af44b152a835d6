"""fwid's outputs and sensitivities against an independent computation: the hand-written
`lax.scan` RK4 of `benchmarks/simd.py` on arrays with the flights innermost (no fwid, no
diffrax, the model written out again in `benchmarks/cases/delfly_speed.py`)."""

import sys
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np

import fwid
from fwid.simulation._simulate import simulate_sensitivities

BENCH = Path(__file__).resolve().parents[2] / "benchmarks"


def test_sensitivities_equal_the_flights_innermost_scan():
    sys.path.insert(0, str(BENCH))
    try:
        import cases.delfly_speed as P
        from simd import sensitivities_inner
    finally:
        sys.path.remove(str(BENCH))
    consts, _ = P.vehicle_constants()
    F = P.make_flights(3, 0, consts)
    model = fwid.longitudinal()
    thetas = np.tile(1.2 * F["theta_true"], (3, 1)) * np.array([[1.0], [0.9], [1.1]])
    c = {k: jnp.asarray([ci[k] for ci in F["consts_list"]]) for k in P.CONST_KEYS}
    Y = sensitivities_inner(jnp.asarray(thetas.T), jnp.asarray(np.stack(F["x0"]).T),
                            jnp.transpose(jnp.asarray(np.stack(F["u"])), (1, 2, 0)), c, P.DT)
    for i in range(3):
        sm = model.with_params(dict(zip(P.NAMES, map(float, thetas[i]))))
        ys, dys = jax.jit(lambda th, e: simulate_sensitivities(sm, e, sm.merge, th))(
            sm.theta(), P.experiment(F, i))
        np.testing.assert_allclose(ys, Y[:, 0, :, i], rtol=1e-12, atol=1e-14)
        # fwid (n, outputs, p); the scan (n, p, states)
        np.testing.assert_allclose(dys, np.swapaxes(Y[:, 1:, :, i], 1, 2), rtol=1e-10,
                                   atol=1e-12 * float(np.max(np.abs(dys))))
        assert float(np.max(np.abs(dys))) > 0.0
