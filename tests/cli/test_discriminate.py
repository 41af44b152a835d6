"""The test-input design's control map applies every member of `actuator-dynamics`' family as
the diagnosis does (`_catalogue.actuator_filter`), and reads each back from its words."""

import numpy as np

from fwid.cli._discriminate import _variant, control_map
from fwid.diagnosis._catalogue import ACTUATOR_FILTERS, actuator_filter, filter_text


class _Model:
    inputs = ("de_eff",)


def test_every_actuator_member_maps_the_control_as_the_diagnosis_filters_it():
    dt = 0.004
    t = np.arange(0.0, 1.5, dt)
    u = 0.1 * np.sign(np.sin(2 * np.pi * 1.3 * t)) + 0.03 * np.sin(2 * np.pi * 5 * t)
    for v in ACTUATOR_FILTERS:
        assert _variant(filter_text(v)) == v, v
    firsts = {}
    for v in ACTUATOR_FILTERS:  # one member of each kind (each is a compile)
        firsts.setdefault(v[0], v)
    for v in firsts.values():
        got = np.asarray(control_map(_Model, "lon", v)(t, u))[:, 0]
        np.testing.assert_allclose(got, actuator_filter(u, dt, v), atol=1e-9, err_msg=str(v))
