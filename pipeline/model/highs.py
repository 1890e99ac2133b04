"""This thread's HiGHS instance, for the LPs and QPs passed to HiGHS directly (the least-norm
tensions' QP, ``pipeline.model.distribution``; the certificates' separators,
``pipeline.model.certificates``), made once per thread and cleared by each caller."""

from __future__ import annotations

import os
import sys
import threading

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
