"""The Dataset's environment fields (density, magnetic field, Sun direction, shadow) come from
the tables the kernel read (issue 25: no second pass of the libraries at the outputs), within
the tables' stated errors of the libraries (orbatt.environment.tables)."""
from __future__ import annotations

import re
import warnings
from pathlib import Path

import numpy as np
from astropy import units as u

from orbatt.environment import sun as esun
from orbatt.environment.frames import R_EARTH_WGS84
from orbatt.scenario import Scenario, parse

SCEN = Path(__file__).resolve().parents[2] / "scenarios"


def test_fields_are_the_kernels_tables_within_their_errors():
    text = re.sub(r"^t_end = .*$", 't_end = "1200 s"', (SCEN / "cubesat-3u-disturbances.toml").read_text(),
                  flags=re.M)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sc = Scenario(parse(text, "d.toml"))
        ds = sc.run()
    pot = sc.potential
    t = np.asarray(sc.times)
    pos = sc.orbit.state(t)[0]
    pos = np.asarray(pos.to_value(u.km) if hasattr(pos, "unit") else pos, dtype=np.float64)
    time = sc.orbit.epoch + t * u.s
    rho = pot.atmosphere.density(time, pos)
    B = pot.magnetic_field.field(time, pos)
    sun = esun.sun_position(time)
    fields = pot.fields(t)
    assert np.abs(fields["density"] / rho - 1).max() < 1e-4          # NRLMSIS: 1.7e-5 stated
    assert np.abs(fields["magnetic_field"] - B).max() < 1e-6 * np.abs(B).max()   # IGRF: 1.1e-9 stated
    d = (sun - pos) / np.linalg.norm(sun - pos, axis=-1, keepdims=True)
    assert np.abs(fields["sun_direction"] - d).max() < 1e-10
    assert np.abs(fields["shadow"] - esun.shadow(pos, sun, kind="conical", body_radius=R_EARTH_WGS84)).max() < 1e-9
    # the Dataset holds these, not a second evaluation of the libraries
    np.testing.assert_array_equal(ds["density"].values, fields["density"])
    np.testing.assert_array_equal(ds["magnetic_field"].values, fields["magnetic_field"])
