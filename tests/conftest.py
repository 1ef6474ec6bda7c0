import os
import sys

sys.path.insert(0, os.path.dirname(__file__))

from hypothesis import HealthCheck, settings  # noqa: E402

settings.register_profile("default", deadline=None, suppress_health_check=[HealthCheck.too_slow])
settings.register_profile("ci", deadline=None, suppress_health_check=[HealthCheck.too_slow],
                          derandomize=True)
settings.load_profile("ci" if os.environ.get("CI") else "default")


import pytest  # noqa: E402


@pytest.fixture(scope="session")
def heavy_scale() -> str:
    """'full' with PRS_HEAVY=full, else 'reduced' (what CI runs for tests marked heavy)."""
    return "full" if os.environ.get("PRS_HEAVY") == "full" else "reduced"
