"""The `fwid` command line: thin, it calls the public API.

One module per command: `fwid simulate` (`_simulate.py`), `fwid template` (`_template.py`), `fwid identify` (`_identify.py`,
all four models), `fwid diagnose` (`_diagnose.py`), `fwid reconstruct` (`_reconstruct.py`),
`fwid design` (`_design.py`); the arguments are in `_parser.py`.

Exit codes: 0 on success, 2 on bad input (one line on stderr: what and where), 1 on an
internal error.
"""

from __future__ import annotations

import os
import sys

from ._design import design
from ._diagnose import diagnose
from ._identify import identify
from ._parser import parser
from ._reconstruct import reconstruct
from ._simulate import simulate
from ._template import template

COMMANDS = {"simulate": simulate, "template": template, "identify": identify,
            "diagnose": diagnose, "reconstruct": reconstruct, "design": design}


def executable_setup() -> None:
    """What the `fwid` executable sets for its process before anything imports Equinox:
    runtime checks that return NaN instead of raising (`EQX_ON_ERROR=nan`), unless the user
    set `EQX_ON_ERROR`.

    A raising check is a host callback inside the compiled program, and JAX never writes a
    program with a host callback to its persistent compilation cache: the batched fit and the
    simulation would be compiled again by every process (about 5 s of a 16-flight
    `fwid identify`, `benchmarks/results/speed_process.md`). fwid's solves already run with
    `throw=False` and judge the result themselves (a NaN is a diverged fit, reported as such).
    Equinox reads the variable when it is imported, so this does nothing after that."""
    if "equinox" not in sys.modules:
        os.environ.setdefault("EQX_ON_ERROR", "nan")


def run(argv=None) -> int:
    """The `fwid` executable: [`executable_setup`][], then [`main`][]."""
    executable_setup()
    return main(argv)


def _one_line(message, category, filename, lineno, file=None, line=None) -> None:
    """A warning as the command line prints it: one line, no source location."""
    print(f"fwid: warning: {message}", file=sys.stderr if file is None else file)


def main(argv=None) -> int:
    import warnings

    from fwid._errors import FitDivergedError, InputError
    from fwid._advice import command_line

    args = parser().parse_args(argv)
    try:
        with warnings.catch_warnings(), command_line():
            warnings.showwarning = _one_line
            return COMMANDS[args.command](args)
    except InputError as e:
        print(f"fwid: error: {e}", file=sys.stderr)
        return 2
    except FitDivergedError as e:  # a fit that failed, not a bug: say why
        print(f"fwid: error: {e}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print("fwid: interrupted", file=sys.stderr)
        return 1
    except Exception as e:  # internal error: short message plus where, for a bug report
        import traceback

        tb = traceback.extract_tb(e.__traceback__)[-1]
        print(f"fwid: internal error: {type(e).__name__}: {e} (at {tb.filename}:{tb.lineno}); "
              "please report it", file=sys.stderr)
        return 1
