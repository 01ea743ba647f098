"""Test configuration shared by the whole suite."""
from hypothesis import settings

# The first call of a numba kernel compiles it (or loads its cache), which can take longer
# than hypothesis' default 200 ms deadline on a loaded 2-core CI machine: no deadline.
settings.register_profile("orbatt", deadline=None)
settings.load_profile("orbatt")


import warnings
from pathlib import Path

import pytest

SHIPPED = Path(__file__).parent.parent / "scenarios"


@pytest.fixture(scope="session")
def shipped_outputs(tmp_path_factory):
    """``{name: path}``: the NetCDF file of every shipped scenario's run (written once per
    session; the nominal case of a sweep scenario)."""
    import orbatt

    out = tmp_path_factory.mktemp("shipped")
    files = {}
    for toml in sorted(SHIPPED.glob("*.toml")):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # e.g. the paper's periapsis inside the Earth
            ds = orbatt.load_scenario(toml).run()
        files[toml.stem] = out / f"{toml.stem}.nc"
        ds.orbatt.to_netcdf(files[toml.stem])
    return files
