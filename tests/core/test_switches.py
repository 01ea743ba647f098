"""Steps that land on switches (:mod:`orbatt.core.switches`, issue 25): the located switch
times against the roots of the switching functions sampled every millisecond along the run,
the anti-chatter rule on an edge-on facet, resumability, and accuracy per right-hand side."""
from __future__ import annotations

import numpy as np
import pytest

from orbatt import quaternion as qt
from orbatt.canonical import momentum_from_omega
from orbatt.core import dop853 as kd
from orbatt.core import kepler
from orbatt.core import model as km
from orbatt.core import potentials as kp
from orbatt.core import switches as ksw
from orbatt.core import torques as trq
from orbatt.environment.tables import Pieces, piece_table, piece_times

GM = 398600.4418
ORB = kepler.orbit_vector(6778.0, 0.001, 0.9, 0.3, 0.2, 0.1, np.sqrt(GM / 6778.0**3))
#: a 3U cubesat's inertia, kg km^2
I3U = np.array([3.87e-8, 3.87e-8, 0.67e-8])
NORMALS = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], dtype=float)
EXPONENTIAL = (2e-3, 400.0, 60.0, 6378.137)  # kg km^-3 at 400 km, scale height 60 km


def _facets():
    """The six faces of a 3U box (areas km^2), centre of pressure 2 cm off along axis 3."""
    F = np.zeros((6, trq.FACET_SIZE))
    F[:, 0] = [0.034e-6] * 4 + [0.01e-6] * 2
    F[:, 1:4] = NORMALS
    F[:, 4:7] = NORMALS * 0.05e-3 + np.array([0.0, 0.0, 0.02e-3])
    F[:, 7] = 0.1
    F[:, 8] = 0.3
    return F


def _sun_table(t1):
    """A fixed Sun (km, inertial) placed so that the orbit crosses the Earth's shadow."""
    ts = piece_times(-100.0, t1 + 100.0, Pieces(t1, 3))
    return piece_table(ts, np.tile([1.496e8 * 0.6, 1.496e8 * 0.8, 0.0], (ts.size, 1)), 3)


def _model(t1, shadow=km.SHADOW_CONICAL, srp=True):
    F = _facets()
    terms = [(km.GRAVITY_GRADIENT, [GM], None), (km.DRAG, km.drag_params(F, 0.0, EXPONENTIAL), None)]
    if srp:
        terms.append((km.SRP, km.srp_params(F, 4.5e-3, 1.495978707e8, shadow, 6378.137, 696000.0), _sun_table(t1)))
    return km.build(orbit=(km.ORBIT_KEPLER, ORB, None), terms=terms)


def _run(model, y0, t_out, record_all, switches=True, budget=10**9, rtol=1e-10, max_step=np.inf):
    """``(t, Y, cnt)`` of the compiled single loop: every step end (``record_all``) or the
    outputs ``t_out``."""
    terms = model[0].copy()
    if not switches:
        terms[0, km.FLAGS] |= km.NO_SWITCHES
    y = np.array(y0, dtype=np.float64)
    st, cnt, f0 = kd.new_state()
    work = kp.new_work()
    cap = 200000 if record_all else len(t_out)
    rec_t = np.empty(cap)
    out = np.empty((cap, 8))
    while True:
        status = kd.advance(y, st, cnt, f0, t_out, rec_t, out, record_all, I3U, terms, model[1], model[2], work,
                            rtol, rtol, max_step, 10**8, budget)
        if status != kd.PAUSED:
            break
    assert status == kd.DONE
    n = int(cnt[kd.CNT_NREC]) if record_all else len(t_out)
    return (rec_t[:n].copy() if record_all else t_out), out[:n].copy(), cnt.copy()


def _tumbling(scale=1.0):
    """A state tumbling at ``scale`` times (0.03, 0.02, 0.05) rad/s (body axes)."""
    q0 = qt.normalize(np.array([1.0, 0.2, 0.1, -0.3]))
    return np.r_[q0, momentum_from_omega(q0, scale * np.array([0.03, 0.02, 0.05]), I3U)]


def _values(model, t, Y):
    """The switching functions at the samples ``(t, Y)``: ``(N, n)``."""
    n = ksw.switch_count(model[0], model[1])
    g = np.empty((len(t), kp.MAX_SWITCHES))
    work = kp.new_work()
    for i in range(len(t)):
        ksw.switch_values(t[i], Y[i, :4], *model, work, g[i])
    return g[:, :n]


def _roots(t, g):
    """The zeros of each sampled function (columns of ``g``): bisection down to the sampling,
    then the zero of the chord inside the last interval."""
    out = []
    for k in range(g.shape[1]):
        s = np.sign(g[:, k])
        for i in np.nonzero((s[1:] * s[:-1]) < 0)[0]:
            lo, hi = i, i + 1
            out.append((t[lo] + (t[hi] - t[lo]) * g[lo, k] / (g[lo, k] - g[hi, k]), k))
    return sorted(out)


def test_the_switching_functions_are_the_facets_cosines_and_the_shadow_edges():
    """Each facet's function is n . v^ (drag) or n . s^ (SRP) in body axes, computed here from
    the orbit's velocity and the Sun's table (NaN where the term vanishes: the SRP facets in the
    umbra); the penumbra edge is zero where the shadow function leaves 1."""
    model = _model(6000.0)
    F = _facets()
    q = qt.normalize(np.array([0.3, -0.5, 0.2, 0.7]))
    n = ksw.switch_count(model[0], model[1])
    assert n == 6 + 6 + 3
    g = np.empty(kp.MAX_SWITCHES)
    ksw.switch_values(2000.0, q, *model, kp.new_work(), g)
    assert np.isnan(g[6:12]).all() and np.isfinite(g[:6]).all()  # in the umbra: no SRP, no switch
    for t in (10.0, 1000.0):
        assert ksw.switch_values(t, q, *model, kp.new_work(), g) == n
        _, _, _, pos, vel = kepler.kepler_many(np.array([t]), ORB, GM)
        vb = qt.rotate_inv(q, vel[0] / np.linalg.norm(vel[0]))
        d = np.array([1.496e8 * 0.6, 1.496e8 * 0.8, 0.0]) - pos[0]
        sb = qt.rotate_inv(q, d / np.linalg.norm(d))
        np.testing.assert_allclose(g[:6], F[:, 1:4] @ vb, atol=1e-12)
        np.testing.assert_allclose(g[6:12], F[:, 1:4] @ sb, atol=1e-12)
    # the outer edge's zero along the orbit is where the shadow function leaves 1
    t = np.linspace(0.0, 6000.0, 6001)
    edge = _values(model, t, np.tile(q, (t.size, 1)))[:, 12]
    from orbatt.environment.sun import shadow
    _, _, _, pos, _ = kepler.kepler_many(t, ORB, GM)
    nu = shadow(pos, np.array([1.496e8 * 0.6, 1.496e8 * 0.8, 0.0]), kind="conical", body_radius=6378.137)
    assert np.any(edge < 0) and np.any(edge > 0)
    np.testing.assert_array_equal(edge >= 0, nu == 1.0)


def test_steps_land_on_the_zeros_of_the_facets_and_shadow_switching_functions():
    """A tumbling cubesat with drag and SRP over an eclipse's entry: every zero of every
    switching function, found by bisection on the run sampled every millisecond, is a step end
    to within 1 ms of the sampling (to a few 1e-4 s: the landing is on the step's cubic
    interpolant); without the location they fall anywhere inside steps of seconds."""
    y0 = _tumbling()
    t0, T = 1760.0, 1920.0  # the penumbra from 1838 s, the umbra from 1847 s
    model = _model(T + 10.0)
    t_rec, _, cnt = _run(model, y0, np.array([t0, T]), True)
    _, _, cnt_off = _run(model, y0, np.array([t0, T]), True, switches=False)
    assert cnt[kd.CNT_SWITCHES] > 0 and cnt_off[kd.CNT_SWITCHES] == 0
    tf = t0 + 1e-3 * np.arange(1, int(round((T - t0) / 1e-3)) + 1)
    tf, Yf, _ = _run(model, y0, np.r_[t0, tf], False)
    roots = _roots(tf, _values(model, tf, Yf))
    kinds = {k for _, k in roots}
    assert {0, 1, 6, 7} <= kinds or len(kinds) >= 6  # several facets of both terms
    assert 12 in kinds  # the penumbra's edge
    miss = np.array([np.min(np.abs(t_rec - r)) for r, _ in roots])
    assert miss.max() < 1e-3
    assert np.median(miss) < 1e-4
    t_off, _, _ = _run(model, y0, np.array([t0, T]), True, switches=False)
    miss_off = np.array([np.min(np.abs(t_off - r)) for r, _ in roots])
    assert np.median(miss_off) > 0.05


def test_an_edge_on_facet_is_one_switch_not_thousands():
    """A body at rest on an equatorial orbit (facets without torque: it stays at rest) whose
    end facets 5, 6 have their normals along the orbit normal: edge-on to the flow for the
    whole run. Tilted by 1e-5 rad, their cos theta crosses zero twice an orbit (amplitude 1e-5,
    below the re-arming threshold): that costs at most one retake each over the exactly
    edge-on run (cos theta = 0, no switch), not one per crossing; the side facets, which the
    flow turns through twice an orbit, switch in both (steps of at most 60 s: a step end sees
    each zero)."""
    h = kepler.orbit_vector(6778.0, 0.0, 0.0, 0.0, 0.0, 0.0, np.sqrt(GM / 6778.0**3))  # equatorial: normal z
    T = 6 * 5550.0
    y0 = np.r_[1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
    runs = {}
    for tilt in (0.0, 1e-5):
        F = _facets()
        F[:, 4:7] = 0.0
        F[4:, 1:4] = [[tilt, 0.5 * tilt, 1.0], [tilt, 0.5 * tilt, -1.0]]  # zeros apart from the side facets
        F[4:, 1:4] /= np.linalg.norm(F[4:, 1:4], axis=1)[:, None]
        model = km.build(orbit=(km.ORBIT_KEPLER, h, None),
                         terms=[(km.DRAG, km.drag_params(F, 0.0, EXPONENTIAL), None)])
        _, _, cnt = _run(model, y0, np.array([T]), True, max_step=60.0)
        t = np.linspace(0.0, T, 20001)
        runs[tilt] = (_values(model, t, np.tile(y0, (t.size, 1))), cnt)
    g0, c0 = runs[0.0]
    g1, c1 = runs[1e-5]
    assert np.abs(g0[:, 4:6]).max() == 0.0
    assert np.abs(g1[:, 4:6]).max() < 2e-5
    assert int(np.sum(np.sign(g1[1:, 4]) != np.sign(g1[:-1, 4]))) == 12  # twice an orbit
    assert c0[kd.CNT_SWITCHES] >= 20  # the side facets' 24 zeros (pairs at once)
    assert c1[kd.CNT_SWITCHES] <= c0[kd.CNT_SWITCHES] + 2
    assert c1[kd.CNT_STEPS] <= c0[kd.CNT_STEPS] + 2


def test_a_paused_run_continues_as_if_it_had_not_stopped():
    """Budgets of 3 attempts a call (pauses between a located switch and the step that lands
    on it included) give the bits of one call."""
    y0 = _tumbling()
    model = _model(2000.0)
    t_out = np.linspace(1760.0, 1920.0, 9)
    _, Y1, c1 = _run(model, y0, t_out, False)
    _, Y2, c2 = _run(model, y0, t_out, False, budget=3)
    np.testing.assert_array_equal(Y1, Y2)
    np.testing.assert_array_equal(c1[:kd.CNT_FLAGS], c2[:kd.CNT_FLAGS])
    assert c1[kd.CNT_SWITCHES] == c2[kd.CNT_SWITCHES] > 0


@pytest.mark.parametrize("shadow", [km.SHADOW_CYLINDRICAL, km.SHADOW_CONICAL])
def test_location_is_more_accurate_per_right_hand_side(shadow):
    """The cubesat tumbling at ~0.01 rad/s over an eclipse's entry, with and without location,
    against a reference at rtol 1e-13 (located): with location the error is 10x smaller (3x at
    the cylindrical shadow's jump in the torque, which the step lands just past) for fewer
    right-hand sides, and the rejected steps fall below 5 % of the attempts. Measured with the
    Sun's piece table: conical 4.8e-7 -> 9.3e-9 rad, cylindrical 9.5e-7 -> 2.7e-7 rad, 18 %
    fewer right-hand sides."""
    y0 = _tumbling(0.3)
    model = _model(3200.0, shadow)
    t_out = np.linspace(1000.0, 3000.0, 11)
    _, Yref, _ = _run(model, y0, t_out, False, rtol=1e-13)
    err, nfev = {}, {}
    for sw in (False, True):
        _, Y, c = _run(model, y0, t_out, False, switches=sw, rtol=1e-10)
        err[sw] = np.abs(Y[:, :4] - Yref[:, :4]).max()
        nfev[sw] = c[kd.CNT_NFEV]
        attempts = c[kd.CNT_STEPS] + c[kd.CNT_REJECTED] + c[kd.CNT_SWITCHES]
        if sw:
            assert c[kd.CNT_REJECTED] < 0.05 * attempts
        else:
            assert c[kd.CNT_REJECTED] > 0.2 * attempts
    assert err[True] < (0.1 if shadow == km.SHADOW_CONICAL else 0.35) * err[False]
    assert nfev[True] < nfev[False]


def test_models_without_switches_do_not_change():
    """The gravity gradient alone: no switching function, the same bits with the location's
    flag on and off (the switch code folds away)."""
    model = km.build(orbit=(km.ORBIT_KEPLER, ORB, None), terms=[(km.GRAVITY_GRADIENT, [GM], None)])
    assert ksw.switch_count(model[0], model[1]) == 0
    y0 = _tumbling()
    t_out = np.linspace(500.0, 3000.0, 6)
    _, Y1, c1 = _run(model, y0, t_out, False)
    _, Y2, c2 = _run(model, y0, t_out, False, switches=False)
    np.testing.assert_array_equal(Y1, Y2)
    np.testing.assert_array_equal(c1, c2)


@pytest.mark.parametrize("kind", ["conical", "cylindrical"])
def test_eclipse_times_are_the_shadow_functions_edges(kind):
    """The eclipse entries and exits (the outer shadow edge's zeros along the orbit) against
    a bisection of the shadow function itself (orbatt.environment.sun.shadow, numpy) on the
    Keplerian positions: entry where it leaves 1, exit where it comes back; a window that
    begins or ends inside an eclipse has no entry or no exit there (NaN)."""
    from orbatt.environment.sun import shadow

    sun = np.array([1.496e8 * 0.6, 1.496e8 * 0.8, 0.0])
    model = _model(11000.0, km.SHADOW_CONICAL if kind == "conical" else km.SHADOW_CYLINDRICAL)

    def lit(t):
        _, _, _, pos, _ = kepler.kepler_many(np.atleast_1d(np.asarray(t, dtype=float)), ORB, GM)
        return shadow(pos, sun, kind=kind, body_radius=6378.137, sun_radius=696000.0) == 1.0

    def bisect(lo, hi):
        a = lit(lo)[0]
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            if lit(mid)[0] == a:
                lo = mid
            else:
                hi = mid
        return 0.5 * (lo + hi)

    t = np.arange(0.0, 11000.0, 1.0)
    s = lit(t)
    edges = [bisect(t[i], t[i + 1]) for i in np.nonzero(s[1:] != s[:-1])[0]]
    assert len(edges) == 4 and s[0]
    entry, exit_ = ksw.eclipse_times(*model, 0.0, 11000.0)
    np.testing.assert_allclose(entry, edges[0::2], rtol=0, atol=1e-6)
    np.testing.assert_allclose(exit_, edges[1::2], rtol=0, atol=1e-6)
    entry, exit_ = ksw.eclipse_times(*model, 2000.0, 8000.0)  # from inside the first to inside the second
    np.testing.assert_allclose(entry, [np.nan, edges[2]], rtol=0, atol=1e-6)
    np.testing.assert_allclose(exit_, [edges[1], np.nan], rtol=0, atol=1e-6)
    model_none = _model(11000.0, km.SHADOW_NONE)
    assert [x.size for x in ksw.eclipse_times(*model_none, 0.0, 11000.0)] == [0, 0]


def test_the_eclipse_times_in_the_dataset_and_its_file(tmp_path):
    """A scenario with SRP and the conical shadow: ``eclipse_entry`` / ``eclipse_exit`` are UTC
    datetimes, the epoch plus the eclipse times of the scenario's model, and come back from the
    NetCDF file (written through xarray and by ``orbatt run``'s direct writer) as they were;
    every entry is followed by its exit ~36 min later (a LEO eclipse)."""
    import warnings
    from pathlib import Path

    import orbatt
    from orbatt.dataset.netcdf import write_netcdf

    path = Path(__file__).resolve().parents[2] / "scenarios" / "iss-tle-disturbances.toml"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sc = orbatt.load_scenario(path)
        content = sc.run_content()
    ds = content.to_dataset()
    entry, exit_ = ds["eclipse_entry"].values, ds["eclipse_exit"].values
    assert entry.dtype == np.dtype("datetime64[ns]") and entry.size == exit_.size >= 1
    epoch = np.datetime64(ds.attrs["epoch"].rstrip("Z"), "ns")
    t0, t1 = float(ds["elapsed"].values[0]), float(ds["elapsed"].values[-1])
    e, x = ksw.eclipse_times(*sc.potential.kernel_model(), t0, t1)
    ok = ~np.isnan(e)
    np.testing.assert_allclose((entry[ok] - epoch) / np.timedelta64(1, "s"), e[ok], rtol=0, atol=1e-6)
    both = ~np.isnat(entry) & ~np.isnat(exit_)
    assert both.any()
    minutes = (exit_[both] - entry[both]) / np.timedelta64(60, "s")
    assert np.all((minutes > 25) & (minutes < 40))
    for name, form in (("xarray.nc", ds), ("direct.nc", content)):
        write_netcdf(form, tmp_path / name)
        back = orbatt.open_dataset(tmp_path / name)
        for v in ("eclipse_entry", "eclipse_exit"):
            np.testing.assert_array_equal(back[v].values, ds[v].values)
            assert back[v].attrs == ds[v].attrs
