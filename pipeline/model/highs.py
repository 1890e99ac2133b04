"""This thread's HiGHS instance, for the LPs and QPs passed to HiGHS directly (the least-norm
tensions' QP, ``pipeline.model.distribution``; the certificates' separators,
``pipeline.model.certificates``), made once per thread and cleared by each caller."""

from __future__ import annotations

import os
import sys
import threading

import numpy as np

_SOLVERS = threading.local()


def solver():
    """This thread's HiGHS instance, made once: HiGHS prints its banner on the process's stdout
    when an instance is made (before any option can silence it), which would mix into a job's
    output, so the descriptor is pointed at the null device for that moment only."""
    found = getattr(_SOLVERS, "solver", None)
    if found is None:
        import highspy

        sys.stdout.flush()
        saved = os.dup(1)
        try:
            with open(os.devnull, "w") as null:
                os.dup2(null.fileno(), 1)
                found = highspy.Highs()
        finally:
            os.dup2(saved, 1)
            os.close(saved)
        found.setOptionValue("output_flag", False)
        _SOLVERS.solver = found
    return found


def block_columns(blocks: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The column-wise (start, index, value) arrays of the block-diagonal matrix of ``blocks``
    (B, r, width): block b's column j is the model's column b width + j, its rows b r .. b r + r - 1;
    zeros are left out (HiGHS would drop them on passing the model)."""
    count, rows, _ = blocks.shape
    columns = np.swapaxes(blocks, 1, 2)  # (B, width, r): block b's column j
    nonzero = columns != 0
    start = np.concatenate([[0], np.cumsum(nonzero.sum(axis=2).ravel())])
    index = np.broadcast_to(np.arange(rows) + rows * np.arange(count)[:, None, None], nonzero.shape)[nonzero]
    return start, index, columns[nonzero]


def solved(model) -> np.ndarray | None:
    """The columns' values of ``model`` (a ``HighsLp`` or ``HighsModel``) solved by this thread's
    HiGHS, or None if HiGHS does not reach an optimum (infeasible, unbounded or stopped)."""
    import highspy

    found = solver()
    found.clearModel()
    found.passModel(model)
    found.run()
    if found.getModelStatus() != highspy.HighsModelStatus.kOptimal:
        return None
    return np.asarray(found.getSolution().col_value)
