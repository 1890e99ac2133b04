"""Matplotlib styles shipped with the package: ``plt.style.use("pipeline.styles.paper")``."""
