"""Hydra plugins of cdpr-studies: the ``cdpr`` sweeper and launcher (Hydra discovers plugins in
the ``hydra_plugins`` namespace only)."""
