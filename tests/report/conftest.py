"""A small scenario for the report's tests: two start temperatures, 2600 s, short dwells
(a study of it trains and tabulates in seconds)."""

from __future__ import annotations

import pytest

from nfs.config.scenario import load_scenario

SMALL = """name = "small"
seed = 5
start_temperatures_c = [-20.0, 40.0]
duration_s = 2600.0
[schedule]
positions_deg = [0.0, 90.0, 180.0, 270.0]
dwell_s = 150.0
move_s = 10.0
"""


@pytest.fixture(scope="module")
def small_scenario(tmp_path_factory):
    """The small scenario, loaded from a file as a user's is."""
    p = tmp_path_factory.mktemp("small") / "small.toml"
    p.write_text(SMALL)
    return load_scenario(p)
