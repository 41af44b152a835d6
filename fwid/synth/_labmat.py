"""A lab's own MATLAB log, as the 29 g flapping-wing vehicle's logger writes it (the guide's
"Your lab's recordings"), and the recording map `lab.toml` that reads it: one file holds the
tracked pose and the autopilot's outputs on one clock.

- `record_time_stamp`: `1 x N`, milliseconds;
- `record_Sensor_data`: `N x 6`, the tracked position (mm, z-up: X forward, Y left, Z up) then
  roll, pitch and yaw (deg, 3-2-1: `R = Rz(yaw) Ry(pitch) Rx(roll)`, z-up body axes), NaN
  where the tracking lost the body;
- `record_PWM`: `N x 4` whole PWM counts: `de` as `32767 + de / 1e-5`, the flapping frequency
  twice as `100 + f / 0.001` (two motors), `dr` as `32767 + dr / 1e-5`.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
from scipy.io import savemat
from scipy.spatial.transform import Rotation

from ._vendors import z_up_pose

#: The recording map of `write_lab_mat`'s files.
LAB_MAP = """\
# The 29 g vehicle's MATLAB logger: pose and PWM outputs in one file, one clock.
[time]
column = "record_time_stamp"
unit = "ms"

[tracking]
position = ["record_Sensor_data[0]", "record_Sensor_data[1]", "record_Sensor_data[2]"]
position_unit = "mm"
frame = "z-up"
attitude = ["record_Sensor_data[3]", "record_Sensor_data[4]", "record_Sensor_data[5]"]
attitude_unit = "deg"
euler = "ZYX"

[onboard]
file = "{name}.mat"          # the take itself

[inputs]
de = { column = "record_PWM[0]", offset = 32767, scale = 1e-5 }
f = { column = ["record_PWM[1]", "record_PWM[2]"], offset = 100, scale = 0.001 }
dr = { column = "record_PWM[3]", offset = 32767, scale = 1e-5 }
"""

#: (offset, scale) of the PWM counts of `de`, `f` and `dr` (`LAB_MAP`'s `[inputs]`).
PWM = {"de": (32767.0, 1e-5), "f": (100.0, 1e-3), "dr": (32767.0, 1e-5)}


def write_lab_mat(path, t, position, matrix, tracked, inputs) -> Path:
    """The MATLAB log (v5, scipy's `savemat`) of a NED pose (`t` s, positions m, body -> NED
    matrices, the mask `tracked`) and the `inputs` `{"de", "dr", "f"}` on the same clock."""
    path = Path(path)
    tracked = np.asarray(tracked, bool)
    pos, R = z_up_pose(position, matrix, tracked)
    ypr = Rotation.from_matrix(R).as_euler("ZYX", degrees=True)
    sensor = np.column_stack([pos, ypr[:, ::-1]])
    sensor[~tracked] = np.nan
    pwm = {c: np.rint(off + np.asarray(inputs[c]) / k) for c, (off, k) in PWM.items()}
    data = {"record_time_stamp": 1e3 * np.asarray(t, float)[None, :],
            "record_Sensor_data": sensor,
            "record_PWM": np.column_stack([pwm["de"], pwm["f"], pwm["f"], pwm["dr"]])}
    tmp = path.with_name(f".{path.stem}.tmp.mat")
    savemat(tmp, data)
    os.replace(tmp, path)
    return path
