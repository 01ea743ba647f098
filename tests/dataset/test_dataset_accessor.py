"""The ``ds.orbatt`` accessor (issue 5): Quantities, unit conversion, refusals, plots."""
import numpy as np
import pytest
from astropy import units as u

import orbatt
from orbatt import dataset as D
from orbatt.errors import InputError
from orbatt.trajectory import Trajectory

from dataset_support import EPOCH, I_PAPER, P0_PAPER, Q0_PAPER, _every_units_parses, _propagate, _tangent


def test_plots(free_ds, orbit_ds, tmp_path):
    mpl = pytest.importorskip("matplotlib")
    mpl.use("Agg")
    import matplotlib.pyplot as plt

    fig = free_ds.orbatt.plot_state()
    axl, axr = fig.axes
    assert len(axl.lines) == 4 and len(axr.lines) == 4
    assert np.array_equal(axl.lines[0].get_ydata(), free_ds["q"].values[:, 0])
    assert np.array_equal(axr.lines[3].get_ydata(), free_ds["Q"].values[:, 3])
    fig.savefig(tmp_path / "state.png")
    fig2 = orbit_ds.orbatt.plot_attitude()
    assert len(fig2.axes) == 2 and len(fig2.axes[1].lines) == 3
    assert np.allclose(fig2.axes[0].lines[1].get_ydata(), np.degrees(orbit_ds["euler_313"].values[:, 1]))
    fig3 = free_ds.orbatt.plot_drift()
    assert len(fig3.axes) == 3
    fig3.savefig(tmp_path / "drift.png")
    plt.close("all")


def test_dimensional_units_and_omega_in_deg_per_s():
    body = orbatt.RigidBody([400, 500, 600] * u.kg * u.km**2)
    t = np.linspace(0.0, 100.0, 11)
    ds = D.to_dataset(_propagate(body, Q0_PAPER, _tangent(Q0_PAPER, P0_PAPER), orbatt.TorqueFree(), t))
    _every_units_parses(ds)
    expect = {"elapsed": "s", "q": "1", "Q": "kg m^2 s^-1", "omega": "rad s^-1", "g": "kg m^2 s^-1",
              "G": "kg m^2 s^-1", "energy": "J", "kinetic_energy": "J",
              "potential_energy": "J", "q_norm_error": "1", "qQ": "kg m^2 s^-1",
              "euler_313": "rad", "inertia": "kg m^2"}
    for name, units in expect.items():
        assert ds[name].attrs["units"] == units, name
    assert not ds.orbatt.dimensionless
    w = ds["omega"].values
    da = ds.orbatt.to("omega", "deg/s")
    assert da.attrs["units"] == "degree s^-1"
    assert np.allclose(da.values, np.degrees(w), rtol=1e-15, atol=0)
    assert np.allclose(ds.orbatt.quantity("omega").to_value(u.deg / u.s), np.degrees(w), rtol=1e-15, atol=0)
    assert ds["omega"].attrs["units"] == "rad s^-1"  # the dataset is unchanged
    qd = ds.orbatt.quantity("energy")
    assert qd.unit == u.J
    assert np.allclose(qd.to_value(u.kg * u.km**2 / u.s**2), ds["energy"].values * 1e-6, rtol=1e-15)
    assert ds.orbatt.unit("time") == u.s and np.array_equal(ds.orbatt.quantity("time").value, t)
    conv = ds.orbatt.convert(omega=u.deg / u.s, euler_313="degree")
    assert conv["euler_313"].attrs["units"] == "degree"
    assert np.allclose(conv["euler_313"].values, np.degrees(ds["euler_313"].values), rtol=1e-15)
    assert ds.orbatt.times().unit == u.s  # no epoch: a Quantity


def test_dimensionless_refuses_physical_units(free_ds):
    with pytest.raises(InputError, match="cannot convert"):
        free_ds.orbatt.to("omega", "deg/s")
    with pytest.raises(InputError, match="not a variable"):
        free_ds.orbatt.quantity("nope")
    with pytest.raises(InputError, match="dimensionless"):
        D.to_dataset(Trajectory(body=orbatt.RigidBody(I_PAPER), potential=orbatt.TorqueFree(), t=np.zeros(1),
                                q=Q0_PAPER[None], Q=P0_PAPER[None], inertia=I_PAPER, method="x"), epoch=EPOCH)
