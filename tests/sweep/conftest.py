"""A short scenario for sweep tests: two start temperatures, 40 min runs (the start-up stage
its first 30 min, the stable stage the last 10: the shortest stages inside the typical ranges
of nfs.ranges)."""

import pytest

SHORT_SCENARIO = """\
name = "short"
instrument = "default"
seed = 0
start_temperatures_c = [-20.0, 30.0]
duration_s = 2400.0
latitude_deg = 30.0
true_heading_deg = 40.0

[schedule]
positions_deg = [0.0, 90.0, 180.0, 270.0]
dwell_s = 100.0
move_s = 10.0

[northfind]
startup_end_s = 1800.0
stable_start_s = 1800.0
"""


@pytest.fixture
def short_scenario(tmp_path):
    """Path of the short scenario file (in tmp_path)."""
    p = tmp_path / "short.toml"
    p.write_text(SHORT_SCENARIO, encoding="utf-8")
    return p

