"""The application around the physics: the structured config and its validation, the preflight
and the command line (Hydra), one job's files, Parquet results, progress lines, ``--help``, and
the shipped resources."""
