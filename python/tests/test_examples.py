# examples/python/: each maker's script runs to its end against sim://.
import os
import subprocess
import sys

import pytest

SCRIPTS = {
    "timelapse_slider.py": ["--frames", "4", "--settle", "0"],
    "pan_tilt_scan.py": ["--pan", "30", "90", "--tilt", "-20", "--dwell", "0"],
    "status_monitor.py": ["--demo", "--duration", "1", "--every", "0.25"],
}


@pytest.mark.parametrize("script", sorted(SCRIPTS))
def test_example_runs(script, examples, sim_url):
    path = os.path.join(examples, "python", script)
    done = subprocess.run([sys.executable, path, "--port", sim_url(), *SCRIPTS[script]],
                          capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    assert done.stdout.startswith("board: simulated board")
    if script == "timelapse_slider.py":
        assert "frame 4/4 at 300.00 mm (24000 steps)" in done.stdout
    if script == "pan_tilt_scan.py":
        assert "view pan 90.0 deg, tilt -20.0 deg" in done.stdout and "scan done" in done.stdout
    if script == "status_monitor.py":
        assert "event: motor 3" in done.stdout
