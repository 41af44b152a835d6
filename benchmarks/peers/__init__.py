"""What a Python user would otherwise write, timed and compared against fwid in the same run.

- `scipy_output_error`: numpy RK4 + `scipy.optimize.least_squares` output-error ML (Eqs.
  10-11, R relaxed between solves); no JAX, so an independent reference.
- `jax_output_error`: a hand-written JAX output-error estimator (`lax.scan` RK4, `jacfwd`,
  Gauss-Newton with step halving); no diffrax, optimistix or fwid.
"""
