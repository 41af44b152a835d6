"""The benchmark cases: what is flown or read, and the truth or book values to compare with.

- `textbook`: the `Case` description the textbook cases share (equations written once for
  numpy and JAX), the fwid fit, the reference fit and the agreement rule.
- `tc01`, `tc02`, `tc04`, `tc08`, `twin_otter`: FVSysID test cases 1, 2, 4 and 8 and SIDPAC's
  Twin Otter `tlonss` demo (data read in place from `../shared/flightdata`, never copied).
- `attas`: loader and book values of the ATTAS test cases.
- `methods`: the textbook cases that need multiple shooting or filter error.
- `delfly_speed`: the simulated DelFly problem of the speed benchmarks.
"""
