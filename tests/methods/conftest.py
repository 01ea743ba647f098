"""Fixtures of the tests of orbatt.methods and orbatt.propagation: the paper's bodies with
its printed initial state (docs/design.md §9)."""
import astropy.units as u
import pytest
from method_cases import P0_PAPER, Q0_PAPER

import orbatt


@pytest.fixture(scope="module")
def free():
    """The paper's torque-free body (dimensionless inertia) and initial state."""
    body = orbatt.RigidBody([1.25, 1.0, 0.75])
    return body, orbatt.State(body, Q0_PAPER, P0_PAPER)


@pytest.fixture(scope="module")
def sat():
    """The paper's satellite (kg km^2) and initial state (Sect. 6.2)."""
    body = orbatt.RigidBody([400, 500, 600] * u.kg * u.km**2)
    return body, orbatt.State(body, Q0_PAPER, P0_PAPER)
