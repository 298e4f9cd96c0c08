"""Shared by the Python tests that run the firmware preset's image on hmc-emu (imported, not run):
without the image the test is skipped (exit 77), unless CI=true, where it must have been built
and its absence fails, as cli/sim_test_lib.sh's require_built does for the shell tests."""
import os
import sys


def require_image(path):
    if os.path.isfile(path):
        return
    if os.environ.get("CI") == "true":
        sys.exit(f"FAIL: no firmware image {path} (build the firmware preset first)")
    print(f"SKIP: no firmware image {path}")
    sys.exit(77)
