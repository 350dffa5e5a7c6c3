"""Runs this directory's pytest suite for ctest; exits 77 (skipped) when pytest or numpy is missing."""
import sys

try:
    import numpy  # noqa: F401
    import pytest
except ImportError as e:
    print(f"SKIP: {e} (tools/bootstrap.sh installs python3-pytest and python3-numpy)")
    sys.exit(77)

# -p no:cacheprovider: write nothing into the source tree.
sys.exit(pytest.main(["-q", "-p", "no:cacheprovider", "--durations=5", sys.argv[1]]))
