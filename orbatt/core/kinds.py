"""The term kinds of the kernel model, each described once (``docs/design.md`` §10).

A :class:`TermKind` says what a kind of term row (:mod:`orbatt.core.model`) is: its code in
the compiled if-chains, its name (the Dataset's ``torque_<name>`` and the scenario's words),
a description for messages, and what it reads (the orbit, the orbit's velocity, a sampled
table of its own, the extended state of wheels and control laws, the body rate). The kind
sets of :mod:`orbatt.core.model` (which rows need an orbit, a velocity, a table slot, the
extended right-hand side), its :data:`~orbatt.core.model.KIND_DESCRIPTIONS` and the
Dataset names of :mod:`orbatt.torques` are all derived from :data:`KINDS`; the compiled
dispatch (``term_value``, ``term_constants``) stays an if-chain on the codes, as numba needs.

The parameters (``params[p0:p1]``) and table of each kind's row:

=====================  ====  =====================================================================
term kind              code  params
=====================  ====  =====================================================================
heavy top (eq. 18)     1     ``[s Mg, xc1, xc2, xc3]`` (:func:`orbatt.core.potentials.heavy_top`)
gravity gradient       2     ``[GM]``; reads the orbit's ``r`` and radial unit vector
(eq. 20)                     (:func:`orbatt.core.potentials.gravity_gradient`)
aerodynamic drag       3     :func:`~orbatt.core.model.drag_params`: the atmosphere's rotation rate
of flat plates               and the facets of :mod:`orbatt.core.torques`; reads the orbit's position
                             and velocity; table: the density, none for an exponential
                             atmosphere (closed form) (a torque: ``G = -2 q (0, tau)``)
solar radiation        4     :func:`~orbatt.core.model.srp_params`; table: the Sun's position
pressure
magnetic dipole        5     the body's dipole (3); table: the field ``B`` (inertial)
reaction wheels        6     :func:`orbatt.core.control.wheel_params` (the body is a gyrostat and
                             the state ``(q, Q, h)``, :mod:`orbatt.core.gyrostat`)
PD control             7     :func:`orbatt.core.control.pd_params`; table: the Sun's position
                             (``target = sun``)
B-dot control          8     ``[gain, max dipole]``; table: the field ``B`` (inertial)
constant body torque   9     ``[tau1, tau2, tau3]`` (body axes): thruster misalignment,
                             outgassing; reads nothing (a torque: ``G = -2 q (0, tau)``)
momentum dumping       10    :func:`orbatt.core.control.dump_params` (:data:`~orbatt.core.control.DUMP`):
                             magnetorquers unloading the wheels, ``m = k (h x B) / |B|^2``; table:
                             the field ``B`` (inertial); follows a PD law's row on wheels
mode sequence          11    :func:`orbatt.core.control.modes_params`
navigation             12    :func:`orbatt.core.estimator.nav_params`: the gyro, the star tracker and
                             the MEKF (:mod:`orbatt.core.estimator`); optional table: the Sun's
                             position (the star tracker's exclusion)
magnetorquers          13    :func:`orbatt.core.control.magnetorquer_params`: the per-axis dipole
                             limit; table: the field ``B`` (inertial); follows a PD law's row with
                             ``actuator = magnetorquers``, which holds the dipole
vector sensor          14    :func:`orbatt.core.estimator.vector_params`: a magnetometer or a Sun
                             sensor updating the MEKF; table: the field ``B`` or the Sun's
                             position; follows the navigation row
=====================  ====  =====================================================================

Adding a kind: a :class:`TermKind` here, its kernel (a function of ``(q, c)`` and its
parameters, in :mod:`orbatt.core.torques` or :mod:`orbatt.core.potentials`) with a branch in
``core.model.term_value``, and the API/scenario key that builds its row.
"""
from __future__ import annotations

from dataclasses import dataclass

__all__ = ["TermKind", "KINDS", "BY_CODE", "BY_NAME", "codes_where"]


@dataclass(frozen=True)
class TermKind:
    """One kind of term row of the kernel model.

    Attributes
    ----------
    code : int
        The row's ``KIND`` (the compiled dispatch's constant).
    name : str
        Identifier: the Dataset variable ``torque_<name>`` of a torque term.
    description : str
        In words, for messages ("the gravity gradient").
    orbit : bool
        Reads the orbit (row 0 must hold one).
    velocity : bool
        Reads the orbit's velocity (row 0 gets ``NEEDS_VELOCITY``).
    table : bool
        Owns a sampled table (an environment field along the orbit; a ``work`` slot).
    extended : bool
        Needs the extended state (wheels' momenta, the body rate: :mod:`orbatt.core.gyrostat`).
    conservative : bool
        Has a potential ``U`` (else a torque, ``U = 0``).
    """

    code: int
    name: str
    description: str
    orbit: bool = False
    velocity: bool = False
    table: bool = False
    extended: bool = False
    conservative: bool = False


#: every term kind, by code
KINDS = (
    TermKind(1, "heavy_top", "a heavy top", conservative=True),
    TermKind(2, "gravity_gradient", "the gravity gradient", orbit=True, conservative=True),
    TermKind(3, "drag", "aerodynamic drag", orbit=True, velocity=True, table=True),
    TermKind(4, "srp", "solar radiation pressure", orbit=True, table=True),
    TermKind(5, "magnetic", "a magnetic dipole", orbit=True, table=True),
    TermKind(6, "wheels", "reaction wheels", extended=True),
    # a PD law reads the orbit's velocity (orbital target) and, pointing at the Sun, a table:
    # row 0 may then be empty (an inertial target), and its table is optional
    TermKind(7, "control", "a PD control law", velocity=True, extended=True),
    TermKind(8, "control", "a B-dot control law", orbit=True, table=True, extended=True),
    TermKind(9, "constant", "a constant body torque"),
    TermKind(10, "control", "momentum dumping with magnetorquers", orbit=True, table=True, extended=True),
    # the flight software's mode sequence: which law rows act (issue 32 item 4)
    TermKind(11, "modes", "a mode sequence of control laws", extended=True),
    # the flight software's sensors and attitude filter (issue 32's ticks, issue 33); its table
    # (the Sun's position, for the star tracker's exclusion) is optional
    TermKind(12, "navigation", "attitude sensors and their filter", extended=True),
    # magnetorquers making a PD law's torque: the companion row after it, with the field's table
    TermKind(13, "control", "magnetorquers actuating a PD law", orbit=True, table=True, extended=True),
    # a vector sensor of the navigation (a magnetometer or a Sun sensor, issue 33): its table the
    # field B or the Sun's position; it follows the NAVIGATION row
    TermKind(14, "vector_sensor", "a magnetometer or Sun sensor of the attitude filter", orbit=True, table=True,
             extended=True),
)
#: the kinds by code
BY_CODE = {k.code: k for k in KINDS}
#: the torque-term kinds by name (the Dataset's ``torque_<name>``; control laws excluded: their
#: torque is ``torque_control``)
BY_NAME = {k.name: k for k in KINDS if not k.extended}


def codes_where(flag: str) -> frozenset:
    """The codes of the kinds whose attribute ``flag`` is true."""
    return frozenset(k.code for k in KINDS if getattr(k, flag))
