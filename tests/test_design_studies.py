"""The accepted ranges that docs/studies.md reports for the design-variable studies, recomputed
in-process over the values declared in studies/design_*.yaml."""

import pytest
from omegaconf import OmegaConf

from pipeline.app.resources import STUDIES_DIR
from conftest import compute_workspace

ACCEPTED = {  # study -> {actuator: accepted values}
    "design_winch_radius": {1: [0.075, 0.08, 0.09, 0.1, 0.12], 2: [0.08], 3: [], 4: [], 5: []},
    "design_gear_ratio": {1: [20, 25, 30], 2: [25], 3: [], 4: [], 5: []},
    "design_mass": {1: [0.5, 1, 1.5, 2, 3], 2: [0.5, 1, 1.5, 2], 3: [0.5], 4: [0.5], 5: []},
    "design_v_max": {1: [0.4, 0.6, 0.8, 1.0, 1.3], 2: [0.4, 0.6, 0.8, 1.0, 1.3], 3: [], 4: [], 5: []},
}


@pytest.mark.parametrize("study", sorted(ACCEPTED))
def test_accepted_ranges_match_the_docs(study, make_cfg, catalogue):
    sweep = OmegaConf.load(STUDIES_DIR / f"{study}.yaml").sweep
    (key,) = [k for k in sweep if k != "actuator"]
    values = [float(v) for v in str(sweep[key]).split(",")]
    for actuator, expected in ACCEPTED[study].items():
        accepted = [
            v for v in values
            if compute_workspace(make_cfg(f"actuator={actuator}", f"{key}={v}"), catalogue)[1][
                "feasible_pct"] >= 90.0
        ]
        assert accepted == pytest.approx(expected), (study, actuator)
