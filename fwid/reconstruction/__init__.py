"""From what a lab records to flight data: raw tracking takes and autopilot logs to the flight
files every other stage reads.

[`fwid.read_raw`][] reads a take (a fwid raw CSV, or an OptiTrack Motive export with its
autopilot log) and [`fwid.read_map`][] a recording map for a lab's own columns;
[`fwid.reconstruct`][] smooths the pose, aligns the autopilot's clock, and computes the body
states and aerodynamic loads from the full nonlinear rigid-body equations;
[`fwid.write_reconstruction`][] writes the flights and `reconstruction.json`. `fwid
reconstruct` does it all from the command line. The raw forms and the keys of
`reconstruction.json` are on the guide's page "Formats and interfaces"; the pages "Raw
recordings and reconstruction" and "Your lab's recordings" say how to use them.

The modules:

- Reading (numpy, no JAX): the form is told by the first line (`_read.py`, [`fwid.read_raw`][]):
  the fwid raw CSV (`_fwid_raw.py`) and the OptiTrack Motive CSV export with its autopilot
  log `NAME.onboard.csv` (`_motive.py`); the checks they share (uniform time base, unit
  quaternions, the dropouts) and the `RawTake` (`_raw.py`);
  rotations, quaternion sign continuity, y-up / z-up to north-east-down (`_rotations.py`);
  Motive's time base from its frame numbers and its length unit when unsaid (`_frames.py`,
  `_units.py`); held poses, orientation flips and position jumps dropped (`_glitches.py`).
- A lab's own files through a recording map (`_map.py`, [`fwid.read_map`][]; read by
  `_mapped.py`), time stamps made uniform (`fwid.data._timebase`), the pose's convention checked
  against the onboard accelerometer and gyro (`_imu.py`), the flapping frequency of a
  tracking-only take from the pose's ripple (`_ripple.py`).
- Smoothing (JAX): a linear Kalman filter and Rauch-Tung-Striebel smoother with
  `lax.scan` (`_kalman.py`) on a kinematic model per axis, white jerk plus the flapping
  harmonics 1-3 with wandering coefficients and a gyro bias (`_model.py`), noise levels by
  maximum likelihood, vmapped over takes padded to one length (`_smoother.py`); the attitude as an
  iterated error-state smoother on SO(3) (`_attitude.py`).
- The autopilot's clock against the tracking clock, and its signals resampled onto the
  take's time base without aliasing (`_clock.py`).
- Where a take is airborne: the rests on the ground from the pose (and the logged wing beat),
  the take cut to its airborne stretches between them and between tracking losses longer
  than `max_dropout`, each long enough a flight of its own (`_airborne.py`).
- States and loads from the full nonlinear rigid-body equations (`_loads.py`); the frame
  check and residuals (`_checks.py`); the pipeline, [`fwid.reconstruct`][] (`_pipeline.py`);
  writing the flights and `reconstruction.json` atomically (`_write.py`); the per-take work
  (reading, clocks, writing, figures) on worker processes, one per core (`_workers.py`).

`reconstruction.json` holds `{"flights": [entry, ..]}`, one entry per flight:

- `flight`, `source`, `clock_offset_s` (`t_tracking = t_onboard + clock_offset_s`; 0 when one
  file holds both), `dropouts` (`[start, end]` times of the samples lost), `warnings`;
- `rate_hz`, `duration_s`: the flight's time base;
- `clock`: the offset's quality, or null without a log: `offset_s`, `std_s` (its standard
  error from the curvature of the fit), `corr` (correlation of the aligned gyro and
  smoothed rates), `rms_rad_s` (their residual, bias removed), `given` (from `--clock-offset`);
- `noise`: the measurement noise found by maximum likelihood: `position_m`, `attitude_rad`
  (per body axis), `gyro_rad_s` (per axis, or null);
- `smoother`: the chosen cut-off of the slow part (`position_cutoff_hz`, `attitude_cutoff_hz`)
  and tracking bandwidth of the flapping coefficients (`..._harmonic_bandwidth_hz`);
- `gyro_bias_rad_s`: the gyro's estimated bias (per axis, or null);
- `residuals`: recorded minus smoothed, rms: `position_rms_m`, `attitude_rms_rad` (per
  axis), `gyro_rms_rad_s` (gyro less bias minus smoothed rates, per axis, or null); about the
  noise levels when the smoother and the data agree;
- `specific_force_body_mean`: the mean aerodynamic force per unit mass in body axes (m/s^2),
  what the frame check judges;
- `imu` (when the take has an accelerometer or gyro): per sensor (`acc`, `gyro`) and body axis
  (`x y z`) the `corr` and `rms` of the cycle-averaged sensor and reconstructed signals, and
  `frame`: the convention used.
"""

from ._pipeline import (
    ReconstructedFlight as ReconstructedFlight,
    Reconstruction as Reconstruction,
    reconstruct as reconstruct,
)
from ._raw import OnboardLog as OnboardLog, RawTake as RawTake
from ._map import RecordingMap as RecordingMap, read_map as read_map
from ._read import raw_files as raw_files, read_raw as read_raw
from ._write import write_reconstruction as write_reconstruction
from ._loads import rigid_body_loads as rigid_body_loads

__all__ = ["OnboardLog", "RawTake", "ReconstructedFlight", "Reconstruction", "RecordingMap",
           "raw_files", "read_map", "read_raw", "reconstruct", "rigid_body_loads", "write_reconstruction"]
