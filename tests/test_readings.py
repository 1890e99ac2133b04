"""Feasible grid points (of 216) per actuator 1-5 under the settings of docs/model.md section 4
that are not model.* readings (those are pinned with the evidence, tests/test_evidence.py).

These are our computed values (regression pins for the documented table). Paper, Table 2 (zero
orientation): 216, 208, 184, 188, 16 points (100, 96.3, 85.19, 87.04, 7.41 %). The paper
withholds the 0.5 rad value.
"""

import pytest

from pipeline.app.problem import compute_workspace

ROTATED = ("orientation.psi=0.5", "orientation.theta=0.5", "orientation.phi=0.5")
READINGS = {
    "default": ((), [216, 208, 184, 184, 0], [182, 120, 30, 10, 0]),
    "grid_centred": (("grid.spacing=centred",), [216, 216, 208, 184, 0], [190, 131, 30, 4, 0]),
    "lower_anchors_at_floor": (("robot.lower_anchor_drop=2.2",), [208, 80, 8, 0, 0], [216, 216, 202, 158, 0]),
}


@pytest.mark.parametrize("reading", sorted(READINGS))
def test_reading_counts(make_cfg, catalogue, reading):
    overrides, zero, rotated = READINGS[reading]
    for orientation, expected in (((), zero), (ROTATED, rotated)):
        got = [
            compute_workspace(make_cfg(f"actuator={a}", *overrides, *orientation), catalogue)[1]["n_feasible"]
            for a in range(1, 6)
        ]
        assert got == expected, (reading, orientation)


@pytest.mark.parametrize("overrides,paper,newton", [
    (("motion.t_dec=0.91", "model.pinv_columns=translational"), ([216, 204, 184, 184, 9], [207, 191, 183, 182, 8]),
     ([216, 208, 184, 184, 14], [207, 193, 183, 183, 16])),
    (("motion.t_dec=0.91",), ([216, 192, 184, 178, 0], [179, 109, 16, 1, 0]),
     ([216, 204, 184, 181, 0], [180, 117, 25, 3, 0])),
    (("model.acceleration_set=colon", "model.pinv_columns=translational"),
     ([216, 208, 184, 184, 28], [207, 193, 183, 183, 26]),
     ([216, 208, 184, 184, 34], [208, 195, 183, 183, 34])),
])
def test_sign_of_the_inertial_term_matters_only_for_an_asymmetric_acceleration_set(
        make_cfg, catalogue, overrides, paper, newton):
    """Eq. (31) as printed flips a against Newton's law with z up; the default box is symmetric
    (t_acc = t_dec), so only a braking time of its own or the colon set tells them apart
    (docs/model.md's table: forces only, and all six columns with the braking time)."""
    for inertia, expected in (("paper", paper), ("newton", newton)):
        for orientation, counts in zip(((), ROTATED), expected):
            got = [compute_workspace(make_cfg(f"actuator={a}", f"model.inertia={inertia}", *overrides,
                                              *orientation), catalogue)[1]["n_feasible"]
                   for a in range(1, 6)]
            assert got == counts, (inertia, overrides, orientation)
