"""Hydra sweeper plugin of cdpr-studies (Hydra discovers plugins in the ``hydra_plugins`` namespace)."""
