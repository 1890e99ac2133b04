"""Hydra sweeper plugin of cdpr-studies (discovered by Hydra in the ``hydra_plugins`` namespace)."""
