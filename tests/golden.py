"""The golden file (tests/golden.yaml): numbers this model produces, each pinned against
unintended change by tests/test_golden.py and read by the tests that check the same numbers
elsewhere (the command line, other BLAS kernels, the API).

Each case is data: its overrides, the one key it sweeps (``each``) and the summary keys it
pins (``values``). After an intended change of the model, regenerate the values and say why in
the commit::

    python tests/golden.py

The papers' claims are not here: tests/test_paper_table2.py and tests/test_irpm.py assert
them as claims, with their tolerances.
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

import yaml

FILE = Path(__file__).with_name("golden.yaml")
HEADER = """\
# Numbers this model produces (tests/golden.py says how each is made): pinned by
# tests/test_golden.py and read by the tests that check them elsewhere. Regenerate the values
# after an intended change with `python tests/golden.py` and say why in the commit.
# The papers' claims are not here: tests/test_paper_table2.py and tests/test_irpm.py.
"""


def cases() -> dict:
    """The golden file's cases by name."""
    return yaml.safe_load(FILE.read_text())


def values(name: str, key: str = "n_feasible") -> list:
    """The pinned values of ``key`` in case ``name``, one per value of its ``each`` key."""
    return cases()[name]["values"][key]


def compute(case: dict, catalogue) -> dict:
    """The values of ``case``'s keys as the model gives them today, one per value of its
    ``each`` key, each job run as the command line runs it: its analysis kind writes its files
    (``pipeline.app.job.JobFiles``) into a scratch folder, and every file it names exists."""
    from conftest import make_cfg

    from pipeline.app.job import JobFiles
    from pipeline.app.problem import ANALYSES, build_problem

    (key, settings), = case["each"].items()
    found = {name: [] for name in case["values"]}
    for setting in settings:
        cfg = make_cfg(*case["overrides"], f"{key}={setting}")
        problem, grid = build_problem(cfg, catalogue)
        with tempfile.TemporaryDirectory() as folder:
            files = JobFiles(Path(folder), "golden")
            summary = ANALYSES[cfg.analysis].files(cfg, problem, grid, files, False)
            assert files.written and all(path.is_file() for path in files.written), files.written
        for name in found:
            value = summary[name]
            found[name].append(value.item() if hasattr(value, "item") else value)  # numpy -> Python
    return found


def main() -> None:
    from pipeline.model.catalogue import load_catalogue

    catalogue = load_catalogue()
    every = cases()
    for name, case in every.items():
        case["values"] = compute(case, catalogue)
        print(name, case["values"], file=sys.stderr)
    FILE.write_text(HEADER + yaml.safe_dump(every, sort_keys=False, width=100, default_flow_style=None))


if __name__ == "__main__":
    main()
