"""The estimation methods [`fwid.fit`][] dispatches to with `method=`."""

from __future__ import annotations

METHODS = ("output-error", "multiple-shooting", "filter-error")


def fit_method(method: str, model, exps, options: dict, **kw):
    """Fit by `method` (one of [`METHODS`][] other than plain output error) with the
    method's own `options` and [`fwid.fit`][]'s common arguments `kw`."""
    if method == "output-error":
        raise TypeError(f"fwid.fit: unexpected option(s) {', '.join(sorted(options))} for "
                        "method='output-error'")
    kw.update(options)
    if method == "multiple-shooting":
        from ._shooting import fit_shooting
        return fit_shooting(model, exps, **kw)
    if method == "filter-error":
        from ._filter_error import fit_filter_error
        return fit_filter_error(model, exps, **kw)
    raise ValueError(f"method must be one of {', '.join(map(repr, METHODS))}, not {method!r}")
