"""An independent, straightforward implementation of a CPR-WWA job, the reference of
``bench_process.py`` for the 125 000-pose job: section 3 of Filipovic & Kevac (2018) written
from the paper with plain numpy, sharing no code with ``pipeline`` (no Hydra, no config
checks, no cost model, no compiled code).

    python benchmarks/straightforward_job.py N OUT.parquet [ACTUATOR]

It does what ``python -m pipeline grid.n=N grid.n_vel=6 actuator=ACTUATOR`` computes: the
CPR-8 of section 3.1 (frame 3.2 x 2.2 x 2.2 m, carrier 0.224 x 0.154 x 0.140 m, 2 kg), an
N^3 grid over the geometric workspace, the 93 velocities of eqs. (23)-(26) (N_v = 6,
|v| < V), the 8 acceleration corners of eqs. (27)-(29), M = (J^T)^+ F with all six columns of
J (eq. 20, pseudo-inverse by SVD, rtol 1e-9), and a pose is feasible when every combination
(v, a) of the sets meets eqs. (30), (32)-(34) (margins within 1e-9 of zero count as met).
Every combination is formed in chunks of poses, as plain vectorised numpy does; the verdicts
go to OUT.parquet (x, y, z, feasible) and the feasible share is printed.
"""

from __future__ import annotations

import csv
import itertools
import sys
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

CATALOGUE = Path(__file__).resolve().parent.parent / "pipeline" / "data" / "actuators_table1.csv"
D, S, V = 3.2, 2.2, 2.2  # frame, m
L, W, H = 0.224, 0.154, 0.140  # carrier, m
MASS, G = 2.0, 9.81
V_MAX, T_ACC, T_DEC, N_VEL = 1.3, 1.82, 1.82, 6
CHUNK = 2_000


def actuator(number: int) -> dict:
    """Eq. (22) constants and the limits of eqs. (30), (32)-(34) behind the gearbox."""
    with open(CATALOGUE, newline="") as handle:
        row = next(r for r in csv.DictReader(handle) if int(r["id"]) == number)
    x = {k: float(v) for k, v in row.items() if k != "name"}
    n_v = x["gear_ratio"]
    n_m = n_v * x["efficiency"]
    c_m = x["torque_constant_Nm_per_A"] * n_m
    j_r = x["inertia_g_cm2"] * 1e-7 * n_v * n_m
    return {
        "radius": x["winch_radius_m"],
        "G": j_r * x["resistance_ohm"] / c_m,
        "L": x["viscous_friction_Nm_per_rad_s"] * n_v * n_m * x["resistance_ohm"] / c_m
        + x["back_emf_V_per_rad_s"] * n_v,
        "S": x["resistance_ohm"] / c_m,
        "limits": np.array([x["speed_rpm"] / 9.549296585513721 / n_v, x["torque_Nm"] * n_m,
                            x["torque_Nm"] * n_m / j_r, x["voltage_V"]]),
    }


def robot():
    """Anchors (8, 3), attachment points in the carrier frame (8, 3) and the grid box."""
    corners = [(0, 0), (D, 0), (D, S), (0, S)]
    anchors = np.array([(x, y, 0.0) for x, y in corners] + [(x, y, -H) for x, y in corners])
    vertices = [(-L / 2, -W / 2), (L / 2, -W / 2), (L / 2, W / 2), (-L / 2, W / 2)]
    attach = np.array([(x, y, H / 2) for x, y in vertices] + [(x, y, -H / 2) for x, y in vertices])
    de = np.sqrt((L / 2) ** 2 + (W / 2) ** 2 + (H / 2) ** 2)
    return anchors, attach, np.array([de, de, -(V - de)]), np.array([D - de, S - de, -de])


def main() -> None:
    n, out = int(sys.argv[1]), Path(sys.argv[2])
    act = actuator(int(sys.argv[3]) if len(sys.argv) > 3 else 1)
    anchors, attach, lo, hi = robot()
    axes = [np.linspace(a, b, n) for a, b in zip(lo, hi)]
    points = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    steps = np.linspace(-V_MAX, V_MAX, N_VEL + 1)
    velocities = np.array([v for v in itertools.product(steps, repeat=3)
                           if np.linalg.norm(v) < V_MAX * (1 - 1e-9)])
    accelerations = np.array(list(itertools.product((-V_MAX / T_DEC, V_MAX / T_ACC), repeat=3)))
    wrenches = np.zeros((len(accelerations), 6))  # eq. (31): F = [m a - m g e_z; 0]
    wrenches[:, :3] = MASS * accelerations
    wrenches[:, 2] -= MASS * G
    feasible = np.empty(len(points), dtype=bool)
    for start in range(0, len(points), CHUNK):
        p = points[start:start + CHUNK]
        cable = p[:, None, :] + attach[None] - anchors[None]  # zero orientation: R = I
        unit = cable / np.linalg.norm(cable, axis=2, keepdims=True)
        # eq. (19) at zero orientation: the Euler-rate columns are (b_i x u_i)
        jac = np.concatenate([unit, np.cross(attach[None], unit)], axis=2) / act["radius"]
        pinv = np.linalg.pinv(np.transpose(jac, (0, 2, 1)), rtol=1e-9)  # (n, 8, 6)
        speed = np.einsum("nmj,vj->nvm", jac[:, :, :3], velocities)  # eq. (19)
        accel = np.einsum("nmj,aj->nam", jac[:, :, :3], accelerations)  # J a
        torque = np.einsum("nmc,ac->nam", pinv, wrenches)  # eq. (20)
        # every combination k = (v, a): (n, 93, 8, 8 cables)
        voltage = (act["G"] * accel[:, None] + act["L"] * speed[:, :, None] + act["S"] * torque[:, None])
        worst = np.stack([np.abs(speed).max(axis=(1, 2)), np.abs(torque).max(axis=(1, 2)),
                          np.abs(accel).max(axis=(1, 2)), np.abs(voltage).max(axis=(1, 2, 3))], axis=1)
        margins = 1.0 - worst / act["limits"]
        feasible[start:start + CHUNK] = (np.where(np.abs(margins) <= 1e-9, 0.0, margins) >= 0).all(axis=1)
    pq.write_table(pa.table({"x": points[:, 0], "y": points[:, 1], "z": points[:, 2],
                             "feasible": feasible}), out)
    print(f"{feasible.sum()}/{len(points)} feasible ({100 * feasible.mean():.2f} %)")


if __name__ == "__main__":
    main()
