"""Embedded DelFly-like flight simulator: fwid's default data (there is no public DelFly data).

An independent numpy implementation of the paper's combined model (Eqs. 7-9 with the
cycle-averaged aerodynamics Eqs. 1-6 of Tables 1 and 4, and the flapping Fourier series
Eq. 12 of Table 7, superposed as in Eqs. 13-15), with realistic measurement: rippling
control surfaces, sensor noise, and loads reconstructed from the measured motion. Flights are
written as in the flight-data format; `effect` injects an unmodelled effect (the effect names) in one of
a family of forms (`form`, `FORMS`), or two at once;
`effect_noise_ratio` measures how strong it is against the noise on its loads, and
`random_vehicle` draws a stable DelFly with every derivative and Fourier coefficient within
+-30 % of the paper's.

Raw recordings (the raw-recording formats): `simulate_raw` flies the same vehicle and loads
with the full nonlinear rigid-body equations (JAX, diffrax) and records the flight as a lab
would (a tracking take with pose noise and dropouts, an autopilot log on its own clock with a
biased gyro); `write_raw_flights` writes such flights as fwid raw CSVs, as the tracking vendors' exports
(OptiTrack Motive, Vicon Nexus, Qualisys QTM TSV and MATLAB) with the autopilot's log, or as a
lab's MATLAB log with its recording map, with the truth beside them.
"""

from ._delfly import (
    ALL_PARAMS as ALL_PARAMS,
    DELFLY as DELFLY,
    FLAP_LAT_PARAMS as FLAP_LAT_PARAMS,
    FLAP_LON_PARAMS as FLAP_LON_PARAMS,
    FORCES as FORCES,
    LAT_PARAMS as LAT_PARAMS,
    LON_PARAMS as LON_PARAMS,
    STATES as STATES,
    DelFly as DelFly,
    lat_matrices as lat_matrices,
    lon_matrices as lon_matrices,
    state_space as state_space,
)
from ._effects import (
    ALIASES as ALIASES,
    EFFECT_COEFFICIENTS as EFFECT_COEFFICIENTS,
    EFFECTS as EFFECTS,
    FORM_COEFFICIENTS as FORM_COEFFICIENTS,
    FORMS as FORMS,
    OUT_OF_CATALOGUE as OUT_OF_CATALOGUE,
    Effect as Effect,
    form_axes as form_axes,
)
from ._inputs import (
    DEFAULT_UNIT as DEFAULT_UNIT,
    INPUTS as INPUTS,
    doublet as doublet,
    input_211 as input_211,
    input_3211 as input_3211,
    make_input as make_input,
    pulse as pulse,
)
from ._reconstruct import derivative as derivative, reconstruct_loads as reconstruct_loads
from ._simulate import (
    COLUMNS as COLUMNS,
    DEFAULT_AMPLITUDE as DEFAULT_AMPLITUDE,
    NOISE as NOISE,
    FlapFrequency as FlapFrequency,
    flapping_harmonics as flapping_harmonics,
    flapping_loads as flapping_loads,
    simulate_flight as simulate_flight,
)
from ._strength import effect_noise_ratio as effect_noise_ratio
from ._raw import ONBOARD as ONBOARD, RAW_AMPLITUDE as RAW_AMPLITUDE, TRACKING as TRACKING, simulate_raw as simulate_raw
from ._rawfiles import (
    RAW_COLUMNS as RAW_COLUMNS,
    MAP_NAME as MAP_NAME,
    RAW_FORMS as RAW_FORMS,
    Y_UP as Y_UP,
    ned_to_y_up as ned_to_y_up,
    write_fwid_raw as write_fwid_raw,
    write_motive as write_motive,
    write_onboard as write_onboard,
    write_raw_flights as write_raw_flights,
    write_take as write_take,
    write_truth as write_truth,
)
from ._labmat import LAB_MAP as LAB_MAP, write_lab_mat as write_lab_mat
from ._vendors import (
    Z_UP as Z_UP,
    ned_to_z_up as ned_to_z_up,
    write_nexus as write_nexus,
    write_qtm_mat as write_qtm_mat,
    write_qtm_tsv as write_qtm_tsv,
)
from ._sixdof import (
    SIXDOF_STATES as SIXDOF_STATES,
    SixDof as SixDof,
    euler_to_quat as euler_to_quat,
    initial_state as initial_state,
    integrate as integrate_sixdof,
    quat_to_euler as quat_to_euler,
    quat_to_matrix as quat_to_matrix,
    sixdof_model as sixdof_model,
)
from ._vehicles import RANDOM_PARAMS as RANDOM_PARAMS, random_vehicle as random_vehicle
from ._write import (
    INPUT_CYCLE as INPUT_CYCLE,
    write_csv as write_csv,
    write_flights as write_flights,
    write_sidecar as write_sidecar,
    write_vehicle as write_vehicle,
)
