"""The rigid body: principal moments of inertia or a full inertia tensor in the body frame,
validated, with units at the boundary (a tensor's principal frame: :mod:`orbatt.body_frame`)."""
from __future__ import annotations

import numpy as np
from astropy import units as u

from . import units as U
from .body_frame import BodyFrame, inertia_tensor, principal_axes
from .control import MAX_WHEELS, ReactionWheel, reaction_wheel
from .errors import InputError


#: principal-moment triples ``(i, j, k)`` and the inequality ``Ii + Ij >= Ik`` each stands for
TRIANGLE = ((0, 1, 2, "I1 + I2 >= I3"), (1, 2, 0, "I2 + I3 >= I1"), (2, 0, 1, "I3 + I1 >= I2"))
#: relative tolerance of the triangle inequality (round-off in moments given as decimals)
TRIANGLE_TOLERANCE = 1e-12


def _violates(inertia, i, j, k):
    if type(inertia) is list:  # one body's moments as floats (check_triangle)
        return inertia[i] + inertia[j] < inertia[k] * (1.0 - TRIANGLE_TOLERANCE)
    return inertia[..., i] + inertia[..., j] < inertia[..., k] * (1.0 - TRIANGLE_TOLERANCE)


def triangle_violation(inertia):
    """Where principal moments violate the triangle inequality ``Ii + Ij >= Ik``.

    Parameters
    ----------
    inertia : array_like (..., 3)
        Principal moments ``(I1, I2, I3)`` (any one unit; body axes).

    Returns
    -------
    ndarray of bool (...)
        True where no rigid body has these moments (relative tolerance
        :data:`TRIANGLE_TOLERANCE`).
    """
    inertia = np.asarray(inertia, dtype=np.float64)
    bad = np.zeros(inertia.shape[:-1], dtype=bool)
    for i, j, k, _ in TRIANGLE:
        bad |= _violates(inertia, i, j, k)
    return bad


def check_triangle(inertia):
    """Raise :class:`InputError` naming the first triangle inequality ``Ii + Ij >= Ik`` that
    the principal moments ``inertia (3,)`` violate (see :func:`triangle_violation`)."""
    inertia = np.asarray(inertia, dtype=np.float64)
    # one body: the same comparisons on Python floats (numpy scalars cost ~1 us an operation)
    moments = inertia.tolist() if inertia.shape == (3,) else inertia
    for i, j, k, names in TRIANGLE:
        if _violates(moments, i, j, k):
            raise InputError(f"inertia: {inertia.tolist()} violates the triangle inequality {names}; "
                             "no rigid body has these principal moments")


#: a body whose largest moment is at least this (kg m^2) prints its inertia in kg km^2
REPR_KM2_FROM = 1e3


def _numbers(values):
    """``[12, 15, 18]``: a short list of numbers to 7 significant digits."""
    return "[" + ", ".join(f"{float(v):.7g}" for v in values) + "]"


def _check_wheels(wheels, inertia, dimensionless):
    """The wheels as a tuple, checked: ReactionWheel objects of a dimensional body, at most
    :data:`~orbatt.control.MAX_WHEELS`, leaving ``J = diag(I) - sum Iw a a^T`` positive
    definite (``inertia``: the moments (3,), or the tensor (3, 3) in the wheels' frame)."""
    wheels = tuple(wheels or ())
    if not wheels:
        return ()
    if not all(isinstance(w, ReactionWheel) for w in wheels):
        raise InputError("wheels: expected a list of orbatt.ReactionWheel")
    if dimensionless:
        raise InputError("wheels: reaction wheels need a dimensional body (inertia with units)")
    if len(wheels) > MAX_WHEELS:
        raise InputError(f"wheels: {len(wheels)} wheels, more than {MAX_WHEELS}")
    I = np.diag(inertia) if np.ndim(inertia) == 1 else inertia
    J = I - sum(w.inertia * np.outer(w.axis, w.axis) for w in wheels)
    low = float(np.linalg.eigvalsh(J).min())
    if not low > 0:
        raise InputError(f"wheels: the rotors' axial moments leave the body without inertia about an axis "
                         f"(smallest moment of J = I - sum Iw a a^T: {low * 1e6:.4g} kg m^2); check the wheels' "
                         "inertia (kg m^2) against [body] inertia")
    return wheels


class RigidBody:
    """A rigid body given by its principal moments of inertia ``(I1, I2, I3)`` or by its inertia
    tensor in the body (mechanical) frame.

    Parameters
    ----------
    inertia : Quantity (mass x length^2), str, or plain numbers
        Principal moments ``[I1, I2, I3]`` about body axes 1, 2, 3; or the inertia tensor about
        the centre of mass in the body frame ``B``, a 3x3 matrix ``[[Ixx, Ixy, Ixz], [Ixy, Iyy,
        Iyz], [Ixz, Iyz, Izz]]`` or its six values ``[Ixx, Iyy, Izz, Ixy, Ixz, Iyz]`` (the
        matrix's off-diagonal entries: ``I_xy = -∫ x y dm``). A Quantity (``[400, 500, 600] *
        u.kg * u.km**2``) makes a dimensional problem (internal unit kg km^2, time in s); plain
        numbers make a dimensionless one (like the paper's Sect. 6.1).

        With a tensor that is not diagonal, orbatt integrates in its principal frame ``P``
        (:mod:`orbatt.body_frame`: ``x_B = R x_P``), and everything body-fixed stays in ``B``,
        in and out: the attitude ``q`` (``B`` relative to space), ``Q``, rates, torques, facets,
        wheels, dipoles, control targets and the Dataset's body-axes variables
        (:mod:`orbatt.frame_boundary` does the change at the boundary). A diagonal tensor is
        the principal moments of its diagonal (``frame`` None).

    wheels : sequence of orbatt.ReactionWheel, optional
        Reaction wheels (dimensional bodies only; axes in body axes ``B``): the body becomes a
        gyrostat (:mod:`orbatt.control`); ``inertia`` is then that of the whole spacecraft with
        the rotors locked.

    Attributes
    ----------
    frame : BodyFrame or None
        The change of frame to the principal axes; None when the body axes are principal.
    tensor : ndarray (3, 3) or None
        The tensor as given (internal unit, symmetrized), None for principal moments.

    Raises
    ------
    InputError
        Wrong shape, non-finite values, an asymmetric tensor, non-positive moments, or moments
        violating the triangle inequality ``Ii + Ij >= Ik`` (no physical body has them); wheels
        whose axial moments leave the body without inertia about an axis.
    """

    def __init__(self, inertia, wheels=()):
        self.dimensionless = not isinstance(inertia, (u.Quantity, str))
        if not self.dimensionless:
            if isinstance(inertia, str):
                inertia = u.Quantity(inertia)
            if inertia.unit is not U.INERTIA and inertia.unit.physical_type != "moment of inertia":
                raise InputError(f"inertia: {inertia} has the wrong dimension; expected mass x length^2, "
                                 f"e.g. [400, 500, 600] kg km^2")
        value = U.strip(inertia, U.INERTIA, "inertia", allow_plain=True)
        self.tensor, self.frame = None, None
        if value.shape != (3,):
            value = self._principal_moments(value)
        if min(value.tolist()) <= 0:  # (value <= 0).any() of three finite floats
            raise InputError(f"inertia: moments must be positive, got {value.tolist()}")
        check_triangle(value)
        self._value = np.array(value, dtype=np.float64)  # a copy: the caller's array stays writeable
        self._value.flags.writeable = False
        self.wheels = _check_wheels(wheels, value if self.tensor is None else self.tensor, self.dimensionless)

    def _principal_moments(self, value):
        """The principal moments of a tensor ``value`` ((3, 3) or six values, internal unit),
        setting :attr:`tensor` and :attr:`frame`; refusals name the tensor and the fix."""
        unit, f = ("", 1.0) if self.dimensionless else (" kg m^2", 1e6)
        t = inertia_tensor(value, "inertia", unit.strip() or "plain")
        moments, axes = principal_axes(t)
        shown = (t * f).tolist()
        if not min(moments.tolist()) > 0:
            raise InputError(f"inertia: the tensor {shown}{unit} is not positive definite (principal moments "
                             f"{(moments * f).tolist()}); check the signs of the products of inertia: the matrix's "
                             "off-diagonal entries are I_xy = -∫ x y dm (CAD tools that list +∫ x y dm need them "
                             "negated)")
        try:
            check_triangle(moments)
        except InputError as exc:
            raise InputError(f"inertia: the tensor {shown}{unit} has principal moments {(moments * f).tolist()}, "
                             f"which violate the triangle inequality ({str(exc).split('inequality ')[-1]}); check "
                             "the diagonal and the products of inertia") from None
        self.tensor = t
        self.tensor.flags.writeable = False
        if axes is not None:
            self.frame = BodyFrame(t, moments, axes)
        return moments

    @property
    def principal(self):
        """The same body in its principal frame ``P`` (what the kernels integrate): principal
        moments, the wheels' axes in ``P`` (``R^T a``); the body itself when ``frame`` is None."""
        if self.frame is None:
            return self
        p = self.__dict__.get("_principal")
        if p is None:
            wheels = [reaction_wheel({**w.settings(), "axis": self.frame.to_principal(w.axis).tolist()},
                                     name=getattr(w, "name", None)) for w in self.wheels]
            p = RigidBody(self._value.tolist() if self.dimensionless else self._value * U.INERTIA, wheels=wheels)
            self._principal = p
        return p

    def momentum(self, omega):
        """``I omega + sum Iw speed a`` (body axes, momentum unit): the total angular momentum
        for the body rate ``omega`` (rad per time unit, body axes) and the wheels' initial
        speeds."""
        w = np.asarray(omega, dtype=np.float64)
        g = self._value * w if self.frame is None else self.frame.times_tensor(w)
        return g + self.rotor_momentum if self.wheels else g

    def rate(self, g):
        """``I^-1 (g - sum Iw speed a)``: the body rate (body axes) of the total angular momentum
        ``g`` (body axes) with the wheels' initial speeds."""
        g = np.asarray(g, dtype=np.float64) - (self.rotor_momentum if self.wheels else 0.0)
        return g / self._value if self.frame is None else self.frame.solve_tensor(g)

    @property
    def rotor_momentum(self):
        """``sum Iw_k speed_k a_k`` (kg km^2/s, body axes): the rotors' momentum relative to
        the body at the start (0 without wheels)."""
        h = np.zeros(3)
        for w in self.wheels:
            h += w.inertia * w.speed_rad_s * w.axis
        return h

    def wheel_momenta(self, omega):
        """The wheels' axial momenta ``Iw_k (a_k . omega + speed_k)`` (kg km^2/s) for the body
        rate ``omega`` (rad/s, body axes) and the wheels' initial speeds."""
        return np.array([w.inertia * (float(np.dot(w.axis, omega)) + w.speed_rad_s) for w in self.wheels])

    @property
    def inertia_value(self):
        """Principal moments as floats in the internal unit (kg km^2, or plain numbers): a fresh
        writeable copy (the body's own array stays frozen; a read-only array handed to a compiled
        kernel is another numba type, which compiled the kernel a second time)."""
        return self._value.copy()

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
    def rate_unit(self):
        return U.DIMENSIONLESS if self.dimensionless else U.RATE

    @property
    def inertia(self):
        """Principal moments as a Quantity (kg km^2, or dimensionless); those of the principal
        frame ``P`` for a body given by a tensor (:attr:`inertia_tensor` is the tensor)."""
        return self._value * self.inertia_unit

    @property
    def inertia_tensor(self):
        """The inertia tensor in the body frame ``B`` (3, 3) as a Quantity: the tensor given,
        or ``diag(I1, I2, I3)``."""
        return (np.diag(self._value) if self.tensor is None else np.array(self.tensor)) * self.inertia_unit

    def __repr__(self):
        """``RigidBody(inertia=[12, 15, 18] kg m^2)``: kg m^2 below :data:`REPR_KM2_FROM`
        (1e3 kg m^2), kg km^2 from there on; plain numbers for a dimensionless body."""
        values = self._value if self.tensor is None else self.tensor
        shown = (lambda v: "[" + ", ".join(_numbers(row) for row in v) + "]") if values.ndim == 2 else _numbers
        if self.dimensionless:
            return f"RigidBody(inertia={shown(values)} (dimensionless))"
        in_m2 = values * 1e6
        wheels = f", {len(self.wheels)} reaction wheels" if self.wheels else ""
        if np.max(self._value * 1e6) < REPR_KM2_FROM:
            return f"RigidBody(inertia={shown(in_m2)} kg m^2{wheels})"
        return f"RigidBody(inertia={shown(values)} kg km^2{wheels})"

    def __eq__(self, other):
        return (isinstance(other, RigidBody) and self.dimensionless == other.dimensionless
                and np.array_equal(self._value, other._value) and self.wheels == other.wheels
                and self.frame == other.frame)

    def __hash__(self):
        return hash((self.dimensionless, self._value.tobytes(), tuple(self.wheels), self.frame))
