"""cdpr-studies: feasible workspace and actuator choice for cable-driven parallel robots.

Layers, each importing only those before it: ``errors`` (the one exception for bad input),
``model`` (the physics as data), ``workspace`` (criteria, kernel, grid), ``app`` (config, command
line, job files), ``analyses`` (what studies compute and draw). Entry points on top:
``python -m pipeline``, ``pipeline.study``, ``pipeline.report``, ``pipeline.caspr``,
``pipeline.api``."""

import os

# One BLAS thread per process unless the user set one: the kernels solve many small systems
# (6 x 8 per pose), where OpenBLAS's threads add no speed, while starting them costs about 0.06 s
# of CPU for each library that brings its own (numpy's, and scipy's that numba loads), in every
# process (docs/performance.md, "What a process imports"). It must be set before numpy is imported.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
