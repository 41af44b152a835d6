"""Progress lines of the pipelines (on standard output, when asked for)."""


def say(progress: bool, msg: str) -> None:
    """Print `fwid: msg` when `progress` is on."""
    if progress:
        print(f"fwid: {msg}", flush=True)
