"""Test configuration shared by the whole suite."""
from hypothesis import settings

# The first call of a numba kernel compiles it (or loads its cache), which can take longer
# than hypothesis' default 200 ms deadline on a loaded 2-core CI machine: no deadline.
settings.register_profile("orbatt", deadline=None)
settings.load_profile("orbatt")
