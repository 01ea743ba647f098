"""The ECSS-E-ST-60-10C pointing indices (issue 33 item 4; docs/pointing-budgets.md) against
their definitions: the windows and window means recomputed by brute force, the mean and
relative indices of a sinusoid plus a bias, the 99.73 % quantile of Gaussian noise (3 sigma),
the three statistical interpretations on ensembles whose answers are known by construction,
the refusals, and a sweep's ape / rpe / mpe equal to the quantiles of the single run of a case."""
from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest

from orbatt import pointing as P
from orbatt.errors import InputError

SCEN = Path(__file__).resolve().parents[1] / "scenarios"


def _brute_windows(t, window):
    """Window of each output and the mean of each complete window, by the definition, with loops."""
    t0, t1 = t[0], t[-1]
    which = []
    for ti in t:
        k = 0
        while not (t0 + k * window <= ti < t0 + (k + 1) * window):
            k += 1
        which.append(k if t0 + (k + 1) * window <= t1 else -1)
    return np.array(which)


def _brute_mean(t, e, window):
    which = _brute_windows(t, window)
    out = np.full(e.shape, np.nan)
    for i, k in enumerate(which):
        if k < 0:
            continue
        members = [e[j] for j in range(t.size) if which[j] == k]
        out[i] = sum(members) / len(members)
    return out


# ---- windows --------------------------------------------------------------------------------

def test_windows_are_consecutive_from_the_first_output_and_the_partial_tail_is_left_out():
    t = np.arange(0.0, 101.0)  # 0 .. 100 s
    k = P.window_index(t, 10.0)
    assert np.array_equal(k[:100], np.repeat(np.arange(10), 10))
    assert k[100] == -1  # the output at 100 s starts window 10, which the run does not finish
    t = np.arange(0.0, 107.0)
    assert np.array_equal(P.window_index(t, 10.0), np.r_[np.repeat(np.arange(10), 10), [-1] * 7])


def test_non_uniform_window_means_equal_the_brute_force_definition():
    rng = np.random.default_rng(7)
    t = 3.0 + np.cumsum(rng.uniform(0.05, 1.0, 400))
    e = rng.normal(size=400)
    window = 17.3
    assert np.array_equal(P.window_index(t, window), _brute_windows(t, window))
    mean = _brute_mean(t, e, window)
    ok = ~np.isnan(mean)
    assert np.count_nonzero(~ok) > 0  # a partial tail exists in this draw
    np.testing.assert_allclose(P.mpe(t, e, window)[ok], np.abs(mean[ok]), rtol=1e-13, atol=1e-15)
    np.testing.assert_allclose(P.rpe(t, e, window)[ok], np.abs(e - mean)[ok], rtol=1e-13, atol=1e-15)
    assert np.all(np.isnan(P.rpe(t, e, window)[~ok])) and np.all(np.isnan(P.mpe(t, e, window)[~ok]))
    np.testing.assert_array_equal(P.ape(e), np.abs(e))


def test_sinusoid_plus_bias_mean_is_the_bias_and_relative_amplitude_the_sine_amplitude():
    bias, amp, period, window = 2e-4, 5e-5, 7.3, 60.0  # rad, rad, s, s (not a whole number of periods)
    t = np.arange(0.0, 3000.0 + 1e-9, 0.01)
    e = bias + amp * np.sin(2 * np.pi * t / period)
    averaging = amp * period / (np.pi * window)  # the most a window's mean of the sine can be
    m = P.mpe(t, e, window)
    ok = ~np.isnan(m)
    assert np.all(np.abs(m[ok] - bias) <= averaging + 1e-12)
    r = P.rpe(t, e, window)
    assert abs(np.nanmax(r) - amp) <= averaging + 1e-9
    # the temporal 99.73 % value of |RPE| of a sine: amp |sin| exceeded 0.27 % of the time
    expect = amp * np.sin(np.pi / 2 * (1 - 0.0027))  # |sin| <= x a fraction 2/pi asin(x)
    assert abs(P.quantile(r, 0.9973) - expect) <= averaging + 1e-9
    assert P.quantile(m, 0.9973) == pytest.approx(bias, abs=averaging)
    # a whole number of periods in each window: the sine averages out to rounding
    e2 = bias + amp * np.sin(2 * np.pi * t / 6.0)
    np.testing.assert_allclose(P.mpe(t, e2, window)[ok], bias, rtol=0, atol=1e-15)


def test_vectors_take_the_norm_of_the_componentwise_mean_and_difference():
    t = np.arange(0.0, 1200.0, 0.5)
    w = 2 * np.pi * t / 30.0  # 4 periods per 120 s window
    e = np.stack([1e-3 + 2e-4 * np.sin(w), 2e-4 * np.cos(w), np.full_like(t, -5e-4)], axis=1)
    ok = P.window_index(t, 120.0) >= 0
    # |mean e| of the window, not the mean of |e|: the rotating part averages out
    np.testing.assert_allclose(P.mpe(t, e, 120.0)[ok], math.hypot(1e-3, 5e-4), rtol=1e-12)
    np.testing.assert_allclose(P.rpe(t, e, 120.0)[ok], 2e-4, rtol=1e-9)
    np.testing.assert_allclose(P.ape(e), np.sqrt((e * e).sum(axis=1)), rtol=1e-15)
    assert np.array_equal(P.index_series("rke", t, e, 120.0), P.rpe(t, e, 120.0), equal_nan=True)
    assert np.array_equal(P.index_series("ake", t, e), P.ape(e))


def test_drift_between_windows_of_a_linear_error():
    t = np.arange(0.0, 1000.0, 1.0)
    e = 3e-6 * t + 1e-4
    d = P.pde(t, e, 100.0, 200.0)
    k = P.window_index(t, 100.0)
    assert np.all(np.isnan(d[k < 2]))
    np.testing.assert_allclose(d[k >= 2], 3e-6 * 200.0, rtol=1e-12)


# ---- the quantile -----------------------------------------------------------------------------

def test_gaussian_noise_99_73_percent_is_three_sigma():
    sigma = 1e-4
    x = np.random.default_rng(20261128).normal(0.0, sigma, 1_000_000)
    # sampling error of the quantile of |x|: sqrt(p (1-p) / n) / (2 phi(3) / sigma) = 0.006 sigma
    assert abs(P.quantile(P.ape(x), 0.9973) - 3.0 * sigma) < 0.03 * sigma
    # the stated definition: the smallest |x| with a fraction >= P_C at or below it
    v = P.quantile(x, 0.9973)
    a = np.abs(x)
    assert np.mean(a <= v) >= 0.9973 and np.mean(a < v) < 0.9973


def test_quantile_reads_the_confidence_as_its_decimal():
    x = np.arange(1.0, 10001.0)
    assert P.quantile(x, 0.9973) == 9973.0  # k = 10000 * 0.9973 exactly
    assert P.quantile(np.arange(1.0, 11.0), 0.9) == 9.0  # 0.9 is 9/10, not its binary neighbour above
    assert P.quantile(np.arange(1.0, 11.0), 0.95) == 10.0
    assert P.quantile(-np.arange(1.0, 11.0), 0.5) == 5.0  # of |x|
    assert P.quantile([np.nan, 2.0, np.nan, 1.0], 0.5) == 1.0  # NaN left out
    assert math.isnan(P.quantile([np.nan], 0.5))
    rng = np.random.default_rng(3)
    for n in (1, 2, 7, 100, 1001):
        y = np.abs(rng.normal(size=n))
        for p in (0.5, 0.9, 0.9973):
            assert P.quantile(y, p) == np.quantile(y, p, method="inverted_cdf")


# ---- statistical interpretations --------------------------------------------------------------

def test_interpretations_on_ensembles_built_to_separate_them():
    rng = np.random.default_rng(11)
    small = rng.uniform(0.0, 1.0, (10, 100))
    common = small.copy()
    common[:, 5] = 7.0  # every case spikes at the same time
    assert P.ensemble_quantile(common, 0.9) == 7.0  # that time: every case at 7
    np.testing.assert_array_equal(P.temporal_quantile(common, 0.9),
                                  [np.sort(np.abs(row))[89] for row in common])  # one spike in 100: below 1
    assert P.mixed_quantile(common, 0.9) == np.sort(common.ravel())[899] < 1.0
    one_case = small.copy()
    one_case[0] = 5.0  # one case is off at all times
    assert P.temporal_quantile(one_case, 0.9)[0] == 5.0
    assert P.ensemble_quantile(one_case, 0.9) == max(np.sort(col)[8] for col in one_case.T) < 1.0
    assert P.mixed_quantile(one_case, 0.9) == np.sort(small[1:].ravel())[-1]  # 900th of 1000: the largest small
    assert P.interpreted_quantile(one_case, 0.9, "mixed") == P.mixed_quantile(one_case, 0.9)
    nan_time = small.copy()
    nan_time[:, -3:] = np.nan  # a trailing partial window: no value at those times
    assert P.ensemble_quantile(nan_time, 0.9) == max(np.sort(col)[8] for col in small[:, :-3].T)


def test_mixed_value_lies_between_the_cases_and_below_the_ensemble_value():
    rng = np.random.default_rng(5)
    for _ in range(50):
        x = np.abs(rng.standard_t(3, (rng.integers(2, 9), rng.integers(5, 60)))) * rng.uniform(0.1, 3, (1, 1))
        p = float(rng.choice([0.5, 0.9, 0.9973]))
        lo, hi = P.mixed_bounds(P.temporal_quantile(x, p))
        mixed = P.mixed_quantile(x, p)
        assert lo <= mixed <= hi
        assert P.ensemble_quantile(x, p) >= mixed


# ---- refusals ---------------------------------------------------------------------------------

@pytest.mark.parametrize("window, match", [(101.0, "longer than the run"), (1.5, "at least two outputs"),
                                           (0.0, "positive"), (math.nan, "positive"), (-3.0, "positive")])
def test_bad_windows_are_refused(window, match):
    t = np.arange(0.0, 101.0, 2.0)
    with pytest.raises(InputError, match=f"stability_window.*{match}"):
        P.rpe(t, np.zeros_like(t), window)


def test_a_window_with_one_output_among_non_uniform_outputs_is_refused():
    t = np.array([0.0, 1.0, 2.0, 3.0, 10.0, 21.0, 22.0, 30.0])  # window [10, 20) holds one output
    with pytest.raises(InputError, match="1 output"):
        P.window_means(t, np.zeros_like(t), 10.0)


@pytest.mark.parametrize("confidence", [0.0, 1.0, 1.5, -0.1, True, "0.9", math.nan])
def test_bad_confidence_is_refused(confidence):
    with pytest.raises(InputError, match="confidence"):
        P.quantile([1.0, 2.0], confidence)


def test_bad_series_separation_and_interpretation_are_refused():
    t = np.arange(0.0, 100.0)
    with pytest.raises(InputError, match="e: expected"):
        P.rpe(t, np.zeros((100, 2)), 10.0)
    with pytest.raises(InputError, match="strictly increasing"):
        P.rpe(t[::-1], np.zeros(100), 10.0)
    with pytest.raises(InputError, match="multiple of the window"):
        P.pde(t, np.zeros(100), 10.0, 15.0)
    with pytest.raises(InputError, match="interpretation"):
        P.interpreted_quantile(np.zeros((2, 3)), 0.9, "spatial")
    with pytest.raises(InputError, match="needs the stability window"):
        P.index_series("rpe", t, np.zeros(100))


# ---- the [sweep] keys and a sweep's outputs ---------------------------------------------------

def _nadir_hold(t_end="600 s"):
    """The shipped nadir-hold Monte Carlo (PD law on wheels), without its environment torques
    and facets, over ``t_end`` with 10 s outputs, and without its [sweep] table."""
    text = (SCEN / "nadir-hold-montecarlo.toml").read_text()
    text = text[:text.index("[sweep]")]
    text = re.sub(r"\[torques\].*?(?=\n\[initial\])", "", text, flags=re.S)
    text = re.sub(r"\[\[body\.facets\]\].*?(?=\n\[\[body\.wheels\]\])", "", text, flags=re.S)
    text = re.sub(r"^t_end = .*$", f't_end = "{t_end}"', text, flags=re.M)
    return re.sub(r"^output_step = .*$", 'output_step = "10 s"', text, flags=re.M)


GRID = '[sweep.parameters]\nomega1 = { values = ["0.5 deg/s", "0.2 deg/s"] }\n'


def _parse(sweep):
    from orbatt.scenario import parse

    return parse(_nadir_hold() + "[sweep]\n" + sweep + GRID, "mc.toml")


@pytest.mark.parametrize("sweep, where, match", [
    ('outputs = ["rpe"]\n', r"\[sweep\] stability_window", "'rpe' needs it"),
    ('outputs = ["ape"]\nconfidence = 1.0\n', r"\[sweep\] confidence", r"outside \(0, 1\)"),
    ('outputs = ["ape"]\nconfidence = 0\n', r"\[sweep\] confidence", r"outside \(0, 1\)"),
    ('outputs = ["final_state"]\nconfidence = 0.99\n', r"\[sweep\] confidence", "only used with"),
    ('outputs = ["ape"]\nrequirement = { rpe = "1 deg" }\n', r"requirement\.rpe", "add it to \\[sweep\\] outputs"),
    ('outputs = ["ape"]\nrequirement = { xyz = "1 deg" }\n', r"requirement\.xyz", "not a pointing index"),
    ('outputs = ["ape"]\nrequirement = { ape = "10 s" }\n', r"requirement\.ape", ""),
    ('outputs = ["ape"]\nrequirement = { ape = "-1 deg" }\n', r"requirement\.ape", "positive"),
    ('outputs = ["ape"]\nrequirement = "1 deg"\n', r"\[sweep\] requirement", "inline table"),
])
def test_sweep_keys_are_checked_where_they_enter(sweep, where, match):
    from orbatt.scenario import ScenarioError

    with pytest.raises(ScenarioError, match=f"{where}.*{match}"):
        _parse(sweep)


def test_sweep_keys_are_read_in_internal_units():
    spec = _parse('outputs = ["ape", "rpe"]\nstability_window = "1 min"\nconfidence = 0.95\n'
                  'requirement = { ape = "0.5 deg", rpe = "36 arcsec" }\n').sweep
    assert spec.stability_window == 60.0 and spec.confidence == 0.95
    assert spec.requirement == pytest.approx({"ape": math.radians(0.5), "rpe": math.radians(0.01)}, rel=1e-14)
    assert _parse('outputs = ["ape"]\n').sweep.confidence == 0.9973


def test_sweep_indices_equal_the_quantiles_of_the_single_runs():
    from orbatt.dataset.pointing_budget import budget_lines, pointing_budget
    from orbatt.dataset.sweep_figures import sweep_figures_of
    from orbatt.scenario import Scenario, parse
    from orbatt.sweep import Sweep

    text = _nadir_hold()
    table = ('[sweep]\noutputs = ["ape", "rpe", "mpe"]\nstability_window = "60 s"\n'
             'requirement = { rpe = "6.2 deg" }\n' + GRID)
    ds = Sweep(Scenario(parse(text + table, "mc.toml")), seed=1).compute()
    for k, w1 in enumerate(("0.5 deg/s", "0.2 deg/s")):
        one = Scenario(parse(text.replace('omega = ["0.5 deg/s"', f'omega = ["{w1}"'), "case.toml")).run()
        qo = one["q_orbital"].values  # the PD law's target is the orbital frame
        perr = 2 * np.arctan2(np.sqrt((qo[:, 1:] ** 2).sum(axis=-1)), np.abs(qo[:, 0]))
        t = one["elapsed"].values
        means = _brute_mean(t, perr, 60.0)
        assert ds["ape"].values[k] == pytest.approx(np.sort(perr)[math.ceil(perr.size * 0.9973) - 1], rel=1e-12)
        rel = np.abs(perr - means)[~np.isnan(means)]
        assert ds["rpe"].values[k] == pytest.approx(np.sort(rel)[math.ceil(rel.size * 0.9973) - 1], rel=1e-9)
        mean = np.abs(means)[~np.isnan(means)]
        assert ds["mpe"].values[k] == pytest.approx(np.sort(mean)[math.ceil(mean.size * 0.9973) - 1], rel=1e-12)
    assert ds["rpe"].attrs["requirement_rad"] == pytest.approx(math.radians(6.2))
    assert ds["rpe"].attrs["confidence"] == 0.9973 and ds["rpe"].attrs["stability_window"] == 60.0
    rows = {r["name"]: r for r in pointing_budget(ds)}
    assert rows["rpe"]["meeting"] == int(np.count_nonzero(ds["rpe"].values <= math.radians(6.2)))
    assert rows["ape"]["mixed"] == (ds["ape"].values.min(), ds["ape"].values.max())
    text_lines = "\n".join(budget_lines(ds))
    assert f"{np.degrees(ds['mpe'].values.max()):.4g}" in text_lines and "ensemble" in text_lines
    assert "budget" in sweep_figures_of(ds)


def test_a_window_with_too_few_outputs_names_the_sweep_key():
    from orbatt.scenario import Scenario, parse
    from orbatt.sweep import Sweep

    text = _nadir_hold("60 s") + '[sweep]\noutputs = ["rpe"]\nstability_window = "15 s"\n' + GRID
    with pytest.raises(InputError, match=r"\[sweep\] stability_window.*at least two outputs"):
        Sweep(Scenario(parse(text, "mc.toml")), seed=1).compute()


def test_info_prints_the_budget_and_plot_draws_it(tmp_path, capsys):
    from orbatt.cli import main

    p = tmp_path / "sw.toml"
    p.write_text(_nadir_hold() + '[sweep]\noutputs = ["ape", "rpe"]\nstability_window = "60 s"\n'
                 'requirement = { ape = "90 deg" }\n' + GRID)
    assert main(["sweep", str(p), "-o", str(tmp_path / "sw.nc"), "--scheduler", "synchronous", "--quiet"]) == 0
    capsys.readouterr()
    assert main(["info", str(tmp_path / "sw.nc")]) == 0
    out = capsys.readouterr().out
    budget = out[out.index("pointing budget"):]
    row = next(line for line in budget.splitlines() if line.split()[:1] == ["ape"])
    assert row.endswith("90  2 of 2")  # the requirement, and both cases meet it
    assert "ensemble value" in budget and "not computed" in budget
    assert main(["plot", str(tmp_path / "sw.nc"), "-o", str(tmp_path / "figs")]) == 0
    assert sorted(f.name for f in (tmp_path / "figs").iterdir()) == ["sw-budget.png", "sw-distributions.png",
                                                                      "sw-scatter.png"]
