"""The exact torque-free rigid body (Euler-Poinsot motion) in orbatt's canonical variables.

This is the test oracle for every integrator (``docs/design.md`` §4): the closed-form flow of
Hamilton's equations (paper eq. 7) with ``U = 0``.

Conventions and units
---------------------
Plain float64 numbers in the caller's consistent internal unit system (for a dimensional
:class:`~orbatt.body.RigidBody`: inertia kg km^2, time s, momenta kg km^2 s^-1; plain numbers
for a dimensionless body). ``q`` (scalar first) maps body components to space components,
``x_S = q x_B q~``; ``Q = 2 q g``; ``g`` is the angular momentum in **body** components,
``G = q g q~ = 1/2 Im(Q q~)`` in **space** (inertial) components (:mod:`orbatt.quaternion`,
:mod:`orbatt.canonical`).

Method
------
1. **Body angular momentum** (Euler's equations ``dg/dt = g x I^-1 g``). The body axes are
   relabelled by a *proper* signed permutation ``M`` (``det M = +1``, so the Euler equations
   keep their time direction; an odd permutation alone would reverse it), ``g' = M g``, with
   moments ``J1, J2, J3``: ``J2`` the middle moment and axis 3 the axis ``g`` circulates
   about - the largest-moment axis when ``D = |g|^2 / 2T > I_mid``, the smallest-moment axis
   when ``D < I_mid`` - and ``g'3 > 0``. With ``n = J3 (J2 - J1) / (J1 (J3 - J2)) >= 0``
   (inertia only)::

       g'1 = a1 cn(u|m),   g'2 = a2 sn(u|m),   g'3 = a3 dn(u|m),   u = lam t + u0,
       a1^2 = g1^2 + g2^2 J1 (J3-J2) / (J2 (J3-J1)),   a2^2 = a1^2 J2 (J3-J1) / (J1 (J3-J2)),
       a3^2 = g3^2 + g2^2 J3 (J2-J1) / (J2 (J3-J1)),
       m = n a1^2 / a3^2,   1 - m = (g3^2 - n g1^2) / a3^2,
       |lam| = a3 sqrt((J3-J2)(J3-J1) / (J1 J2)) / J3,   sign(lam) = sign(J3 - J1),

   each written as a sum of terms of one sign; ``m1 = 1 - m`` is computed directly from
   ``g`` (never by subtracting ``m`` from 1), its only cancellation, in ``g3^2 - n g1^2``,
   being the intrinsic distance to the separatrix. ``u0`` follows from
   ``cn(u0) = g'1/a1``, ``sn(u0) = g'2/a2`` (normalized components, no angle in between) as
   ``F(am0|m)`` via Carlson's ``R_F``. The argument is reduced here, ``u = 2 K k + u_r``
   with ``|u_r| <= K`` (``sn, cn`` change sign with ``k``, ``dn`` does not), so large times
   lose only the unavoidable ``eps |lam t|``.
   ``sn, cn, dn`` come from :func:`jacobi`, the AGM / descending-Landen algorithm of
   :func:`scipy.special.ellipj` but parametrized by ``1 - m``: ``ellipj`` takes ``m``, which
   cannot hold a small ``1 - m`` (next to the separatrix, e.g. a slightly perturbed spin about
   the intermediate axis, it would lose up to 8 digits). On the separatrix (``1 - m = 0``
   exactly: ``D = I_mid``) the ``m -> 1`` limit is used: ``cn, sn, dn -> s sech u, tanh u,
   sech u`` (``s = sign g'1``, ``lam -> s lam``). Symmetric bodies (two equal moments) give
   ``n = m = 0``: circular functions. Steady rotations (``g`` an eigenvector of the inertia
   tensor: pure spin about a principal axis, any spin of a sphere or within the equal-moment
   plane of a symmetric body, and rest) are exact uniform rotations
   ``q(t) = q0 exp(omega t / 2)``.
2. **Attitude.** ``G`` is constant in space. The relabelled body ``B'`` has 3-1-3 Euler
   angles ``(phi, theta, psi)`` relative to a frame ``L`` whose z axis is along ``G``:
   ``g' = |G| (sin theta sin psi, sin theta cos psi, cos theta)``, so
   ``theta = atan2(|g'_12|, g'3)`` (in ``[0, pi/2)``) and ``psi = atan2(g'1, g'2)``,
   unwrapped with ``k`` so it is continuous. ``phi`` obeys
   ``dphi/dt = |G| (g'1^2/J1 + g'2^2/J2) / (g'1^2 + g'2^2) = |G|/J1 - c n sn^2 / (1 + n sn^2)``
   with ``c = |G| (J3 - J1) / (J1 J3)``, integrated in closed form (no quadrature), up to a
   constant (absorbed below)::

       phi(t) = |G| t / J1 - (c n / lam) W(u),   W(u) = int_0^u sn^2 / (1 + n sn^2) du
                                                     = k 2 W(K) + W(u_r)          (n <= 1)
       phi(t) = |G| t / J3 + (c / lam) Y(u),     Y(u) = int_0^u du / (1 + n sn^2)
                                                     = k 2 Y(K) + Y(u_r)          (n > 1)

   with Carlson's ``R_J`` (:func:`scipy.special.elliprj`; elliptic integrals of the third
   kind): ``W(u_r) = (1/3) sn^3 R_J(cn^2, dn^2, 1, 1 + n sn^2)`` and
   ``Y(u_r) = (m / 3n) sn^3 R_J(cn^2, dn^2, 1, 1 + (m/n) sn^2) + atan2(P sn, cn dn) / P``,
   ``P = sqrt((n+1)(n+m)/n)``. The Y form keeps a nearly degenerate ``J2 ~ J3`` (huge ``n``,
   small ``lam``) at round-off where the W form would multiply its round-off by ``c n / lam``;
   near ``u_r = +-K`` next to the separatrix, where ``cn`` and ``dn`` are both small, both
   are evaluated from ``K`` backwards (``_z_reduced``). On the separatrix
   ``W = (u - atan(sqrt(n) tanh u) / sqrt(n)) / (1 + n)``.
   Then ``q(t) = q_G q_z(phi) q_x(theta) q_z(psi) mu~`` with ``mu`` the quaternion of
   ``M^T`` and the constant ``q_G`` fixed by ``q(0) = q0`` (the product is formed factor by
   factor so that the small ``psi`` is not lost next to the growing ``phi``). All angles are
   continuous in ``t`` (``psi`` is reduced modulo ``4 pi``, the period of ``q_z(psi)``), so
   ``q(t)`` is the branch that starts at ``q0`` itself (the one an integrator follows), not
   ``-q0``.
3. **Momentum.** ``Q(t) = q(t) (q0.Q0, 2 g(t)) / |q0|^2``, i.e. ``Q = 2 q g + (q0.Q0) q`` for
   a unit ``q0``.

Exact flow of eq. (7) off the constraint manifold
-------------------------------------------------
``|q|`` and the radial component ``q.Q`` are invariants of the exact flow, and both are
carried along unchanged: a small ``q0.Q0 != 0`` (the paper's 6-digit ``Q(t0)`` has
``q.Q = -9.7e-8``) stays exactly ``q0.Q0``; a non-unit ``q0`` keeps its norm and rotates as
a rigid body with body angular momentum ``g = 1/2 Im(q0~ Q0)`` (:func:`orbatt.canonical.body_momentum`).

Accuracy
--------
Against a 30-digit Taylor integration (mpmath) of eq. (7): ``|q - q_ref|`` and
``|Q - Q_ref| / |Q|`` at most ``4e-15`` for ``|t| <= 30`` in both regimes, for symmetric and
unsorted bodies, and within ``5e-15`` for orbits whose ``1 - m`` is ``1e-14`` (spin about the
intermediate axis perturbed by about ``1e-7``). The phase error grows as ``eps |lam t|``; ``|q|``,
``q.Q``, the energy and ``G`` stay at round-off for any ``t`` (checked to ``t = 1e12``).
Next to the separatrix the motion itself is ill-conditioned (an input perturbation ``d``
grows as ``d exp(|lam| t)`` while the orbit passes the unstable equilibrium); what is
returned is the exact motion of the inputs as given, with a loss bounded by about
``eps / (1 - m)^(1/4)`` in the precession angle.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import special as sp

from . import quaternion as qt
from .errors import InputError
from .body import RigidBody

__all__ = ["torque_free", "torque_free_momentum", "jacobi"]

_STEADY, _ELLIPTIC, _SEPARATRIX = "steady", "elliptic", "separatrix"


# ---- validation ---------------------------------------------------------------------------
def _reject_quantity(value, name, what):
    try:
        from astropy import units as u
    except ImportError:  # pragma: no cover - astropy is a dependency
        return
    if isinstance(value, (u.Quantity, str)):
        raise InputError(f"{name}: got {value!r}; orbatt.analytic takes plain floats in the internal "
                         f"unit system ({what}); strip units first (e.g. .to_value(...))")


def _inertia(inertia):

    if isinstance(inertia, RigidBody):
        return np.array(inertia.inertia_value, dtype=np.float64)
    _reject_quantity(inertia, "inertia", "a RigidBody or three plain moments (I1, I2, I3)")
    try:
        value = np.asarray(inertia, dtype=np.float64)
    except (TypeError, ValueError):
        raise InputError(f"inertia: {inertia!r} is not a RigidBody or three numbers; give "
                         "RigidBody([...]) or (I1, I2, I3)") from None
    if value.shape != (3,):
        raise InputError(f"inertia: expected a RigidBody or three principal moments (I1, I2, I3), "
                         f"got shape {value.shape} ({inertia!r})")
    if not np.all(np.isfinite(value)):
        raise InputError(f"inertia: {value.tolist()} contains non-finite values; give finite "
                         "positive principal moments")
    if np.any(value <= 0.0):
        raise InputError(f"inertia: {value.tolist()} has a moment <= 0; principal moments must be "
                         "positive")
    return value


def _vector(value, name, size, what):
    _reject_quantity(value, name, what)
    try:
        a = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise InputError(f"{name}: {value!r} is not an array of {size} numbers ({what})") from None
    if a.shape != (size,):
        raise InputError(f"{name}: expected shape ({size},) ({what}), got shape {a.shape}")
    if not np.all(np.isfinite(a)):
        raise InputError(f"{name}: {a.tolist()} contains non-finite values; give finite numbers")
    return a


def _times(t):
    _reject_quantity(t, "t", "times in the internal time unit")
    try:
        a = np.asarray(t, dtype=np.float64)
    except (TypeError, ValueError):
        raise InputError(f"t: {t!r} is not an array of times (plain numbers)") from None
    if not np.all(np.isfinite(a)):
        bad = float(a[~np.isfinite(a)].ravel()[0])
        raise InputError(f"t: contains the non-finite time {bad!r}; give finite times")
    return a


# ---- the momentum solution ----------------------------------------------------------------
@dataclass(frozen=True)
class _Motion:
    """Parameters of the torque-free motion of ``g`` (see the module docstring)."""

    kind: str
    gabs: float                     # |G| = |g|
    omega: np.ndarray               # steady: the body rate (original axes)
    M: np.ndarray = None            # g' = M g (proper signed permutation)
    J: np.ndarray = None            # moments along the relabelled axes
    alpha: np.ndarray = None        # a1, a2, a3 (momentum units)
    lam: float = 0.0                # signed d u / d t
    u0: float = 0.0
    m: float = 0.0
    m1: float = 1.0                 # 1 - m, computed from g (never by subtracting m from 1)
    K: float = np.pi / 2
    n: float = 0.0
    c: float = 0.0
    z_k: float = 0.0                # Z(K): the precession integral over a quarter period
    y_form: bool = False            # precession integral in the Y form (n > 1), else W form
    s1: float = 1.0                 # separatrix: sign of g'1


def _motion(I, g0):
    """Classify the motion and compute its constants for inertia ``I`` and body momentum
    ``g0`` (original axes)."""
    gabs = float(np.linalg.norm(g0))
    omega = g0 / I
    nz = g0 != 0.0
    if not nz.any() or np.all(I[nz] == I[nz][0]):
        # g is an eigenvector of the inertia tensor: uniform rotation about it (or rest)
        return _Motion(_STEADY, gabs, omega)
    e = g0 / gabs  # work with the unit vector: no overflow or underflow in the squares
    imin, imid, imax = np.argsort(I, kind="stable")
    Imin, Imid, Imax = I[imin], I[imid], I[imax]
    # s = (G^2 - 2 T I_mid) / |G|^2, as a sum of one-signed terms per axis
    s = e[imax] ** 2 * ((Imax - Imid) / Imax) - e[imin] ** 2 * ((Imid - Imin) / Imin)
    perm = (imin, imid, imax) if s >= 0.0 else (imax, imid, imin)  # (1', 2', 3')
    parity = float(round(np.linalg.det(np.eye(3)[list(perm)])))  # +-1: the permutation's parity
    eps3 = 1.0 if e[perm[2]] >= 0.0 else -1.0
    signs = np.array([1.0, parity * eps3, eps3])
    M = np.zeros((3, 3))
    M[np.arange(3), perm] = signs
    J = I[list(perm)]
    J1, J2, J3 = J
    h = M @ e  # relabelled unit momentum, h3 >= 0
    r12 = (J1 / J2) * ((J3 - J2) / (J3 - J1))        # a1^2 = h1^2 + r12 h2^2, > 0
    r32 = (J3 / J2) * ((J2 - J1) / (J3 - J1))        # a3^2 = h3^2 + r32 h2^2, >= 0
    a1 = np.sqrt(h[0] ** 2 + r12 * h[1] ** 2)
    a3 = np.sqrt(h[2] ** 2 + r32 * h[1] ** 2)
    a2 = a1 / np.sqrt(r12)
    if a1 == 0.0 or a3 == 0.0:  # pragma: no cover - steady motions are caught above
        return _Motion(_STEADY, gabs, omega)
    n = (J3 / J1) * ((J2 - J1) / (J3 - J2))
    # 1 - m = (h3^2 - n h1^2) / a3^2, kept as such (never formed as 1 - m: near the separatrix
    # m = 1 - (1 - m) would round away the small parameter that carries the motion)
    m1 = min(max(s * (J3 / (J3 - J2)) / a3 ** 2, 0.0), 1.0)
    m = 1.0 - m1
    lam = gabs * a3 * np.sqrt(((J3 - J2) / J1) * ((J3 - J1) / J2)) / J3
    sigma = 1.0 if J3 > J1 else -1.0
    c = gabs * ((J3 - J1) / J1) / J3
    alpha = gabs * np.array([a1, a2, a3])
    if m1 == 0.0:
        # separatrix: cn, sn, dn -> s1 sech, tanh, sech; u0 from sinh u0 = tanh u0 / sech u0
        s1 = 1.0 if h[0] >= 0.0 else -1.0
        sech0 = np.sqrt((h[0] ** 2 + h[2] ** 2) / (a1 ** 2 + a3 ** 2))
        u0 = float(np.arcsinh((h[1] / a2) / sech0))
        return _Motion(_SEPARATRIX, gabs, omega, M, J, alpha, sigma * s1 * lam, u0, 1.0, 0.0,
                       np.inf, n, c, 0.0, s1)
    # cn(u0) = h1/a1, sn(u0) = h2/a2 = h2 sqrt(r12)/a1, normalized directly (not through an
    # angle: cos(pi/2) = 6e-17 would shift u0 by 6e-17/dn(u0), large next to the separatrix)
    x, y = h[0], h[1] * np.sqrt(r12)
    rr = np.hypot(x, y)
    cs, sn = x / rr, y / rr
    K = float(sp.elliprf(0.0, m1, 1.0))
    F = sn * float(sp.elliprf(cs * cs, m1 + m * cs * cs, 1.0))   # F(am|m) for |am| <= pi/2
    if cs >= 0.0:
        u0 = F
    else:  # F(pi - am) = 2K - F(am)
        u0 = (1.0 if sn >= 0.0 else -1.0) * 2.0 * K - F
    y_form = n > 1.0
    if y_form:   # Y(K) = (m / 3n) R_J(0, m1, 1, 1 + m/n) + pi / (2 P)
        z_k = ((m / (3.0 * n)) * float(sp.elliprj(0.0, m1, 1.0, 1.0 + m / n))
               + 0.5 * np.pi / _p_y(n, m))
    else:        # W(K) = R_J(0, m1, 1, 1 + n) / 3
        z_k = float(sp.elliprj(0.0, m1, 1.0, 1.0 + n)) / 3.0 if n > 0.0 else 0.0
    return _Motion(_ELLIPTIC, gabs, omega, M, J, alpha, sigma * lam, float(u0), m, m1, K, n, c,
                   z_k, y_form)


def _p_y(n, m):
    """``P = sqrt((n + 1)(n + m) / n)`` of the Y form."""
    return np.sqrt((n + 1.0) * ((n + m) / n))


def jacobi(u, m1):
    """Jacobi elliptic functions ``sn, cn, dn`` of ``(u|m)``, given the complementary parameter
    ``m1 = 1 - m``.

    The arithmetic-geometric mean and descending Landen transformation of
    :func:`scipy.special.ellipj` (Abramowitz & Stegun 16.4), with three changes: the AGM starts
    from ``b0 = sqrt(m1)``, so a tiny ``m1`` (the motion next to the separatrix), which
    ``m = 1 - m1`` cannot hold, keeps all its digits; each backward step takes
    ``asin(c sin phi / a)`` as ``atan2(c sin phi, sqrt(b^2 + c^2 cos^2 phi))``, well
    conditioned where ``c / a -> 1``; and ``dn = sqrt(m1 + m cn^2)``.

    Parameters
    ----------
    u : array_like
        Argument (dimensionless). Accurate for ``|u| <= K(m)``; reduce larger arguments
        first (``sn, cn`` have period ``4K``, ``dn`` ``2K``), as this module does.
    m1 : float
        Complementary parameter ``1 - m``, ``0 < m1 <= 1``.

    Returns
    -------
    sn, cn, dn : ndarray, each of the shape of ``u``
        Absolute error about ``1e-15`` for ``|u| <= K`` and every ``m1`` in ``(0, 1]``
        (checked against mpmath; :func:`scipy.special.ellipj` loses up to ``4e-11`` at
        ``m1 = 1e-14`` even at the exactly representable ``m``).

    Raises
    ------
    InputError
        ``m1`` outside ``(0, 1]`` (``m1 = 0``, the separatrix, has ``K = inf``: use
        ``sech u, tanh u, sech u``).
    """
    m1 = float(m1)
    if not 0.0 < m1 <= 1.0:
        raise InputError(f"m1: {m1!r} is outside (0, 1]; give the complementary parameter 1 - m "
                         "of a parameter 0 <= m < 1")
    u = np.asarray(u, dtype=np.float64)
    a = [1.0]
    b = [np.sqrt(m1)]
    c = [np.sqrt(1.0 - m1)]
    while c[-1] > 0.5 * np.finfo(float).eps * a[-1] and len(a) < 64:
        an = 0.5 * (a[-1] + b[-1])
        c.append(c[-1] * c[-1] / (4.0 * an))   # = (a - b) / 2 without cancellation
        b.append(np.sqrt(a[-1] * b[-1]))
        a.append(an)
    N = len(a) - 1
    phi = (2.0 ** N * a[N]) * u
    for i in range(N, 0, -1):
        beta = np.arctan2(c[i] * np.sin(phi), np.sqrt(b[i] * b[i] + (c[i] * np.cos(phi)) ** 2))
        phi = 0.5 * (phi + beta)
    sn, cn = np.sin(phi), np.cos(phi)
    return sn, cn, np.sqrt(m1 + (1.0 - m1) * cn * cn)


def _sech(u):
    e = np.exp(-np.abs(u))
    return 2.0 * e / (1.0 + e * e)


def _z_reduced(mo, ur, sn, cn, dn):
    """The precession integral ``Z(u_r)`` for ``|u_r| <= K`` (module docstring, step 2).

    W form (``n <= 1``): ``W(u) = int_0^u sn^2 / (1 + n sn^2) = (1/3) sn^3 R_J(cn^2, dn^2, 1,
    1 + n sn^2)``. Y form (``n > 1``): ``Y(u) = int_0^u 1 / (1 + n sn^2)
    = (m / 3n) sn^3 R_J(cn^2, dn^2, 1, 1 + (m/n) sn^2) + atan2(P sn, cn dn) / P`` (the
    characteristic ``-n`` traded for ``-m/n``; ``P = sqrt((n+1)(n+m)/n)``), whose size
    ``~ 1/sqrt(n)`` matches the small ``lam`` of a nearly degenerate ``J2 ~ J3``; the W form
    there would multiply its round-off by ``c n / lam``.

    Both forms lose ``eps / (cn + dn)`` where ``cn`` and ``dn`` are both small (``u_r`` near
    ``+-K`` next to the separatrix). There, with ``v = K - |u_r|``,
    ``Z(u_r) = sign(u_r) (Z(K) - V(v))`` where ``V`` integrates the same integrand with
    ``cd(v) = sn(K - v)`` for ``sn``; with the functions of ``v`` and
    ``p = (dn^2 + n cn^2) / (1 + n)``::

        W form:  V = (v - m1 / (3 (1+n)) sn^3 R_J(cn^2, dn^2, 1, p)) / (1 + n)
        Y form:  V = (v + n m1 / (3 (1+n)) sn^3 R_J(cn^2, dn^2, 1, p)) / (1 + n)

    which is well conditioned there. Switching at ``dn(u_r)^2 = sqrt(m1)`` bounds the loss by
    about ``eps / m1^(1/4)``.
    """
    n, m, m1 = mo.n, mo.m, mo.m1
    sn3 = sn * sn * sn
    if mo.y_form:
        P = _p_y(n, m)
        z = ((m / (3.0 * n)) * sn3 * sp.elliprj(cn * cn, dn * dn, 1.0, 1.0 + (m / n) * sn * sn)
             + np.arctan2(P * sn, cn * dn) / P)
    else:
        z = (sn3 / 3.0) * sp.elliprj(cn * cn, dn * dn, 1.0, 1.0 + n * sn * sn)
    far = dn * dn < np.sqrt(m1)
    if np.any(far):
        uf = ur[far]
        v = mo.K - np.abs(uf)
        s, c, d = jacobi(v, m1)
        c2, d2 = c * c, d * d
        rj = s * s * s * sp.elliprj(c2, d2, 1.0, (d2 + n * c2) / (1.0 + n))
        if mo.y_form:
            V = (v + (n * m1 / (3.0 * (1.0 + n))) * rj) / (1.0 + n)
        else:
            V = (v - (m1 / (3.0 * (1.0 + n))) * rj) / (1.0 + n)
        z[far] = np.sign(uf) * (mo.z_k - V)
    return z


def _evaluate(mo, t, angles):
    """Relabelled momentum ``g'(t)`` (shape ``t.shape + (3,)``) and, if ``angles``, the
    continuous 3-1-3 angles ``(phi, theta, psi)`` of ``B'`` relative to the ``G`` frame."""
    u = mo.lam * t + mo.u0
    a1, a2, a3 = mo.alpha
    if mo.kind == _SEPARATRIX:
        sech = _sech(u)
        th = np.tanh(u)
        gp = np.stack([mo.s1 * a1 * sech, a2 * th, a3 * sech], axis=-1)
        if not angles:
            return gp, None
        phi = (mo.gabs / mo.J[2] + mo.c / (1.0 + mo.n)) * t   # = |G|/J1 - c n/(1+n), no cancellation
        if mo.n > 0.0:
            rn = np.sqrt(mo.n)
            phi = phi + (mo.c * rn / (mo.lam * (1.0 + mo.n))) * np.arctan(rn * th)
        psi = np.arctan2(gp[..., 0], gp[..., 1])  # g'1 keeps its sign: no wrap
    else:
        K2 = 2.0 * mo.K
        k = np.rint(u / K2)
        ur = u - k * K2
        sn, cn, dn = jacobi(ur, mo.m1)
        flip = np.where(np.fmod(k, 2.0) == 0.0, 1.0, -1.0)
        gp = np.stack([a1 * cn * flip, a2 * sn * flip, a3 * dn], axis=-1)
        if not angles:
            return gp, None
        if mo.y_form:   # phi = |G| t / J3 + (c / lam) Y(u)
            rate, coef = mo.gabs / mo.J[2], mo.c / mo.lam
        else:           # phi = |G| t / J1 - (c n / lam) W(u)
            rate, coef = mo.gabs / mo.J[0], -mo.c * mo.n / mo.lam
        phi = rate * t
        if coef != 0.0:
            phi = phi + coef * (k * (2.0 * mo.z_k) + _z_reduced(mo, ur, sn, cn, dn))
        # -pi k keeps psi continuous; k mod 4 (q_z(psi) has period 4 pi) keeps it small, so
        # that g' and the body's orientation about it stay consistent to round-off at any t
        psi = np.arctan2(a1 * np.abs(cn), a2 * sn) - np.pi * np.fmod(k, 4.0)
    theta = np.arctan2(np.hypot(gp[..., 0], gp[..., 1]), gp[..., 2])
    return gp, (phi, theta, psi)


def _euler_quaternion(phi, theta, psi):
    """``q_z(phi) q_x(theta) q_z(psi)`` as a product: ``phi`` grows without bound while
    ``psi`` stays small, and the combined ``phi + psi`` of eq. (12) would lose ``psi`` (the
    orientation of the body about ``g``) to round-off at large ``t``."""
    h = 0.5 * np.asarray(phi)
    z = np.zeros_like(h)
    return qt.mul(np.stack([np.cos(h), z, z, np.sin(h)], axis=-1), qt.from_euler313(0.0, theta, psi))


# ---- public API ---------------------------------------------------------------------------
def torque_free_momentum(inertia, g0, t):
    """Body angular momentum of the torque-free rigid body, in Jacobi elliptic functions.

    Solves Euler's equations ``dg/dt = g x (I^-1 g)`` exactly (module docstring, step 1),
    in either regime (``D = |g|^2 / 2T`` above or below the middle moment), on the
    separatrix, for steady spins and for symmetric bodies.

    Parameters
    ----------
    inertia : RigidBody or array_like, shape (3,)
        Principal moments ``(I1, I2, I3)`` (internal inertia unit: kg km^2, or plain numbers
        for a dimensionless body), positive, in any order.
    g0 : array_like, shape (3,)
        Angular momentum at ``t = 0`` in **body** components (internal momentum unit).
    t : array_like
        Times (internal time unit, s or dimensionless) relative to the epoch of ``g0``; any
        shape, any order, negative allowed.

    Returns
    -------
    g : ndarray, shape ``t.shape + (3,)``
        Body angular momentum at ``t`` (body components, momentum unit).

    Raises
    ------
    InputError
        Wrong shapes, non-finite values, non-positive moments, Quantities.
    """
    I = _inertia(inertia)
    g0 = _vector(g0, "g0", 3, "body angular momentum (g1, g2, g3)")
    t = _times(t)
    mo = _motion(I, g0)
    if mo.kind == _STEADY:
        return np.broadcast_to(g0, t.shape + (3,)).copy()
    gp, _ = _evaluate(mo, t.ravel(), False)
    return (gp @ mo.M).reshape(t.shape + (3,))


def torque_free(inertia, q0, Q0, t):
    """Exact torque-free motion ``(q(t), Q(t))`` in the canonical variables of eq. (7).

    Parameters
    ----------
    inertia : RigidBody or array_like, shape (3,)
        Principal moments ``(I1, I2, I3)`` (kg km^2, or plain numbers for a dimensionless
        body), positive, in any order; equal moments allowed.
    q0 : array_like, shape (4,)
        Attitude at ``t = 0``, scalar first, body -> space (``x_S = q x_B q~``). Normally a
        unit quaternion; a non-unit one keeps its norm (the exact flow of eq. 7).
    Q0 : array_like, shape (4,)
        Conjugate momentum at ``t = 0`` (kg km^2 s^-1, or plain numbers), ``Q0 = 2 q0 g0``
        with ``g0`` the body angular momentum. A radial component ``q0.Q0 != 0`` is an
        invariant of the exact flow and is carried along unchanged:
        ``Q(t) = 2 q(t) g(t) + (q0.Q0) q(t)`` (for a unit ``q0``).
    t : array_like
        Times relative to the epoch of ``(q0, Q0)`` (s, or dimensionless); any shape, any
        order, negative values and 0 allowed.

    Returns
    -------
    q : ndarray, shape ``t.shape + (4,)``
        Attitude (body -> space, scalar first). Continuous in ``t`` and equal to ``q0`` (not
        ``-q0``) at ``t = 0``: the branch an integrator of eq. (7) produces.
    Q : ndarray, shape ``t.shape + (4,)``
        Conjugate momentum, same unit as ``Q0``.

    Raises
    ------
    InputError
        Wrong shapes, non-finite values, a zero ``q0``, non-positive moments, Quantities.

    Notes
    -----
    Method (Jacobi elliptic functions for ``g``, 3-1-3 angles about the constant ``G`` for
    the attitude, Carlson's ``R_J`` for the precession angle) and accuracy: see
    :mod:`orbatt.analytic`. Space angular momentum ``G = 1/2 Im(Q q~)`` and the energy are
    constant to round-off. Cost is linear in the number of times (about 0.1 s per 1e5).
    Plain moments are not checked against the triangle inequality (a :class:`RigidBody`
    is); the formulas hold for any positive moments.
    """
    I = _inertia(inertia)
    q0 = _vector(q0, "q0", 4, "attitude quaternion, scalar first")
    Q0 = _vector(Q0, "Q0", 4, "conjugate momentum Q = 2 q g")
    t = _times(t)
    shape = t.shape
    t = t.ravel()
    rho2 = float(q0 @ q0)
    if rho2 == 0.0:
        raise InputError(f"q0: the zero quaternion {q0.tolist()} is not an attitude; give a unit "
                         "quaternion (scalar first)")
    rho = np.sqrt(rho2)
    qhat0 = q0 / rho
    w0 = qt.mul(qt.conj(q0), Q0)        # (q0.Q0, 2 g0): both invariant / evolving parts
    radial = w0[0]
    g0 = 0.5 * w0[1:]
    mo = _motion(I, g0)
    if mo.kind == _STEADY:
        qhat = qt.mul(qhat0, qt.exp(qt.pure(0.5 * mo.omega * t[..., None])))
        g = np.broadcast_to(g0, t.shape + (3,))
    else:
        gp, (phi, theta, psi) = _evaluate(mo, t, True)
        _, (phi0, theta0, psi0) = _evaluate(mo, np.zeros(1), True)
        mu = qt.from_matrix(mo.M.T)                   # q' = q mu maps B' to S
        qe0 = _euler_quaternion(phi0[0], theta0[0], psi0[0])
        q_G = qt.mul(qt.mul(qhat0, mu), qt.conj(qe0))  # q'(0) = q_G qe(0)
        qhat = qt.mul(qt.mul(q_G, _euler_quaternion(phi, theta, psi)), qt.conj(mu))
        g = gp @ mo.M
    q = rho * qhat
    w = np.concatenate([np.full(t.shape + (1,), radial), 2.0 * g], axis=-1)
    Q = qt.mul(q, w) / rho2
    return q.reshape(shape + (4,)), Q.reshape(shape + (4,))
