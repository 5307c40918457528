"""`python -m swarmgen.conformance [--update] [--no-qt] [--irp DIR]`: run the W3C SCXML IRP
tests on swarmgen's engine and in Qt SCXML, and compare with (or, with `--update`, rewrite)
tests/conformance/irp_expected.json and docs/conformance.md. Exit 1 when a result differs."""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path

from swarmgen.conformance import irp, qt, report

ROOT = Path(__file__).resolve().parents[2]
RESULTS = ROOT / "tests" / "conformance" / "irp_expected.json"
DOC = ROOT / "docs" / "conformance.md"


def default_irp() -> Path:
    """The IRP copy of the reference corpus (`SWARMGEN_REFERENCE_DIR`, else ../shared)."""
    reference = os.environ.get("SWARMGEN_REFERENCE_DIR") or ROOT.parent / "shared" / "reference"
    return Path(reference).resolve() / "w3c_irp"


def main(argv: list[str] | None = None) -> int:
    """Run the set; compare with the checked-in results or rewrite them."""
    parser = argparse.ArgumentParser(prog="python -m swarmgen.conformance")
    parser.add_argument("--update", action="store_true", help="rewrite the results and the doc")
    parser.add_argument("--no-qt", action="store_true", help="keep Qt's results from the file")
    parser.add_argument("--irp", type=Path, default=None, help="the w3c_irp directory")
    args = parser.parse_args(argv)
    where = args.irp or default_irp()
    if not (where / "manifest.xml").is_file():
        print(f"no IRP manifest in {where}", file=sys.stderr)
        return 2
    tests = irp.tests(where)
    ours = irp.run_all(where)
    expected = json.loads(RESULTS.read_text(encoding="utf-8")) if RESULTS.is_file() else None
    if args.no_qt and expected is not None:
        theirs = {k: irp.Outcome(v["qt"], v["qt_detail"]) for k, v in expected["tests"].items()}
    else:
        theirs = qt.run_all(where)
    got = report.results(tests, ours, theirs)
    if args.update:
        RESULTS.parent.mkdir(parents=True, exist_ok=True)
        RESULTS.write_text(report.dumps(got), encoding="utf-8")
        DOC.write_text(report.markdown(got), encoding="utf-8")
        print(f"wrote {RESULTS.relative_to(ROOT)} and {DOC.relative_to(ROOT)}")
        return 0
    changed = report.differences(expected, got) if expected is not None else ["no results file"]
    for line in changed:
        print(line)
    return 1 if changed else 0


if __name__ == "__main__":
    sys.exit(main())
