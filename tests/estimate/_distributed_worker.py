"""One process of the two-process `fit_each` test (`test_distributed.py`) and benchmark.

    python -m tests.estimate._distributed_worker PROCESS_ID NUM_PROCESSES PORT OUT.npy [N]

Joins a cluster on 127.0.0.1:PORT with one CPU device, fits [`flights`][] (N, default 4) with
`fwid.fit_each` and, on process 0, saves the estimates (one row per flight) to OUT.npy. Exits with
`NO_COLLECTIVES` when JAX cannot set up a CPU cluster.
"""

import socket
import sys

import numpy as np

NO_COLLECTIVES = 3  # the exit status when this JAX cannot join a CPU cluster


def free_port() -> int:
    """A TCP port free on 127.0.0.1 now (for the cluster's coordinator)."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def flights(n: int = 4):
    """`n` noisy copies of the simulated longitudinal flight of the estimation tests."""
    from tests.estimate.conftest import make_flight

    f = make_flight("lon")
    rng = np.random.default_rng(0)
    return [f.experiment(f.ys + 1e-3 * rng.normal(size=f.ys.shape)) for _ in range(n)]


def main(pid: int, nproc: int, port: int, out: str, n: int = 4) -> None:
    import fwid

    try:
        fwid.initialize_distributed(f"127.0.0.1:{port}", nproc, pid, local_devices=1)
    except Exception as e:  # noqa: BLE001  (a jaxlib without CPU collectives: say so)
        print(f"no CPU collectives: {type(e).__name__}: {e}", flush=True)
        sys.exit(NO_COLLECTIVES)
    results = fwid.fit_each(fwid.longitudinal(), flights(n))
    if pid == 0:
        np.save(out, np.stack([np.asarray(r.theta) for r in results]))


if __name__ == "__main__":
    main(int(sys.argv[1]), int(sys.argv[2]), int(sys.argv[3]), sys.argv[4],
         *map(int, sys.argv[5:]))
