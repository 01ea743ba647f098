"""The rigid body: principal moments of inertia, validated, with units at the boundary."""
from __future__ import annotations

import numpy as np
from astropy import units as u

from . import units as U
from .errors import InputError


class RigidBody:
    """A rigid body given by its principal moments of inertia ``(I1, I2, I3)``.

    Parameters
    ----------
    inertia : Quantity (mass x length^2), str, or 3 plain numbers
        Principal moments about body axes 1, 2, 3. A Quantity (``[400, 500, 600] * u.kg *
        u.km**2``) makes a dimensional problem (internal unit kg km^2, time in s); three
        plain numbers make a dimensionless one (like the paper's Sect. 6.1).

    Raises
    ------
    InputError
        Wrong shape, non-finite or non-positive moments, or moments violating the triangle
        inequality ``Ii + Ij >= Ik`` (no physical body has them).
    """

    def __init__(self, inertia):
        self.dimensionless = not isinstance(inertia, (u.Quantity, str))
        if not self.dimensionless:
            if isinstance(inertia, str):
                inertia = u.Quantity(inertia)
            if inertia.unit.physical_type != "moment of inertia":
                raise InputError(f"inertia: {inertia} has the wrong dimension; expected mass x length^2, "
                                 f"e.g. [400, 500, 600] kg km2")
        value = U.strip(inertia, U.INERTIA, "inertia", allow_plain=True)
        if value.shape != (3,):
            raise InputError(f"inertia: expected three principal moments [I1, I2, I3], got shape {value.shape}")
        if np.any(value <= 0):
            raise InputError(f"inertia: moments must be positive, got {value.tolist()}")
        I1, I2, I3 = value
        for (a, b, c, names) in ((I1, I2, I3, "I1 + I2 >= I3"), (I2, I3, I1, "I2 + I3 >= I1"),
                                  (I3, I1, I2, "I3 + I1 >= I2")):
            if a + b < c * (1.0 - 1e-12):
                raise InputError(f"inertia: {value.tolist()} violates the triangle inequality {names}; "
                                 "no rigid body has these principal moments")
        self._value = value
        self._value.flags.writeable = False

    @property
    def inertia_value(self):
        """Principal moments as floats in the internal unit (kg km^2, or plain numbers)."""
        return self._value

    @property
    def inertia_unit(self):
        return U.DIMENSIONLESS if self.dimensionless else U.INERTIA

    @property
    def time_unit(self):
        return U.DIMENSIONLESS if self.dimensionless else U.TIME

    @property
    def momentum_unit(self):
        return U.DIMENSIONLESS if self.dimensionless else U.MOMENTUM

    @property
    def energy_unit(self):
        return U.DIMENSIONLESS if self.dimensionless else U.ENERGY

    @property
    def rate_unit(self):
        return U.DIMENSIONLESS if self.dimensionless else U.RATE

    @property
    def inertia(self):
        """Principal moments as a Quantity (kg km^2, or dimensionless)."""
        return self._value * self.inertia_unit

    def __repr__(self):
        return f"RigidBody(inertia={self.inertia})"

    def __eq__(self, other):
        return (isinstance(other, RigidBody) and self.dimensionless == other.dimensionless
                and np.array_equal(self._value, other._value))

    def __hash__(self):
        return hash((self.dimensionless, self._value.tobytes()))
