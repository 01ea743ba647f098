"""Non-conservative body torques of flat plates (facets) and of a magnetic dipole (compiled,
no units; ``DESIGN.md`` §10).

A torque ``tau`` (body axes) enters Hamilton's equations as ``dQ/dt += 2 q (0, tau)``; in the
term list (:mod:`orbatt.core.model`) every term contributes a generalized gradient ``G``
with ``dQ/dt = 1/4 Q a - sum G``, so a torque term contributes ``G = -2 q (0, tau)``
(:func:`gradient_of_torque`). ``q . (q (0, tau)) = 0``: the constraint ``q.Q = 0`` stays
an invariant, and ``-1/2 Im(q~ G) = tau`` for a unit ``q``.

Facets: each is ``FACET_SIZE`` consecutive parameters ``[c, nx, ny, nz, rx, ry, rz, cs, cd]``:
the coefficient ``c`` (drag: ``C_D A``; SRP: ``A``), the outward unit normal and the centre
of pressure (from the centre of mass), body axes, and the specular and diffuse
reflectivities (read by SRP only). Facets do not shadow each other.

Drag: ``F = -1/2 rho C_D A max(0, n.v^) |v|^2 v^`` with ``v`` the velocity relative to the
atmosphere in body axes; SRP: with ``s^`` the unit vector to the Sun in body axes and
``cos t = n.s^ > 0``, ``F = -P A cos t [(1 - C_s) s^ + 2 (C_s cos t + C_d / 3) n]``;
``tau = r x F`` summed over facets. Magnetic: ``tau = m x B`` (body axes).
"""
from __future__ import annotations

from ._jit import jit_inline
from .qalg import cross, qmul, rotate_inv

#: parameters per facet
FACET_SIZE = 9


@jit_inline
def gradient_of_torque(q, tau):
    """The generalized gradient ``G = -2 q (0, tau)`` of a body torque ``tau``."""
    w = qmul(q, (0.0, tau[0], tau[1], tau[2]))
    return (-2.0 * w[0], -2.0 * w[1], -2.0 * w[2], -2.0 * w[3])


@jit_inline
def add_lever_torque(tx, ty, tz, params, b, F):
    """``(tx, ty, tz) + r x F``: the torque of the force ``F`` (body axes) at the centre of
    pressure ``r = params[b + 4 : b + 7]`` of the facet at ``params[b]``, added to a sum."""
    t = cross((params[b + 4], params[b + 5], params[b + 6]), F)
    return tx + t[0], ty + t[1], tz + t[2]


@jit_inline
def facet_drag(q, k, vhat_s, params, p0, nfacets):
    """Drag torque (body axes) of ``nfacets`` facets at ``params[p0:]`` for the attitude ``q``,
    ``k = 1/2 rho |v|^2`` and the unit relative velocity ``vhat_s`` in inertial axes."""
    v = rotate_inv(q, vhat_s)
    tx = 0.0
    ty = 0.0
    tz = 0.0
    for f in range(nfacets):
        b = p0 + f * FACET_SIZE
        cos = params[b + 1] * v[0] + params[b + 2] * v[1] + params[b + 3] * v[2]
        if cos > 0.0:
            s = -k * params[b] * cos
            tx, ty, tz = add_lever_torque(tx, ty, tz, params, b, (s * v[0], s * v[1], s * v[2]))
    return (tx, ty, tz)


@jit_inline
def facet_srp(q, pressure, shat_s, params, p0, nfacets):
    """Solar-radiation-pressure torque (body axes) of ``nfacets`` facets at ``params[p0:]``
    for the attitude ``q``, the pressure ``pressure = nu Phi / c (1 AU / d)^2`` and the unit
    vector to the Sun ``shat_s`` in inertial axes."""
    s = rotate_inv(q, shat_s)
    tx = 0.0
    ty = 0.0
    tz = 0.0
    for f in range(nfacets):
        b = p0 + f * FACET_SIZE
        n = (params[b + 1], params[b + 2], params[b + 3])
        cos = n[0] * s[0] + n[1] * s[1] + n[2] * s[2]
        if cos > 0.0:
            cs = params[b + 7]
            cd = params[b + 8]
            a = -pressure * params[b] * cos
            ks = a * (1.0 - cs)
            kn = a * 2.0 * (cs * cos + cd / 3.0)
            tx, ty, tz = add_lever_torque(tx, ty, tz, params, b, (ks * s[0] + kn * n[0], ks * s[1] + kn * n[1],
                                                                  ks * s[2] + kn * n[2]))
    return (tx, ty, tz)


@jit_inline
def dipole_torque(q, m, b_s):
    """Magnetic torque ``m x B_B`` (body axes) of the body dipole ``m`` (body axes) in the
    field ``b_s`` (inertial axes)."""
    return cross(m, rotate_inv(q, b_s))
