"""Fixtures of the :mod:`orbatt.dataset` tests: a torque-free and an orbit trajectory and
their Datasets (built once per module)."""
import numpy as np
import pytest
from astropy import units as u

import orbatt
from orbatt import dataset as D
from dataset_support import (I_PAPER, P0_PAPER, Q0_PAPER, SCENARIO, CircularOrbit, GravityGradientStandIn,
                             _propagate, _tangent)


@pytest.fixture(scope="module")
def free_traj():
    body = orbatt.RigidBody(I_PAPER)
    t = np.linspace(0.0, 20.0, 201)
    return _propagate(body, Q0_PAPER, _tangent(Q0_PAPER, P0_PAPER), orbatt.TorqueFree(), t)


@pytest.fixture(scope="module")
def free_ds(free_traj):
    return D.to_dataset(free_traj, scenario_text=SCENARIO)


@pytest.fixture(scope="module")
def orbit_traj():
    orbit = CircularOrbit()
    body = orbatt.RigidBody([400, 500, 600] * u.kg * u.km**2)
    t = np.linspace(0.0, 0.5 * orbit.period, 151)
    return _propagate(body, Q0_PAPER, _tangent(Q0_PAPER, P0_PAPER), GravityGradientStandIn(orbit), t,
                      inertia=body.inertia_value)


@pytest.fixture(scope="module")
def orbit_ds(orbit_traj):
    return D.to_dataset(orbit_traj, scenario_text=SCENARIO)
