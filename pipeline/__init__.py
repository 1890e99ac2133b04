"""cdpr-studies: feasible workspace and actuator choice for cable-driven parallel robots.

Layers, each importing only those before it: ``errors`` (the one exception for bad input),
``model`` (the physics as data), ``workspace`` (criteria, kernel, grid), ``app`` (config, command
line, job files), ``analyses`` (what studies compute and draw). Entry points on top:
``python -m pipeline``, ``pipeline.study``, ``pipeline.report``, ``pipeline.caspr``,
``pipeline.api``."""
