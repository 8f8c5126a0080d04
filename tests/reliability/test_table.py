"""The bad-input table in RELIABILITY.md is what the code gives today."""
import difflib

from make_table import current, table


def test_reliability_table_matches_the_code():
    want, have = table(), current()
    diff = "".join(difflib.unified_diff(have.splitlines(True), want.splitlines(True),
                                        "RELIABILITY.md", "make_table.py", n=0))
    assert have == want, ("the table in RELIABILITY.md is stale; run "
                          "`.venv/bin/python tests/reliability/make_table.py`\n" + diff[:4000])
