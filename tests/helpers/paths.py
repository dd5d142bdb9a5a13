"""Where the tests' files are, for a test at any depth of tests/: the checkout, its sources, examples and fixtures."""

from pathlib import Path

TESTS = Path(__file__).resolve().parents[1]
REPO = TESTS.parent
SRC = REPO / "src"
EXAMPLES = REPO / "examples"
FIXTURES = TESTS / "fixtures"
#: Screenshots and pages the browser tests leave for a person to look at (ignored by git).
ARTIFACTS = TESTS / "artifacts"
