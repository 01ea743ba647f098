"""The symplectic splitting of the coupled binary (orbatt.core.mutual_splitting): its order,
the total angular momentum to round-off, bounded energy error, impulses on the grid."""
import numpy as np
import pytest
from test_binary_physics import P_ORBIT, binary_system, tilted_state

from orbatt.binary import Impulse, binary_content, propagate_binary
from orbatt.errors import InputError


@pytest.fixture(scope="module")
def case():
    s = binary_system(rigid=True)
    y0 = tilted_state(s)
    t = np.linspace(0.0, 4 * P_ORBIT, 5)
    ref = propagate_binary(s, y0, t, rtol=1e-14, atol=1e-18)
    return s, y0, t, ref


@pytest.mark.parametrize("composition,order", [("yoshida4", 4), ("yoshida6", 6)])
def test_order_and_invariants(case, composition, order):
    s, y0, t, ref = case
    errs = []
    for m in (150, 300):
        tr = propagate_binary(s, y0, t, method="splitting", step=P_ORBIT / m, composition=composition)
        errs.append(np.max(np.linalg.norm(tr.y[:, :3] - ref.y[:, :3], axis=1)) / 1.19)
        ds = binary_content(tr)
        L = ds["angular_momentum_total"].values
        assert np.max(np.linalg.norm(L - L[0], axis=1)) / np.linalg.norm(L[0]) < 2e-13   # round-off
        assert np.max(np.abs(ds["q_norm_error"].values)) < 1e-13
    assert errs[0] / errs[1] > 2 ** order * 0.7, errs


def test_energy_bounded_over_many_orbits():
    """No drift: the energy error over the last of 40 orbits is not larger than over the first."""
    s = binary_system(rigid=True)
    y0 = tilted_state(s)
    t = np.linspace(0.0, 40 * P_ORBIT, 401)
    tr = propagate_binary(s, y0, t, method="splitting", step=P_ORBIT / 100, composition="yoshida4")
    E = binary_content(tr)["energy"].values
    dE = np.abs(E - E[0]) / abs(E[0])
    assert dE[-10:].max() < 3 * dE[:11].max() and dE.max() < 2e-8


def test_impulse_on_the_grid_matches_dop853():
    s = binary_system(rigid=False)
    y0 = tilted_state(s)
    t = np.linspace(0.0, 2 * P_ORBIT, 9)
    imp = [Impulse(t[3], (1e-6, -2e-6, 5e-7))]
    a = propagate_binary(s, y0, t, impulses=imp, rtol=1e-13, atol=1e-17)
    b = propagate_binary(s, y0, t, impulses=imp, method="splitting", step=(t[1] - t[0]) / 100,
                         composition="yoshida6")
    assert np.max(np.linalg.norm(a.y[:, :3] - b.y[:, :3], axis=1)) / 1.19 < 1e-8
    with pytest.raises(InputError, match="step"):
        propagate_binary(s, y0, t, method="splitting", step=(t[1] - t[0]) / 100.5)
