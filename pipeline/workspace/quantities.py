"""Per-pose physical quantities behind a verdict (``output.cables=true``): the cable lengths and
the cable tensions the checked model uses, so that a user can see why a pose fails.

Columns, per cable name c: ``length_<c>`` (m). Statics: ``tension_<c>`` (N), the minimum-norm
tensions of eq. (10) (``pinv``) or the distribution the LPs chose (``feasible``, the solution of
the last family's LP); with sagging cables (``robot.catenary``) the settled equilibrium's largest
tension of each cable and its shape (``SaggingStatics.shapes``: ``sag_<c>``, ``angle_platform_<c>``,
``angle_anchor_<c>``, ``unstrained_<c>``, ``added_length_<c>``). CPR-WWA and lines:
``tension_min_<c>`` and ``tension_max_<c>`` (N), the
range over the acceleration set of t = M / R_i with M of eq. (20) (``pinv``) or of the chosen
forces at the vertices of the acceleration box (``feasible``). All at the nominal orientation.
"""

from __future__ import annotations

import numpy as np


from pipeline.workspace.criteria.forces import written_tensions


# A pose's cable quantities (output.cables) against the cost model's unit pose: the least-norm
# tensions of the feasible model, 126 us a pose for the example robot's 8 cables (2026-11-27),
# nothing measurable under the minimum-norm model's (+2 us)
WORK = {"pinv": 0.0, "feasible": 2.5}


def cable_quantities(state, limits) -> dict[str, np.ndarray]:
    """(n,) arrays keyed by column name for one chunk's state (``PoseStatics``/``PoseDynamics``)."""
    names = state.robot.cable_names
    columns = {f"length_{name}": state.cable_lengths[:, i] for i, name in enumerate(names)}
    if state.robot.pulleys is not None:  # where each cable leaves its pulley, and how far it wraps it
        for i, name in enumerate(names):
            columns[f"wrap_{name}"] = state.wrap_angles[:, i]
            columns.update({f"exit_{axis}_{name}": state.exits[:, i, k] for k, axis in enumerate("xyz")})
    if state.tension.model == "pinv":
        high, low = state.force_range
        written = state.variables_of(high)
    else:
        chosen = written_tensions(state, limits)  # (n, K, m) over the required wrenches
        high, low = state.forces_of(chosen.max(axis=1)), state.forces_of(chosen.min(axis=1))
        written = chosen[:, 0, :]
    if not state.ranges_over_a_set:
        columns.update({f"tension_{name}": high[:, i] for i, name in enumerate(names)})
        for quantity, values in state.shapes(written).items():  # elastic or sagging cables' lengths and shapes
            columns.update({f"{quantity}_{name}": values[:, i] for i, name in enumerate(names)})
        return columns
    for i, name in enumerate(names):
        columns[f"tension_min_{name}"] = low[:, i]
        columns[f"tension_max_{name}"] = high[:, i]
    return columns
