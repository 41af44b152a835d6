"""`fwid template DIR`: an example folder in fwid's flight format that a user overwrites with
their own data (the guide's page 'Your own flights', docs/guide/data.md)."""

from __future__ import annotations

from pathlib import Path

GUIDE = """\
fwid flight folder: one CSV per flight, vehicle.json beside them.
Overwrite lon_0.csv with your data (keep the header names), or add more CSV files.

Columns (absolute values, SI units, angles in RADIANS; extra columns are ignored):
  t            s       time, strictly increasing, uniform step
  q u w theta  rad/s, m/s, m/s, rad   longitudinal body states   (--model lon)
  p r v phi    rad/s, rad/s, m/s, rad lateral body states        (--model lat)
  de dr        rad     elevator and rudder deflection as measured
  f            Hz      measured flapping frequency               (--model flap|combined)
  X Y Z        N       aerodynamic forces in body axes, reconstructed from the motion
  L M N        N m     aerodynamic moments in body axes, reconstructed
Body axes: x forward, z down, q positive nose up.

vehicle.json   {"mass": kg, "Ix": kg m^2, "Iy": .., "Iz": .., "Ixz": .., "g": 9.81}
lon_0.json     optional sidecar: {"trim": {"u0": .., "w0": .., "theta0": ..}}; without it the
               trim is estimated from the quiet start before the first input.
               (This example's sidecar also holds the simulator's true values: delete them.)

Then:  fwid identify {folder} --model lon --out report
"""


def template(args) -> int:
    from fwid.synth import write_flights

    out = Path(args.out_dir)
    if out.exists() and any(out.iterdir()):
        from fwid import InputError

        raise InputError(f"{out}: folder exists and is not empty; give a new folder for the "
                         "template")
    write_flights(out, n_flights=1, axis=args.axis, seed=0)
    (out / "README.txt").write_text(GUIDE.replace("{folder}", str(out)))
    print(f"fwid: wrote an example flight folder to {out}/ (see {out / 'README.txt'})")
    return 0
