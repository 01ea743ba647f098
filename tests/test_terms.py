"""The torque terms' descriptors (:mod:`orbatt.terms`, issue 22): the scenario keys, their
reference rows, the model's rows and the Dataset's fields all come from :data:`TERMS`, and
the one assembler (:mod:`orbatt.model_assembly`) packs the potential's, the wheels' and the
control law's rows as they are."""
from __future__ import annotations

import inspect

import numpy as np
import pytest
from astropy import units as u
from astropy.time import Time

import orbatt
from orbatt import terms
from orbatt.control import reaction_wheel, wheels_row
from orbatt.laws import LAWS, control_law
from orbatt.core import kinds
from orbatt.core import model as km
from orbatt.environment.atmosphere import PiecewiseExponentialAtmosphere
from orbatt.environment.magnetic import DipoleField
from orbatt.errors import InputError
from orbatt.model_assembly import assemble, model_rows
from orbatt.scenario import parse
from orbatt.scenario.ranges import RANGES
from orbatt.scenario.schema import KEY_DOCS
from orbatt.scenario.torques_schema import TORQUE_KEYS, torque_arguments
from orbatt.shipped import shipped_file
from orbatt.torques import TERM_KEYWORDS, TERM_NAMES, EnvironmentTorques, Facet, facet

EPOCH = Time("2025-03-20T00:00:00", scale="utc")
ORBIT = orbatt.KeplerOrbit(6778.137 * u.km, 0.001, 51.6 * u.deg, 30 * u.deg, 0 * u.deg, epoch=EPOCH)
FACETS = [Facet(0.05 * u.m**2, [1.0, 0.0, 0.0], [0.05, 0.0, 0.02] * u.m, 2.2, 0.1, 0.3),
          Facet(0.02 * u.m**2, [0.0, 0.0, -1.0], [0.0, 0.01, -0.15] * u.m, 2.2, 0.0, 0.2)]
EVERY_TERM = dict(facets=FACETS, drag=True, srp=True, residual_dipole=[0.01, 0.0, 0.003] * u.A * u.m**2,
                  constant_torque=[1e-7, 0.0, -2e-7] * u.N * u.m, atmosphere=PiecewiseExponentialAtmosphere(),
                  magnetic_field=DipoleField(EPOCH))
WHEELS = [orbatt.ReactionWheel(a, "4e-5 kg m2", "1000 rpm") for a in np.eye(3)]


def _env(**kw):
    return EnvironmentTorques(ORBIT, 600 * u.s, **{**EVERY_TERM, **kw})


def test_every_torque_kind_has_one_descriptor_in_kernel_order():
    codes = [t.kind.code for t in terms.TERMS]
    # every kind that is not a control law or the heavy top (its own potential, HeavyTop)
    assert sorted(codes) == sorted(k.code for k in kinds.BY_NAME.values() if k.code != km.HEAVY_TOP)
    assert codes == sorted(codes)  # the rows' order: the kinds' codes
    assert all(TERM_NAMES[t.kind.code] == t.name for t in terms.TERMS)


def test_the_scenario_keys_and_their_docs_come_from_the_descriptors():
    keys = [k.key for t in terms.TERMS for k in t.keys]
    assert TORQUE_KEYS == set(keys) and list(KEY_DOCS["torques"]) == keys
    params = inspect.signature(EnvironmentTorques).parameters
    for t in terms.TERMS:
        for k in t.keys:
            assert KEY_DOCS["torques"][k.key] == (k.dimension, k.default, k.meaning)
            assert k.argument in params or k.argument in TERM_KEYWORDS, k  # the keyword the key becomes exists
            if k.kind == "vector":
                assert RANGES["torques", k.key].text() == f"|x| <= {k.range[0]:g}".replace("e+", "e") + f" {k.unit}"
    given = {"drag": True, "residual_dipole": np.array([1.0, 0.0, 0.0])}
    args = torque_arguments(given)
    assert set(args) == {k.argument for t in terms.TERMS for k in t.keys}
    for key, (_, k) in terms.BY_KEY.items():
        value = args[k.argument]
        if key not in given:
            assert value is None
        elif k.kind == "vector":  # a Quantity in the key's unit, the same numbers
            assert value.unit == u.Unit(k.unit) and np.array_equal(value.value, given[key])
        else:
            assert value is given[key]


def test_a_term_keyword_beyond_the_named_ones_is_checked():
    with pytest.raises(TypeError, match="unexpected keyword argument 'constant_toque'"):
        EnvironmentTorques(None, None, gravity_gradient=False, constant_toque=[0.0, 0.0, 1.0] * u.N * u.m)


def test_the_model_holds_the_enabled_terms_in_descriptor_order_and_the_fields_theirs():
    env = _env()
    assert env.term_names == [t.name for t in terms.TERMS if t.enabled(env)]
    assert env.term_names[:5] == ["gravity_gradient", "drag", "srp", "magnetic", "constant"]
    t = np.linspace(0.0, 600.0, 7)
    fields = env.fields(t)
    assert set(fields) == {f.name for t in terms.TERMS if t.enabled(env) for f in t.fields}
    assert {"density", "sun_direction", "shadow", "magnetic_field"} <= set(fields)
    for name in fields:
        dims = terms.FIELD_VARIABLES[name][0]
        assert fields[name].shape == t.shape + tuple(3 for _ in dims)
    assert np.allclose(np.linalg.norm(fields["sun_direction"], axis=-1), 1.0, rtol=0, atol=1e-12)
    only = _env(drag=False, srp=False, residual_dipole=None, facets=())
    assert only.term_names == ["gravity_gradient", "constant"] and only.fields(t) == {}


def test_the_assembler_packs_the_potentials_rows_then_the_wheels_then_the_law():
    law = orbatt.PDControl("sun", kp="5e-4 N m", kd="8e-2 N m s", target_axis=[0, 0, 1], actuator="wheels")
    env = _env(control=law)
    body = orbatt.RigidBody([12.0, 10.0, 6.0] * u.kg * u.m**2, wheels=WHEELS)
    terms_, params, table = assemble(env, [body])
    own = env.kernel_model()
    orbit_row, rows = model_rows(own)
    expected = km.build(orbit=orbit_row, terms=rows + [wheels_row(WHEELS), law.row(WHEELS, env.field_table("sun"))])
    for a, b in zip((terms_, params, table), expected):
        assert a.dtype == b.dtype and np.array_equal(a, b)
    # the potential's own rows unchanged, then WHEELS and PD_CONTROL; the law reads the SRP term's Sun table
    n = own[0].shape[0]
    assert np.array_equal(terms_[:n, :km.R1 + 1], own[0][:, :km.R1 + 1])
    assert list(terms_[n:, km.KIND]) == [km.WHEELS, km.PD_CONTROL]
    srp, pd = (next(j for j in range(1, terms_.shape[0]) if terms_[j, km.KIND] == k) for k in (km.SRP, km.PD_CONTROL))
    assert np.array_equal(table[terms_[srp, km.R0]:terms_[srp, km.R1]], table[terms_[pd, km.R0]:terms_[pd, km.R1]])
    assert terms_[0, km.FLAGS] & km.EXTENDED
    # without wheels or a law the assembler gives the potential's own model
    plain = assemble(_env(), [orbatt.RigidBody([12.0, 10.0, 6.0] * u.kg * u.m**2)])
    for a, b in zip(plain, _env().kernel_model()):
        assert np.array_equal(a, b)


def test_a_scenario_holds_plain_settings_and_the_objects_check_them():
    """``Spec`` holds plain data (the objects are built from it, and check it once)."""
    spec = parse(shipped_file("lvlh-hold-wheels").read_text(), "lvlh-hold-wheels.toml")

    def plain(x):
        if isinstance(x, dict):
            return all(isinstance(k, str) and plain(v) for k, v in x.items())
        if isinstance(x, list):
            return all(plain(v) for v in x)
        return x is None or isinstance(x, (str, bool, int, float)) or (isinstance(x, np.ndarray) and x.dtype == float)

    assert plain(spec.control), spec.control
    disturbances = parse(shipped_file("cubesat-3u-disturbances").read_text(), "cubesat-3u-disturbances.toml")
    assert plain(disturbances.torques), disturbances.torques
    assert [facet(f).settings() for f in disturbances.torques["facets"]] == disturbances.torques["facets"]
    law = control_law(spec.control["control"])
    assert isinstance(law, orbatt.PDControl) and law.settings() == spec.control["control"]
    assert [reaction_wheel(w).settings() for w in spec.control["wheels"]] == spec.control["wheels"]
    for name, law in LAWS.items():  # every law's keys are its class's keywords and its settings' keys
        assert law.cls.law == name
        assert set(law.units) <= set(inspect.signature(law.cls).parameters)
    with pytest.raises(InputError, match=r"^law: 'lqr'"):
        control_law({"law": "lqr", "kp": 1.0})
    with pytest.raises(InputError, match=r"^kp: not read by law = 'bdot'"):
        control_law({"law": "bdot", "gain": 1.0, "max_dipole": 0.1, "kp": 1.0})
