"""The preflight validates every job of a command before Hydra creates any folder."""

import pytest

from pipeline.errors import ConfigError
from pipeline.preflight import check, job_overrides


def test_sweep_expands_like_hydra_basic_sweeper():
    assert job_overrides(["-m", "actuator=1,2", "load.mass=1,3"]) == [
        ["actuator=1", "load.mass=1"], ["actuator=1", "load.mass=3"],
        ["actuator=2", "load.mass=1"], ["actuator=2", "load.mass=3"],
    ]
    assert job_overrides(["--cfg", "job"]) is None


@pytest.mark.parametrize(
    "argv, needle",
    [
        (["-m", "actuator=1,2,9"], "actuator=9"),
        (["-m", "robot.frame.d=3.2,0.3"], "robot.frame.d=0.3"),
        (["-m", "load.mass=abc", "load.mass=1,2"], "load.mass=abc"),  # Hydra merges it first
        (["-m", "orientation={psi:x}"], "orientation={psi:x}"),
        (["-m", "hydra/sweeper=nope", "actuator=1,2"], "nope"),
    ],
)
def test_first_bad_job_is_named(argv, needle):
    with pytest.raises(ConfigError) as info:
        check(argv)
    assert needle in str(info.value) and "\n" not in str(info.value)


def test_value_overrides_reuse_one_composition_and_stay_typed():
    masses = ",".join(str(1 + i / 10) for i in range(200))
    check(["-m", f"load.mass={masses}"])
    with pytest.raises(ConfigError, match="grid.n=2.5"):
        check(["-m", f"load.mass={masses}", "grid.n=3,2.5"])
