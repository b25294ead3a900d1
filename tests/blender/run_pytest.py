"""Runs the Blender test suite inside Blender:

    blender -b --factory-startup --python-exit-code 1 --python tests/blender/run_pytest.py -- [pytest args]

Uses this checkout's add-on (addon/lantern) and the library in LANTERN_LIBRARY (set by
scripts/run_tests.sh), never an installed copy. Exits with pytest's code; "no tests ran" fails.
"""
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(os.path.dirname(HERE))
for path in (os.path.join(REPO, "scenes"), HERE, os.path.join(REPO, "addon")):
    if path not in sys.path:
        sys.path.insert(0, path)

import lantern  # noqa: E402  (the checkout's add-on, first on sys.path)
import pytest  # noqa: E402

lantern.register()
args = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
code = int(pytest.main([HERE, "-p", "no:cacheprovider"] + args))
sys.exit(1 if code == 5 else code)
