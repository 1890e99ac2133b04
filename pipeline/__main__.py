"""``python -m pipeline [-m] [key=value ...]``: the Hydra application of ``pipeline.cli``."""

from pipeline.cli import cli

cli()
