"""The payload criterion of ``analysis=payload``: the largest payload each pose holds on top of
the robot's platform (``pipeline.model.statics.PosePayload``) against the payload required."""

from __future__ import annotations

import numpy as np


def payload(state, limits) -> np.ndarray:
    """(max payload - required payload) / max(required, 1 kg), at most 1; -1 where not even the
    platform alone is held (NaN payload)."""
    required = state.spec.payload
    margin = (state.max_payload - required) / max(required, 1.0)
    return np.where(np.isnan(margin), -1.0, np.minimum(margin, 1.0))
