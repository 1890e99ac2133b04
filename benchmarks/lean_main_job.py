"""The main job's five verdicts with nothing around them: one composition, the same kernel,
no preflight, no Hydra run, no files. The reference of ``bench_process.py``; prints the
feasible share of each actuator."""

from hydra import compose, initialize_config_dir

from pipeline.model.catalogue import load_catalogue
from pipeline.app.config import register
from pipeline.app.problem import build_problem, typed_config
from pipeline.app.resources import CONF_DIR
from pipeline.workspace.compute import grid_workspace

register()
catalogue = load_catalogue()
with initialize_config_dir(config_dir=str(CONF_DIR), version_base="1.3"):
    base = compose("config")
for actuator in catalogue.ids:
    base.actuator = int(actuator)
    cfg = typed_config(base)
    _, summary = grid_workspace(cfg, *build_problem(cfg, catalogue))
    print(actuator, f"{summary['feasible_pct']:.2f}")
