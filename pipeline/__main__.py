"""``python -m pipeline [-m] [key=value ...]`` (and the ``cdpr`` command): the Hydra application
of ``pipeline.app.cli``.

The process lives for one command, so Python's cyclic garbage collector is kept off what lives
as long as the process: paused while the application is imported (modules, classes, grammars:
nothing there becomes garbage), whose objects are then frozen (``gc.freeze``: the job's
collections do not scan them), and every object frozen when the command ends, so that the
interpreter's shutdown does not scan them all again before the process exits
(docs/performance.md, "The garbage collector of a one-command process").
"""

import gc


def main() -> None:
    gc.disable()
    from pipeline.app.cli import cli  # imported with the collector paused

    gc.freeze()
    gc.enable()
    try:
        cli()
    finally:
        gc.freeze()


if __name__ == "__main__":
    main()
