"""CPR-WWA followed literally, one pose and one (velocity, acceleration) combination k at a time.

Section 3 of Filipovic & Kevac (2018) as written: for every grid point, build J (eq. 19) cable by
cable, then for every tested combination k compute theta_dot (19), F (31), M (20), theta_ddot and
u (21), and compare with limits (30), (32), (33), (34). It shares no array code with the
vectorised kernel. It exists to validate that kernel (tests) and to be the speed reference of
``benchmarks/``; it is slow by construction.
"""

from __future__ import annotations

import numpy as np

from pipeline.model.actuators import ActuatorModel
from pipeline.model.dynamics import MotionSpec, load_wrench_terms
from pipeline.model.geometry import CableRobot, rotation_matrix, rotation_partials
from pipeline.workspace.criteria import ACCELERATION, SPEED, TORQUE, VOLTAGE


def literal_margins(
    robot: CableRobot, positions: np.ndarray, orientation, motion: MotionSpec, act: ActuatorModel
) -> dict[str, np.ndarray]:
    """Relative margins ``1 - worst/limit`` of the four CPR-WWA criteria, pose by pose."""
    rot = rotation_matrix(*orientation)
    d_rot = rotation_partials(*orientation)
    columns = 3 if motion.pinv_columns == "translational" else 6
    names = (SPEED, TORQUE, ACCELERATION, VOLTAGE)
    limits = (act.speed_limit, act.torque_limit, act.accel_limit, act.voltage_limit)
    out = {name: np.empty(len(positions)) for name in names}
    for p, position in enumerate(positions):
        m = robot.n_cables
        jac, unit, length = np.empty((m, 6)), np.empty((m, 3)), np.empty(m)
        for i in range(m):
            attached = rot @ robot.attachments[i]
            vector = position + attached - robot.anchors[i]
            length[i] = np.sqrt(vector @ vector)
            unit[i] = vector / length[i]
            radius = motion.winch_radius[i]
            jac[i, :3] = unit[i] / radius
            for q in range(3):
                jac[i, 3 + q] = unit[i] @ (d_rot[q] @ robot.attachments[i]) / radius
        pinv = np.linalg.pinv(jac[:, :columns].T, rtol=motion.rank_rtol)
        per_acceleration = []
        for a in motion.accelerations:
            wrench = load_wrench_terms(motion.load, robot.up, rot)  # eq. (31): w = L a + F_0
            wrench = wrench[0] @ a + wrench[1]
            # the generalized force of Euler angle q: the moment along the angular velocity
            # per unit rate of q, the axial vector of dR/dq R^T (virtual work)
            rates = [d_rot[q] @ rot.T for q in range(3)]
            wrench[3:] = [wrench[3:] @ np.array([r[2, 1], r[0, 2], r[1, 0]]) for r in rates]
            per_acceleration.append((pinv @ wrench[:columns], jac[:, :3] @ a))  # eq. (20), J a
        worst = [0.0, 0.0, 0.0, 0.0]
        for v in motion.velocities:
            theta_dot = jac[:, :3] @ v  # eq. (19), Euler rates zero
            centripetal = np.zeros(m)
            if motion.jdot:
                centripetal = ((v @ v) - (unit @ v) ** 2) / (length * motion.winch_radius)
            for torque, j_a in per_acceleration:  # every combination k = (v, a)
                theta_ddot = j_a + centripetal
                u = act.G_v * theta_ddot + act.L_v * theta_dot - act.S_v * torque  # eq. (21): the motor holds M
                for c, values in enumerate((theta_dot, torque, theta_ddot, u)):
                    worst[c] = max(worst[c], float(np.abs(values).max()))
        for c, name in enumerate(names):
            out[name][p] = 1.0 - worst[c] / limits[c]
    return out
