"""The repository's paths for the tests, whatever the depth of the test file's folder."""
from pathlib import Path

#: The repository's root.
ROOT = Path(__file__).resolve().parents[2]
#: The tests' folder.
TESTS = ROOT / "tests"
