"""The term list: what acts on the body, evaluated in one loop (``docs/design.md`` §10).

The right-hand side of eq. (7) is the kinetic part plus the sum of the terms acting on the
body. This module is the **only** place that dispatches on term kinds; the step loops of
:mod:`orbatt.core.dop853` (single, batch, lockstep lanes) and :mod:`orbatt.core.splitting`
all evaluate the terms through :func:`gradient` (one member) or :func:`gradient_lanes` (a
lockstep group, the orbit evaluated once).

A model is three plain arrays (in the caller's consistent unit system), built by
:func:`build` from Python:

``terms`` : int64 ``(1 + n_terms, TERM_FIELDS)``
    Row 0 is the **orbit** the terms may read: ``[orbit kind, p0, p1, r0, r1, flags]``
    (``flags``: :data:`NEEDS_VELOCITY`); rows ``1..n`` are the **terms** ``[term kind, p0,
    p1, r0, r1, 0]``. ``params[p0:p1]`` are the row's parameters and ``table[r0:r1]`` its
    table rows.
``params`` : float64 ``(P,)``
    Every row's parameters, concatenated.
``table`` : float64 ``(R, C)``
    Every row's table, stacked (``C`` the widest; narrower tables are zero-padded).

=====================  ====  =====================================================================
orbit kind             code  params / table
=====================  ====  =====================================================================
none                   0     (a model without orbit-driven terms)
Keplerian              1     the ``orb`` vector of :mod:`orbatt.core.kepler` (15 entries)
sampled                2     ``[t_first, t_last]``; table = samples ``[t, x, y, z, vx, vy, vz,
                             ax, ay, az]`` of :mod:`orbatt.core.sampled` (quintic Hermite)
Keplerian, in the      3     as Keplerian; the independent variable of the step loops is the
eccentric anomaly            eccentric anomaly ``E`` instead of the time (:func:`orbit_at`)
=====================  ====  =====================================================================

The term kinds (rows ``1..n``), their codes and parameters: :mod:`orbatt.core.kinds`.

The last three are the **extended** kinds (:data:`EXTENDED_KINDS`): a model holding one gets
row 0's :data:`EXTENDED` flag, and the right-hand side of :mod:`orbatt.core.hamiltonian`
hands it to :func:`orbatt.core.gyrostat.rhs_extended` (the wheels' momenta and the body rate
that the control laws read). :func:`term_value` gives them ``(0, 0)``, so the sums below are
those of the other terms.

Every term contributes ``(U, G)``: its potential and its generalized gradient, so that the
momentum equation reads ``dQ/dt = 1/4 Q a - sum G`` (:mod:`orbatt.core.hamiltonian`).
Conservative terms give the tangential gradient of their potential (``docs/design.md`` §2). The
sum starts from the first term's value (not from zero), so a model of one term gives exactly
the numbers of that term alone.

**The eccentric anomaly as the independent variable.** With the orbit kind
:data:`ORBIT_KEPLER_ANOMALY` the right-hand sides (:func:`orbatt.core.hamiltonian.rhs`,
``rhs_lanes``, :func:`orbatt.core.gyrostat.rhs_extended`) take ``s = E`` (rad, unreduced) in
place of ``t`` and return ``dy/dE = dt/dE dy/dt`` with ``dt/dE = (1 - e cos E) / n``
(Sundman's transformation): the orbit is then closed-form at every stage
(:func:`orbatt.core.kepler.kepler_anomaly`), with no Kepler solve, and the terms that read the
time get ``t(E) = (E - e sin E - M0) / n``. The Python drivers map the output times to
anomalies once (``orbatt.methods.dop853``). The evaluation kernels (:func:`gradient`,
:mod:`orbatt.core.evaluation`) take the time, with the Keplerian kind.

The older kernel specification of a potential, ``(kind, params, table)`` with the kinds of
:mod:`orbatt.core.potentials`, converts with :func:`from_spec`.
"""
from __future__ import annotations

import numpy as np

import math

from ._jit import jit, jit_inline
from . import environment as env
from . import potentials as pot
from . import torques as trq
from .kinds import KINDS, codes_where
from .kepler import ORB_SIZE, anomaly_of_time, kepler_anomaly, kepler_radial, kepler_state, time_of_anomaly
from .sampled import TABLE_COLUMNS, sampled_radial, sampled_state

# orbit kinds (row 0)
ORBIT_NONE = 0
ORBIT_KEPLER = 1
ORBIT_SAMPLED = 2
ORBIT_KEPLER_ANOMALY = 3
# term kinds (rows 1..n): the codes of :data:`orbatt.core.kinds.KINDS` (described there,
# once), as the module constants the compiled if-chains compare with
HEAVY_TOP = 1
GRAVITY_GRADIENT = 2
DRAG = 3
SRP = 4
MAGNETIC = 5
WHEELS = 6
PD_CONTROL = 7
BDOT_CONTROL = 8
CONSTANT_TORQUE = 9
MOMENTUM_DUMP = 10
MODES = 11
NAVIGATION = 12
MAGNETORQUERS = 13
VECTOR_SENSOR = 14
#: what each term kind is, in words (error messages: a method refusing the terms that act)
KIND_DESCRIPTIONS = {k.code: k.description for k in KINDS}

#: columns of a ``terms`` row
KIND, P0, P1, R0, R1, FLAGS = 0, 1, 2, 3, 4, 5
TERM_FIELDS = 6
#: row 0 ``FLAGS`` bit: a term reads the orbit's velocity
NEEDS_VELOCITY = 1
#: row 0 ``FLAGS`` bit: the model has reaction wheels or a control law (the extended
#: right-hand side of :mod:`orbatt.core.gyrostat`)
EXTENDED = 2
#: row 0 ``FLAGS`` bit: the step loops do not locate the model's switching functions
#: (:mod:`orbatt.core.switches`; the ``switches = False`` option of the drivers)
NO_SWITCHES = 4
#: the kinds that make a model extended: they read the body rate (and the wheels' momenta)
EXTENDED_KINDS = codes_where("extended")

#: terms that read the orbit, those that read its velocity, and those with a table of their
#: own (an environment field sampled along the orbit; the row's ``FLAGS`` column holds the
#: slot of ``work`` that keeps its interval; a PD law's table is optional)
ORBIT_TERMS = codes_where("orbit")
VELOCITY_TERMS = codes_where("velocity")
TABLE_TERMS = codes_where("table")
#: the first slot of ``work`` given to tables (0..2: Kepler's warm start, 3: the sampled
#: orbit); :data:`orbatt.core.potentials.WORK_SIZE` bounds the number of table terms
FIRST_TABLE_SLOT = 4
#: parameters of a drag term before its facets: ``[omega, nfacets, density model, rho0, h0, H, R]``
DRAG_HEADER = 7
#: density models of the drag term: its table (pieces), or the exponential atmosphere in
#: closed form (``rho0 exp(-(r - R - h0) / H)``, no table)
DENSITY_TABLE, DENSITY_EXPONENTIAL = 0, 1
#: parameters of an SRP term before its facets: ``[P1AU, AU, shadow, R_body, R_sun, nfacets]``
SRP_HEADER = 6
#: shadow models of the SRP term
SHADOW_NONE, SHADOW_CYLINDRICAL, SHADOW_CONICAL = 0, 1, 2
#: how many constants a term row may take per evaluation (:func:`term_constants`: the
#: tuple ``c``, computed once per evaluation and shared by every member): the one place that
#: sets the width. The kinds of today use at most 4 (the padding costs nothing: the tuples are
#: inlined into the step loops and LLVM drops the unused entries); a kind that needs more than
#: :data:`N_CONSTANTS` widens it here and in :func:`constants_of`.
N_CONSTANTS = 8


# ---------------------------------------------------------------------------------------
# Kernels


@jit_inline
def time_of_s(s, terms, params):
    """The time at the step loops' independent variable ``s``: ``s`` itself, or the time of the
    eccentric anomaly ``s`` for :data:`ORBIT_KEPLER_ANOMALY` (:func:`orbit_at`)."""
    if terms[0, KIND] == ORBIT_KEPLER_ANOMALY:
        return time_of_anomaly(s, math.sin(s), params[terms[0, P0]:terms[0, P1]])
    return s


@jit_inline
def orbit_at(s, terms, params, table, work):
    """``(t, dt/ds, r, xhat, v)`` at the step loops' independent variable ``s``: the
    eccentric anomaly for :data:`ORBIT_KEPLER_ANOMALY` (:func:`orbatt.core.kepler.kepler_anomaly`),
    else the time itself (``t = s``, ``dt/ds = 1``, and :func:`orbit_radial`)."""
    if terms[0, KIND] == ORBIT_KEPLER_ANOMALY:
        return kepler_anomaly(s, params[terms[0, P0]:terms[0, P1]], (terms[0, FLAGS] & NEEDS_VELOCITY) != 0, work)
    r, xhat, v = orbit_radial(s, terms, params, table, work)
    return s, 1.0, r, xhat, v


@jit
def next_breakpoint(s, terms, params, table):
    """The first knot after ``s`` of the model's tables, a sampled orbit's samples (row 0) and
    every term row's table (drag, SRP, magnetic, control: :mod:`orbatt.core.environment`), in
    the step loops' independent variable (:func:`orbit_at`); ``inf`` if none. Both are
    piecewise polynomials in time (the fields' Chebyshev pieces, whose derivatives jump at the
    knots by the interpolation error; the orbit's quintic Hermite pieces, C2, whose third
    derivative jumps): the step loops land on them, as on output times, so that no step
    straddles one (an error the error estimate does not see) and DOP853 keeps its order, at the
    cost of a step per knot at least. Measured (``benchmarks/README.md``, issue 15): a residual
    dipole over 20 s cubic-spline knots, rtol 1e-8: 1e-11 rad instead of 1.6e-5; the TLE orbit
    of ``iss-tle-gravity-gradient``: ~5e-15 rad at any rtol instead of 1.0e-8 at rtol 1e-12. The
    fields' pieces span 600 s or more (:mod:`orbatt.environment.tables`), so their knots cost a
    few steps per orbit. The facets' shading (drag, SRP) is a kink in the attitude, not in time,
    and stays."""
    best = np.inf
    kind0 = terms[0, KIND]
    orb = params[terms[0, P0]:terms[0, P1]]
    t = time_of_s(s, terms, params)
    for j in range(terms.shape[0]):
        r0 = terms[j, R0]
        r1 = terms[j, R1]
        if r1 - r0 < 2:
            continue
        # the first knot > t
        if table[r1 - 1, 0] <= t:
            continue
        k = r0 if table[r0, 0] > t else r0 + env.bisect_row(table[r0:r1], t) + 1
        while k < r1:
            tk = table[k, 0]
            sk = tk
            if kind0 == ORBIT_KEPLER_ANOMALY:
                sk = anomaly_of_time(tk, orb)
            if sk > s:
                if sk < best:
                    best = sk
                break
            k += 1
    return best


@jit_inline
def orbit_radial(t, terms, params, table, work):
    """``(r, xhat, v)``: radius, radial unit vector and velocity (inertial components) of the
    model's orbit at ``t``. The velocity is computed only when a term reads it (row 0's
    :data:`NEEDS_VELOCITY` flag; else zero), and ``r``, ``xhat`` are the same numbers either
    way; ``(1, (1, 0, 0), 0)`` when the model has no orbit. Inlined: a call passing four
    arrays cost 30 ns of a 170 ns gravity-gradient evaluation (the Keplerian loops ran 5-10 %
    slower than 0.1.0 with it called)."""
    kind = terms[0, KIND]
    if (terms[0, FLAGS] & NEEDS_VELOCITY) != 0:
        if kind == ORBIT_KEPLER:
            return kepler_state(t, params[terms[0, P0]:terms[0, P1]], work)
        elif kind == ORBIT_SAMPLED:
            return sampled_state(t, table[terms[0, R0]:terms[0, R1]], work)
    elif kind == ORBIT_KEPLER:
        r, xhat = kepler_radial(t, params[terms[0, P0]:terms[0, P1]], work)
        return r, xhat, (0.0, 0.0, 0.0)
    elif kind == ORBIT_SAMPLED:
        r, xhat = sampled_radial(t, table[terms[0, R0]:terms[0, R1]], work)
        return r, xhat, (0.0, 0.0, 0.0)
    return 1.0, (1.0, 0.0, 0.0), (0.0, 0.0, 0.0)


@jit
def _drag_constants(rho, params, p0, r, xhat, v):
    """``(1/2 rho |v_rel|^2, v_rel / |v_rel|)`` of a drag term for the density ``rho``;
    ``v_rel = v - omega s3 x r`` (``omega = params[p0]``: the atmosphere's rotation)."""
    w = params[p0]
    vx = v[0] + w * r * xhat[1]
    vy = v[1] - w * r * xhat[0]
    vz = v[2]
    speed = math.sqrt(vx * vx + vy * vy + vz * vz)
    if speed == 0.0:
        return (0.0, 1.0, 0.0, 0.0)
    return (0.5 * rho * speed * speed, vx / speed, vy / speed, vz / speed)


@jit
def _srp_constants(sun, params, p0, r, xhat):
    """``(P, s^)`` of an SRP term: the pressure ``nu P1AU (AU / d)^2`` with the shadow
    function ``nu`` and the unit vector ``s^`` from the body to the Sun (``sun``: the Sun's
    position, inertial)."""
    rs = (r * xhat[0], r * xhat[1], r * xhat[2])
    dx = sun[0] - rs[0]
    dy = sun[1] - rs[1]
    dz = sun[2] - rs[2]
    d = math.sqrt(dx * dx + dy * dy + dz * dz)
    kind = params[p0 + 2]
    nu = 1.0
    if kind == SHADOW_CONICAL:
        nu = env.shadow_conical(rs, sun, params[p0 + 3], params[p0 + 4])
    elif kind == SHADOW_CYLINDRICAL:
        nu = env.shadow_cylindrical(rs, sun, params[p0 + 3], params[p0 + 4])
    au = params[p0 + 1] / d
    return (nu * params[p0] * au * au, dx / d, dy / d, dz / d)


@jit_inline
def constants_of(c0, c1, c2, c3):
    """The constants tuple (:data:`N_CONSTANTS` entries) of a term that uses the first four."""
    return (c0, c1, c2, c3, 0.0, 0.0, 0.0, 0.0)


@jit_inline
def term_constants(j, t, terms, params, table, work, r, xhat, v):
    """``(kind, p0, c)``: the kind of term row ``j``, the start of its parameters and the
    constants ``c`` (a tuple of :data:`N_CONSTANTS`) it needs at time ``t`` (read once per
    evaluation, outside any loop over members): gravity gradient ``(GM / r^3, xhat)``, heavy
    top ``(s Mg, x_c)``, drag ``(1/2 rho |v|^2, v^)``, SRP ``(P, s^)``, magnetic ``B``
    (inertial); the rest zero. The environment fields come from the term's piece table
    (:func:`orbatt.core.environment.piece_eval`), an exponential atmosphere's density from
    its formula at ``r``."""
    kind = terms[j, KIND]
    p0 = terms[j, P0]
    if kind == GRAVITY_GRADIENT:
        return kind, p0, constants_of(params[p0] / (r * r * r), xhat[0], xhat[1], xhat[2])
    elif kind == HEAVY_TOP:
        return kind, p0, constants_of(params[p0], params[p0 + 1], params[p0 + 2], params[p0 + 3])
    elif kind == DRAG or kind == SRP or kind == MAGNETIC:
        return kind, p0, _environment_constants(kind, t, table[terms[j, R0]:terms[j, R1]], terms[j, FLAGS], work,
                                                params, p0, r, xhat, v)
    return kind, p0, constants_of(0.0, 0.0, 0.0, 0.0)


@jit
def _environment_constants(kind, t, tab, slot, work, params, p0, r, xhat, v):
    """:func:`term_constants` of the environment terms (drag, SRP, magnetic), compiled once
    and called (not inlined: inlining them into every step loop multiplied the compile time
    of every run, which mostly does not use them)."""
    if kind == DRAG:
        if params[p0 + 2] == DENSITY_EXPONENTIAL:
            rho = params[p0 + 3] * math.exp(-((r - params[p0 + 6]) - params[p0 + 4]) / params[p0 + 5])
        else:
            rho = env.piece_eval(tab, t, 1, slot, work)[0]
        c = _drag_constants(rho, params, p0, r, xhat, v)
    elif kind == SRP:
        c = _srp_constants(env.piece_eval(tab, t, 3, slot, work), params, p0, r, xhat)
    else:
        b = env.piece_eval(tab, t, 3, slot, work)
        c = (b[0], b[1], b[2], 0.0)
    return constants_of(c[0], c[1], c[2], c[3])


@jit_inline
def term_value(kind, p0, c, q, inertia, params):
    """``(U, G)`` of a term of ``kind`` with constants ``c`` (:func:`term_constants`) and
    parameters from ``params[p0]`` at the attitude ``q`` (4-tuple) of a body of principal
    moments ``inertia``. The one dispatch on term kinds."""
    if kind == GRAVITY_GRADIENT:
        return pot.gravity_gradient(q, inertia, c[0], (c[1], c[2], c[3]))
    elif kind == HEAVY_TOP:
        return pot.heavy_top(q, (c[0], c[1], c[2], c[3]))
    elif kind == DRAG or kind == SRP or kind == MAGNETIC or kind == CONSTANT_TORQUE:
        return 0.0, _environment_gradient(kind, c, q, params, p0)
    return 0.0, (0.0, 0.0, 0.0, 0.0)


@jit
def _environment_gradient(kind, c, q, params, p0):
    """:func:`term_value` of the torque terms (drag, SRP, magnetic, constant; compiled once
    and called, as :func:`_environment_constants`): ``G = -2 q (0, tau)``."""
    if kind == DRAG:
        tau = trq.facet_drag(q, c[0], (c[1], c[2], c[3]), params, p0 + DRAG_HEADER, int(params[p0 + 1]))
    elif kind == SRP:
        if c[0] == 0.0:     # the umbra: no pressure (the facets' sum would be exactly 0 too)
            tau = (0.0, 0.0, 0.0)
        else:
            tau = trq.facet_srp(q, c[0], (c[1], c[2], c[3]), params, p0 + SRP_HEADER, int(params[p0 + 5]))
    elif kind == CONSTANT_TORQUE:
        tau = (params[p0], params[p0 + 1], params[p0 + 2])
    else:
        tau = trq.dipole_torque(q, (params[p0], params[p0 + 1], params[p0 + 2]), (c[0], c[1], c[2]))
    return trq.gradient_of_torque(q, tau)


@jit_inline
def terms_at(t, q, inertia, terms, params, table, work, r, xhat, v):
    """``(U, G)`` summed over the terms (rows ``1..n``) at the attitude ``q`` (4-tuple), the
    orbit's ``r``, ``xhat`` and ``v`` given; starts from the first term's value."""
    U = 0.0
    G = (0.0, 0.0, 0.0, 0.0)
    for j in range(1, terms.shape[0]):
        kind, p0, c = term_constants(j, t, terms, params, table, work, r, xhat, v)
        u, g = term_value(kind, p0, c, q, inertia, params)
        if j == 1:  # the sum starts from the first term's value (one term: its exact numbers)
            U = u
            G = g
        else:
            U += u
            G = (G[0] + g[0], G[1] + g[1], G[2] + g[2], G[3] + g[3])
    return U, G


@jit_inline
def gradient(t, q, inertia, terms, params, table, work):
    """``(U, G)``: the total potential and generalized gradient of all terms at time ``t`` and
    attitude ``q`` (4-tuple); ``(0, 0)`` for an empty model."""
    _, U, G = gradient_at(t, q, inertia, terms, params, table, work)
    return U, G



@jit_inline
def gradient_at(s, q, inertia, terms, params, table, work):
    """``(dt/ds, U, G)``: the total potential and generalized gradient of all terms at the step
    loops' independent variable ``s`` (:func:`orbit_at`; the time for the evaluation kernels'
    models) and the rate ``dt/ds`` (1 when ``s`` is the time); ``(1, 0, 0)`` for an empty
    model."""
    if terms.shape[0] > 1:
        t, dtds, r, xhat, v = orbit_at(s, terms, params, table, work)
        U, G = terms_at(t, q, inertia, terms, params, table, work, r, xhat, v)
        return dtds, U, G
    return 1.0, 0.0, (0.0, 0.0, 0.0, 0.0)


@jit_inline
def _term_lanes(kind, p0, c, Y, nl, I, params, G, first):
    """One term over the lanes into ``G`` (``first``: assign, else add)."""
    if first:
        for l in range(nl):
            _, g = term_value(kind, p0, c, (Y[0, l], Y[1, l], Y[2, l], Y[3, l]), (I[0, l], I[1, l], I[2, l]),
                              params)
            G[0, l], G[1, l], G[2, l], G[3, l] = g
    else:
        for l in range(nl):
            _, g = term_value(kind, p0, c, (Y[0, l], Y[1, l], Y[2, l], Y[3, l]), (I[0, l], I[1, l], I[2, l]),
                              params)
            G[0, l] += g[0]
            G[1, l] += g[1]
            G[2, l] += g[2]
            G[3, l] += g[3]


@jit
def terms_lanes(t, Y, nl, I, terms, params, table, work, r, xhat, v, G):
    """:func:`terms_at` for lanes ``0..nl-1`` of ``Y (8, L)`` (inertia ``I (3, L)``) into
    ``G (4, L)``, the same sums in the same order as one member. One loop over the lanes per
    term, specialized to the term's kind (a constant kind makes :func:`term_value`'s
    dispatch fold away, so that LLVM vectorizes the loop: it does not unswitch a loop on a
    run-time kind); kinds without a specialization take the generic loop. Compiled once and
    called (one call serves a whole group): the lanes right-hand side
    (:func:`orbatt.core.hamiltonian.rhs_lanes`) and the splitting kicks
    (:func:`gradient_lanes_called`) share it instead of compiling a copy each (~15 s apiece
    from a cold cache). Pass borrowed arrays (:func:`orbatt.core._jit.borrow`)."""
    for j in range(1, terms.shape[0]):
        kind, p0, c = term_constants(j, t, terms, params, table, work, r, xhat, v)
        first = j == 1
        if kind == GRAVITY_GRADIENT:
            _term_lanes(GRAVITY_GRADIENT, p0, c, Y, nl, I, params, G, first)
        elif kind == HEAVY_TOP:
            _term_lanes(HEAVY_TOP, p0, c, Y, nl, I, params, G, first)
        else:
            _term_lanes(kind, p0, c, Y, nl, I, params, G, first)


@jit_inline
def gradient_lanes(t, Y, nl, I, terms, params, table, work, G):
    """:func:`gradient` for lanes ``0..nl-1`` of ``Y (8, L)`` (inertia ``I (3, L)``) at the
    common time ``t``, into ``G (4, L)``; the orbit is evaluated once for the group. Returns
    False (``G`` untouched) for an empty model."""
    if terms.shape[0] <= 1:
        return False
    r, xhat, v = orbit_radial(t, terms, params, table, work)
    terms_lanes(t, Y, nl, I, terms, params, table, work, r, xhat, v, G)
    return True


@jit
def gradient_lanes_called(t, Y, nl, I, terms, params, table, work, G):
    """:func:`gradient_lanes`, compiled once and called (not inlined): one call serves a whole
    group, so the call costs nothing beside the loops over the lanes, and the splitting group
    loops (:mod:`orbatt.core.splitting`) that call it compile without a copy of every term's
    lanes loop of their own. Pass borrowed arrays (:func:`orbatt.core._jit.borrow`)."""
    return gradient_lanes(t, Y, nl, I, terms, params, table, work, G)


# ---------------------------------------------------------------------------------------
# Building models (Python)


def build(orbit=None, terms=()):
    """Pack an orbit and a list of terms into the arrays ``(terms, params, table)``.

    Parameters
    ----------
    orbit : None or (int, array_like, array_like or None)
        ``(orbit kind, params, table)``; None: no orbit (:data:`ORBIT_NONE`).
    terms : sequence of (int, array_like, array_like or None)
        ``(term kind, params, table)`` of each term, in evaluation order.

    Returns
    -------
    terms : ndarray int64 (1 + n, TERM_FIELDS)
    params : ndarray float64 (P,)
    table : ndarray float64 (R, C), C-contiguous and writeable
    """
    rows = [(ORBIT_NONE, (), None) if orbit is None else orbit, *terms]
    spec = np.zeros((len(rows), TERM_FIELDS), dtype=np.int64)
    plist, tlist = [], []
    p = r = 0
    for k, (kind, par, tab) in enumerate(rows):
        par = np.asarray(par, dtype=np.float64).ravel()
        tab = np.zeros((0, 0)) if tab is None else np.asarray(tab, dtype=np.float64)
        if tab.ndim != 2:
            raise ValueError(f"model row {k}: the table must be 2-D, got shape {tab.shape}")
        spec[k, :R1 + 1] = (int(kind), p, p + par.size, r, r + tab.shape[0])
        plist.append(par)
        tlist.append(tab)
        p += par.size
        r += tab.shape[0]
    width = max((t.shape[1] for t in tlist), default=0)
    table = np.zeros((r, width))
    for (_, _, _, r0, r1, _), tab in zip(spec, tlist):
        if r1 > r0:
            table[r0:r1, :tab.shape[1]] = tab
    params = np.concatenate(plist) if p else np.zeros(1)
    kinds = {int(k) for k in spec[1:, KIND]}
    if kinds & ORBIT_TERMS and spec[0, KIND] == ORBIT_NONE:
        raise ValueError("a term that reads the orbit needs an orbit (row 0)")
    if kinds & VELOCITY_TERMS:
        spec[0, FLAGS] |= NEEDS_VELOCITY
    if kinds & EXTENDED_KINDS:
        spec[0, FLAGS] |= EXTENDED
    if sum(1 for k in spec[1:, KIND] if k == WHEELS) > 1:
        raise ValueError("at most one row of reaction wheels")
    slot = FIRST_TABLE_SLOT
    for row in spec[1:]:  # a PD law's table is optional, a drag term's too with a closed-form density
        optional = int(row[KIND]) in (PD_CONTROL, NAVIGATION) or (int(row[KIND]) == DRAG and params[row[P0] + 2] != DENSITY_TABLE)
        if (int(row[KIND]) in TABLE_TERMS and not optional) or (optional and row[R1] > row[R0]):
            if row[R1] - row[R0] < 2:
                raise ValueError(f"term kind {int(row[KIND])} needs a table of at least 2 rows")
            if slot >= pot.WORK_SIZE:
                raise ValueError(f"at most {pot.WORK_SIZE - FIRST_TABLE_SLOT} terms with tables")
            row[FLAGS] = slot
            slot += 1
    return spec, params, table


def drag_params(facets, omega, exponential=None):
    """The parameters of a :data:`DRAG` term: the atmosphere's rotation rate ``omega`` (rad per
    time unit about inertial axis 3; 0: a still atmosphere), the density model and the facets
    ``(F, FACET_SIZE)`` of :mod:`orbatt.core.torques` (coefficient ``C_D A``). ``exponential``
    None: the density is the term's table (one component, kg per volume unit, along the
    orbit); else ``(rho0, h0, H, R)``, the exponential atmosphere in closed form (kg per volume
    unit, lengths; ``h = |r| - R``) and no table."""
    facets = np.asarray(facets, dtype=np.float64).reshape(-1, trq.FACET_SIZE)
    model = [DENSITY_TABLE, 0.0, 0.0, 1.0, 0.0] if exponential is None else [DENSITY_EXPONENTIAL, *exponential]
    return np.concatenate([[omega, facets.shape[0]], np.asarray(model, dtype=np.float64), facets.ravel()])


def srp_params(facets, pressure_1au, au, shadow, body_radius, sun_radius):
    """The parameters of an :data:`SRP` term: the radiation pressure at 1 AU (force per area,
    the caller's units), the AU (length unit), the shadow model (:data:`SHADOW_NONE`,
    :data:`SHADOW_CYLINDRICAL`, :data:`SHADOW_CONICAL`), the radii of the occulting body and
    of the Sun, and the facets (coefficient: the area). Its table: the Sun's position
    (inertial, three components)."""
    facets = np.asarray(facets, dtype=np.float64).reshape(-1, trq.FACET_SIZE)
    return np.concatenate([[pressure_1au, au, shadow, body_radius, sun_radius, facets.shape[0]], facets.ravel()])


def from_spec(kind, params, table):
    """The model of a potential given by its kernel specification ``(kind, params, table)``
    (kinds of :mod:`orbatt.core.potentials`)."""
    kind = int(kind)
    params = np.asarray(params, dtype=np.float64).ravel()
    if kind == pot.TORQUE_FREE:
        return build()
    if kind == pot.HEAVY_TOP:
        return build(terms=[(HEAVY_TOP, params[:4], None)])
    if kind == pot.GRAVITY_GRADIENT_KEPLER:
        if params.size < 1 + ORB_SIZE:
            raise ValueError(f"gravity gradient (Keplerian): expected {1 + ORB_SIZE} params, got {params.size}")
        return build(orbit=(ORBIT_KEPLER, params[1:], None), terms=[(GRAVITY_GRADIENT, params[:1], None)])
    if kind == pot.GRAVITY_GRADIENT_SAMPLED:
        table = np.asarray(table, dtype=np.float64)
        if table.ndim != 2 or table.shape[1] != TABLE_COLUMNS or table.shape[0] < 2:
            raise ValueError(f"gravity gradient (sampled orbit): expected a table of shape (N >= 2, {TABLE_COLUMNS}), "
                             f"got {table.shape}")
        return build(orbit=(ORBIT_SAMPLED, params[1:3], table), terms=[(GRAVITY_GRADIENT, params[:1], None)])
    raise ValueError(f"unknown potential kind {kind}")
