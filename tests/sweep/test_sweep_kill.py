"""A sweep process killed midway keeps its finished cells; the rerun computes the rest."""

import io
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

from nfs.sweep import LocalExecutor, SweepProgress, load_sweep, run_sweep

ROOT = Path(__file__).resolve().parents[2]


def test_killed_sweep_reruns_only_the_missing_cells(tmp_path, short_scenario):
    sweep = tmp_path / "sweep.toml"
    sweep.write_text(f'scenario = "{short_scenario.name}"\nseeds = {{ first = 0, count = 12 }}\n'
                     "[axes]\nlatitude_deg = [20.0, 50.0]\n", encoding="utf-8")
    out = tmp_path / "out"
    env = {**os.environ, "PYTHONPATH": str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", "")}
    proc = subprocess.Popen([sys.executable, "-m", "nfs.cli", "sweep", str(sweep), "-o",
                             str(out), "--jobs", "1", "-q"], env=env,
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline and proc.poll() is None:
            if len(list((out / "cells").glob("*.json"))) >= 3:
                break
            time.sleep(0.02)
        proc.send_signal(signal.SIGKILL)
    finally:
        proc.wait()
    stored = len(list((out / "cells").glob("*.json")))
    spec = load_sweep(sweep)
    assert 3 <= stored < spec.n_cells == 24         # killed midway, finished cells kept whole
    res = run_sweep(spec, out, executor=LocalExecutor(1), quiet=True, figures=False)
    assert res.n_computed == spec.n_cells - stored
    assert res.n_rows == 24 * 2 * 2                 # cells x start temperatures x stages


def test_progress_off_a_terminal_is_a_line_every_tenth():
    buf = io.StringIO()
    p = SweepProgress(50, stream=buf, every_s=0.0)
    for _ in range(50):
        p.update()
    p.close()
    lines = buf.getvalue().splitlines()
    assert len(lines) == 10 and lines[-1].startswith("sweep: 50/50 cells")
    assert "cells/s" in lines[0] and "ETA" in lines[0]
