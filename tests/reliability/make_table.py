"""Write the "input tried -> what it gets" table of RELIABILITY.md from the test cases.

Every row is a case of tests/reliability/rel_cases.py, run now, with the message the code
really gives; tests/reliability/test_table.py fails when the table in RELIABILITY.md is
not what this script would write (so it cannot drift from the code).

    .venv/bin/python tests/reliability/make_table.py           # rewrite the table
    .venv/bin/python tests/reliability/make_table.py --check   # exit 1 if it is stale
"""
from __future__ import annotations

import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from rel_cases import all_cases, names_field, outcome  # noqa: E402

DOC = HERE.parents[1] / "RELIABILITY.md"
START, END = "<!-- bad-input:start -->", "<!-- bad-input:end -->"
ENTRIES = {
    "Params": "Python API: `Params(...)`",
    "simulate": "Python API: `simulate(Params(), ...)` (work ceiling 200k steps / 20k impacts)",
    "bifurcation": "Python API: `bifurcation(Params(), name, values, ...)`",
    "regime_map": "Python API: `regime_map(Params(), name_x, values_x, name_y, values_y, ...)`",
    "CLI": "Command line: `python -m impactlib ...`",
    "URL": "App, URL query (a new session from the link)",
    "widget": "App, widget value (typed or dragged, from a good scene)",
}


def _cell(text: str) -> str:
    return " ".join(str(text).split()).replace("|", "\\|")


def verdict(case, got) -> str:
    if got.kind == "crash":
        return "**crash**"
    if case.fields:
        named = all(names_field(got.message, f) for f in case.fields)
        ok = got.kind == "rejected" and named
        kept = "" if case.entry not in ("URL", "widget") else (
            ", scene kept" if case.entry == "widget" and got.kept else
            ", default scene shown" if got.kept else ", **no scene**")
        return ("rejected, names " + ", ".join(f"`{f}`" for f in case.fields) + kept
                if ok else "**not rejected as expected**")
    return {"runs": "runs", "partial": "partial result + message"}.get(got.kind, got.kind)


def table() -> str:
    lines = []
    cases = all_cases()
    for entry, title in ENTRIES.items():
        rows = [c for c in cases if c.entry == entry]
        if not rows:
            if entry == "CLI":
                lines += [f"**{title}**: not available in this checkout.", ""]
            continue
        lines += [f"**{title}**", "", "| input tried | outcome | what it gets (verbatim) |",
                  "|---|---|---|"]
        for c in rows:
            got = outcome(c.id)
            lines.append(f"| {_cell(c.tried)} | {verdict(c, got)} | {_cell(got.message)} |")
        lines.append("")
    return "\n".join(lines).rstrip() + "\n"


def current() -> str:
    body = DOC.read_text()
    return body.split(START, 1)[1].split(END, 1)[0].strip("\n") + "\n"


def write() -> None:
    body = DOC.read_text()
    head, rest = body.split(START, 1)
    _, tail = rest.split(END, 1)
    DOC.write_text(f"{head}{START}\n{table()}{END}{tail}")


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if "--check" in argv:
        stale = current() != table()
        print("RELIABILITY.md table is stale: run tests/reliability/make_table.py"
              if stale else "RELIABILITY.md table is current")
        return 1 if stale else 0
    write()
    print(f"wrote the table into {DOC}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
