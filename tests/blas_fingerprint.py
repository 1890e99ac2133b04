"""Print the verdicts of configurations with poses exactly on a limit, as one line of JSON.

Run by tests/test_blas_kernels.py under several ``OPENBLAS_CORETYPE`` values; not a test itself.
Also prints the bits of one BLAS determinant, to show that the forced kernel really changed the
arithmetic.
"""

import hashlib
import json
import sys

import numpy as np
from hydra import compose, initialize_config_dir

from pipeline.model.catalogue import load_catalogue
from pipeline.app.config import register
from pipeline.app.resources import CONF_DIR
from conftest import compute_workspace

CASES = [
    ["robot=irpm6", "robot.r_base=4"],  # 50 poses with a cable at exactly zero tension
    ["robot=irpm6", "robot.r_base=8"],
    ["robot=irpm6", "robot.gamma_deg=30"],
    *[[f"actuator={a}"] for a in (1, 2, 3, 4, 5)],
    ["actuator=4", "orientation.psi=0.5", "orientation.theta=0.5", "orientation.phi=0.5"],
]


def main() -> None:
    register()
    catalogue = load_catalogue()
    out = {}
    with initialize_config_dir(config_dir=str(CONF_DIR), version_base="1.3"):
        for overrides in CASES:
            cfg = compose(config_name="config", overrides=["compute.n_jobs=1", *overrides, *sys.argv[1:]])
            points, summary = compute_workspace(cfg, catalogue)
            verdict = points["feasible"].to_numpy().tobytes() + points["limiting"].astype(str).str.cat().encode()
            out[" ".join(overrides)] = [int(summary["n_feasible"]), hashlib.sha256(verdict).hexdigest()[:16]]
    a = np.random.default_rng(0).random((50, 50))
    out["blas_probe"] = float(np.linalg.det(a @ a.T)).hex()
    print(json.dumps(out))


if __name__ == "__main__":
    main()
