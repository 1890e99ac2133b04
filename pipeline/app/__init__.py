"""The application around the physics: the structured config and its validation, the plan of a
command (Hydra composes), its run and one job's files, the command line, Parquet results,
progress lines, ``--help``, and the shipped resources."""
