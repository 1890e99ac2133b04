"""The preflight validates every job of a command before Hydra creates any folder."""

import pytest

from pipeline.errors import ConfigError
from pipeline.app.preflight import check, job_overrides


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


def test_expansion_matches_hydra_basic_sweeper_with_ranges_and_repeated_keys():
    """Same jobs, in the same order, as the basic sweeper's own split (Hydra's internal code is
    used here only as the reference, never by the package)."""
    from hydra._internal.core_plugins.basic_sweeper import BasicSweeper

    from pipeline.app.preflight import parse

    argv = ["-m", "actuator=range(1,4)", "load.mass=1", "grid.n=2,3", "load.mass=4,5"]
    expected = BasicSweeper.split_arguments(parse(argv[1:]), max_batch_size=None)[0]
    assert job_overrides(argv) == expected and len(expected) == 12


def test_sweeps_the_preflight_cannot_enumerate_are_checked_by_their_fixed_part():
    """interval(...) and other sweepers (e.g. Optuna) choose values at run time: not refused,
    and a bad fixed value is still caught."""
    assert job_overrides(["-m", "load.mass=interval(1,3)", "actuator=2"]) == [["actuator=2"]]
    assert job_overrides(["-m", "hydra/sweeper=optuna", "load.mass=1,2"]) == [["hydra/sweeper=optuna"]]
    with pytest.raises(ConfigError, match="actuator=9"):
        check(["-m", "load.mass=interval(1,3)", "actuator=9"])
