"""``python -m pipeline [-m] [key=value ...]``: the Hydra application of ``pipeline.app.cli``."""

from pipeline.app.cli import cli

cli()
