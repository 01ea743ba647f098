"""Non-conservative body torques of flat plates (facets) and of a magnetic dipole (compiled,
no units; ``docs/design.md`` §10).

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
def facet_force(srp, a, cos, u, params, b):
    """The force (body axes) on the facet at ``params[b]`` lit at ``cos = n.u > 0`` from the
    unit direction ``u`` (body axes), ``a = -(scale) params[b] cos``: drag (``srp`` False)
    ``a u``; SRP ``a [(1 - C_s) u + 2 (C_s cos + C_d / 3) n]``."""
    if not srp:
        return (a * u[0], a * u[1], a * u[2])
    cs = params[b + 7]
    cd = params[b + 8]
    ks = a * (1.0 - cs)
    kn = a * 2.0 * (cs * cos + cd / 3.0)
    return (ks * u[0] + kn * params[b + 1], ks * u[1] + kn * params[b + 2], ks * u[2] + kn * params[b + 3])


@jit_inline
def facet_torque(srp, q, scale, u_s, params, p0, nfacets):
    """``sum r x F`` (body axes) over the ``nfacets`` facets at ``params[p0:]`` that face the
    unit direction ``u_s`` (inertial axes; the body's attitude ``q``), with the force of
    :func:`facet_force` for ``scale`` = ``1/2 rho |v|^2`` (drag) or the pressure (SRP)."""
    u = rotate_inv(q, u_s)
    tx = 0.0
    ty = 0.0
    tz = 0.0
    for f in range(nfacets):
        b = p0 + f * FACET_SIZE
        cos = params[b + 1] * u[0] + params[b + 2] * u[1] + params[b + 3] * u[2]
        if cos > 0.0:
            t = cross((params[b + 4], params[b + 5], params[b + 6]),
                      facet_force(srp, -scale * params[b] * cos, cos, u, params, b))
            tx, ty, tz = tx + t[0], ty + t[1], tz + t[2]
    return (tx, ty, tz)


@jit_inline
def facet_drag(q, k, vhat_s, params, p0, nfacets):
    """Drag torque (body axes) of ``nfacets`` facets at ``params[p0:]`` for the attitude ``q``,
    ``k = 1/2 rho |v|^2`` and the unit relative velocity ``vhat_s`` in inertial axes."""
    return facet_torque(False, q, k, vhat_s, params, p0, nfacets)


@jit_inline
def facet_srp(q, pressure, shat_s, params, p0, nfacets):
    """Solar-radiation-pressure torque (body axes) of ``nfacets`` facets at ``params[p0:]``
    for the attitude ``q``, the pressure ``pressure = nu Phi / c (1 AU / d)^2`` and the unit
    vector to the Sun ``shat_s`` in inertial axes."""
    return facet_torque(True, q, pressure, shat_s, params, p0, nfacets)


@jit_inline
def dipole_torque(q, m, b_s):
    """Magnetic torque ``m x B_B`` (body axes) of the body dipole ``m`` (body axes) in the
    field ``b_s`` (inertial axes)."""
    return cross(m, rotate_inv(q, b_s))
