"""The ``[sweep]`` table of a binary-asteroid scenario (``[orbit] provider = "coupled"``):
scenario keys varied by their paths (``"body.mass"``, ``"body.inertia[2]"``,
``"orbit.position[0]"``, ``"orbit.impulses[0].delta_v[1]"``, ``"primary.omega[2]"``), and the
per-case outputs of a binary (:data:`BINARY_OUTPUTS`). Manual: ``docs/sweeps.md``
(Binary asteroids).

The parameters, distributions, grid and seed are those of every sweep
(:func:`orbatt.scenario.sweep_schema.parse_sweep_table`); the named single-body parameters
(``inertia1``, ``orbit_a``, ...) and the pointing keys do not apply here: a binary varies its
keys by path.
"""
from __future__ import annotations

from .paths import ALIAS_PATHS
from .sweep_schema import PARAMETERS, parse_sweep_table

__all__ = ["BINARY_OUTPUTS", "BINARY_DEFAULT_OUTPUTS", "BINARY_SWEEP_KEYS", "parse_binary_sweep"]

#: the per-case outputs of a binary sweep (``docs/sweeps.md``: Binary asteroids), and the
#: Dataset variables each gives
BINARY_OUTPUTS = {
    "final_state": ("position_final", "velocity_final", "q_final", "omega_final", "q_primary_final",
                    "omega_primary_final"),
    "final_orbit": ("orbit_a_final", "orbit_e_final", "orbit_i_final", "orbit_period_final", "min_separation"),
    "conservation": ("max_energy_error", "max_angular_momentum_error"),
    "max_libration": ("max_libration_angle",),
    "mean_period": ("mean_period_initial", "mean_period_final"),
}
BINARY_DEFAULT_OUTPUTS = tuple(BINARY_OUTPUTS)
#: the keys of [sweep] a binary takes
BINARY_SWEEP_KEYS = ("parameters", "samples", "seed", "chunk_size", "outputs", "on_invalid")



def parse_binary_sweep(ctx, table, data, potential_kind="coupled"):
    """Validate the ``[sweep]`` table of a binary scenario.

    Parameters
    ----------
    ctx : FieldContext
        Error context (names the file).
    table : dict
        The TOML table.
    data : dict
        The whole scenario (TOML): the swept paths are looked up there.
    potential_kind : str
        ``[potential] kind``: ``"conservation"`` needs ``"coupled"`` (the only conservative one).

    Returns
    -------
    SweepSpec
        With ``outputs`` from :data:`BINARY_OUTPUTS` (default: all of them).

    Raises
    ------
    ScenarioError
        Naming ``[sweep] key`` or ``[sweep.parameters."path"]``, the value and the fix.
    """
    if not isinstance(table, dict):
        raise ctx.error("[sweep]", f"must be a table [sweep], got {table!r}")
    for k in table:
        if k not in BINARY_SWEEP_KEYS:
            raise ctx.error(f"[sweep] {k}", f"not used with [orbit] provider = 'coupled'; allowed keys in [sweep]: "
                                            f"{', '.join(BINARY_SWEEP_KEYS)}")
    raw = table.get("parameters")
    for name in raw if isinstance(raw, dict) else ():
        if name in PARAMETERS:
            alt = ALIAS_PATHS.get(name)
            fix = f'give it by its path, "{alt}"' if alt else 'vary the keys of [initial] by their paths ("initial.q[1]")'
            raise ctx.error(f"[sweep.parameters] {name}", f"the named parameters are those of a single body; in a "
                                                          f"binary scenario {fix}")
    outs = table.get("outputs", list(BINARY_DEFAULT_OUTPUTS))
    if not isinstance(outs, list) or not outs:
        raise ctx.error("[sweep] outputs", f"expected a non-empty list such as {list(BINARY_DEFAULT_OUTPUTS)}, "
                                           f"got {outs!r}")
    for o in outs:
        if not isinstance(o, str) or o not in BINARY_OUTPUTS:
            raise ctx.error("[sweep] outputs", f"{o!r} is not an output of a binary sweep; give some of "
                                               f"{', '.join(map(repr, BINARY_OUTPUTS))}")
    if "conservation" in outs and potential_kind != "coupled":
        raise ctx.error("[sweep] outputs", f"'conservation': nothing is conserved with [potential] kind = "
                                           f"{potential_kind!r} (the orbit does not feel the torque); remove it")
    rest = {k: v for k, v in table.items() if k != "outputs"}
    spec = parse_sweep_table(ctx, rest, dimensionless=False, potential_kind="coupled", orbit=None, frame="inertial",
                             conservative=False, data=data)
    spec.outputs = tuple(o for o in BINARY_OUTPUTS if o in outs)
    return spec
