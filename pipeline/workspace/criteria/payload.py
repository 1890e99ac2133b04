"""The payload criterion of ``analysis=payload``: the largest payload each pose holds on top of
the robot's platform (``pipeline.model.statics.PosePayload``) against the payload required."""

from __future__ import annotations

import numpy as np


def payload(state, limits) -> np.ndarray:
    """The payload required (``load.mass``) must lie in the interval of payloads the pose holds
    (``PosePayload.payload_range``): margin min(largest - required, required - least) /
    max(required, 1 kg), at most 1, the second term only where the least is above 0 (the cables
    need a payload's weight to reach t_min); -1 where no payload is held (NaN)."""
    required = state.spec.payload
    least, largest = state.payload_range[:, 0], state.payload_range[:, 1]
    below = np.where(least > 0, required - least, np.inf)
    margin = np.minimum(largest - required, below) / max(required, 1.0)
    return np.where(np.isnan(margin), -1.0, np.minimum(margin, 1.0))
