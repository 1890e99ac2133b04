"""Feasible grid points (of 216) per actuator 1-5 under each reading of docs/model.md.

These are our computed values (regression pins for the documented table), one switch away from
the default reading at a time. Paper, Table 2 (zero orientation): 216, 208, 184, 188, 16 points
(100, 96.3, 85.19, 87.04, 7.41 %). The paper withholds the 0.5 rad value.
"""

import pytest

from pipeline.workspace import compute_workspace

ROTATED = ("orientation.psi=0.5", "orientation.theta=0.5", "orientation.phi=0.5")
READINGS = {
    "default": ((), [216, 208, 184, 184, 24], [207, 193, 183, 183, 24]),
    "pinv_full": (("model.pinv_columns=full",), [216, 208, 184, 184, 0], [182, 120, 30, 9, 0]),
    "velocity_include": (("model.velocity_boundary=include",), [216, 192, 184, 184, 24], [207, 187, 183, 180, 24]),
    "acceleration_colon": (("model.acceleration_set=colon",), [216, 208, 184, 184, 28], [207, 193, 183, 183, 26]),
    "jdot": (("model.jdot=true",), [212, 204, 184, 184, 24], [200, 191, 183, 182, 24]),
    "torque_limit_without_xi": (("model.xi_in_torque_limit=false",), [216, 216, 184, 184, 120], [213, 204, 185, 183, 108]),
    "grid_centred": (("grid.spacing=centred",), [216, 216, 212, 192, 28], [216, 216, 208, 187, 27]),
    "inertia_newton": (("model.inertia=newton",), [216, 208, 184, 184, 24], [207, 193, 183, 183, 24]),
    "lower_anchors_at_floor": (("robot.lower_anchor_drop=2.2",), [216, 216, 216, 216, 0], [216, 216, 216, 216, 0]),
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


def test_orientation_shrinks_the_workspace_under_every_reading(make_cfg, catalogue):
    """Section 3.1.2: at psi = theta = phi = 0.5 rad the workspace is smaller than at zero."""
    for overrides, zero, rotated in READINGS.values():
        assert sum(rotated) <= sum(zero)


@pytest.mark.parametrize("overrides,paper,newton", [
    (("motion.t_dec=0.91",), ([216, 204, 184, 184, 9], [207, 191, 183, 180, 8]),
     ([216, 208, 184, 184, 14], [207, 193, 183, 183, 16])),
    (("model.acceleration_set=colon",), ([216, 208, 184, 184, 28], [207, 193, 183, 183, 26]),
     ([216, 208, 184, 184, 34], [208, 195, 183, 183, 34])),
])
def test_sign_of_the_inertial_term_matters_only_for_an_asymmetric_acceleration_set(
        make_cfg, catalogue, overrides, paper, newton):
    """Eq. (31) as printed flips a against Newton's law with z up; the default box is symmetric
    (t_acc = t_dec), so only a braking time of its own or the colon set tells them apart."""
    for inertia, expected in (("paper", paper), ("newton", newton)):
        for orientation, counts in zip(((), ROTATED), expected):
            got = [compute_workspace(make_cfg(f"actuator={a}", f"model.inertia={inertia}", *overrides,
                                              *orientation), catalogue)[1]["n_feasible"]
                   for a in range(1, 6)]
            assert got == counts, (inertia, overrides, orientation)
