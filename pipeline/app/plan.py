"""The plan of a command: every job it launches, composed, typed, validated and given its folder
before anything is written (``plan(argv) -> Plan``; :mod:`pipeline.app.run` runs it).

Hydra composes: each set of config files a command names (its config-group choices, ``+``/``~``
overrides, ``--config-dir``) is composed once through Hydra's compose API
(:class:`Composition`), and a sweep (``-m``) is expanded as Hydra's basic sweeper expands it,
with Hydra's override parser: the cartesian product of every override's values, in command
order. Each job's plain ``key=value`` overrides are applied to a copy of its composition with
the typed merge Hydra's config loader uses (the dataclass schema rejects a bad key or type), the
job is validated and its problem built (:func:`pipeline.app.problem.validate`) and its folder named by Hydra's rules
(``hydra.run.dir``, or ``hydra.sweep.dir``/``hydra.sweep.subdir`` with Hydra's
``override_dirname``). The first problem is a ConfigError with one line naming the key and
value: nothing is written.
"""

from __future__ import annotations

import copy
import difflib
import functools
import hashlib
import itertools
import math
import os
import pickle
import re
import shutil
import threading
from collections import OrderedDict
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, NoReturn

from hydra import compose, initialize_config_dir
from hydra.core.override_parser.overrides_parser import OverridesParser
from hydra.core.override_parser.types import ChoiceSweep, Override, RangeSweep
from hydra.errors import MissingConfigException
from omegaconf import DictConfig, ListConfig, OmegaConf, open_dict, read_write
from omegaconf.errors import ConfigAttributeError, ConfigKeyError, MissingMandatoryValue

from pipeline.app.config import masked, register
from pipeline.app.problem import grid_size, typed_schema, validate
from pipeline.workspace.dispatch import fused_pays
from pipeline.app.resources import CONF_DIR
from pipeline.app.yamltext import to_yaml
from pipeline.errors import ConfigError, one_line
from pipeline.model.catalogue import Catalogue, load_catalogue
from pipeline.workspace.kernel import WorkspaceProblem

# Hydra's flags that launch no job (Hydra answers them), and those that take a value
NO_JOB_FLAGS = {"--help", "-h", "--hydra-help", "--info", "-i", "--cfg", "-c", "--version",
                "--shell-completion", "-sc", "--resolve", "-p", "--package"}
FLAGS_WITH_VALUE = {"--config-path", "-cp", "--config-name", "-cn", "--config-dir", "-cd",
                    "--experimental-rerun"}
MAX_JOBS = 100_000  # jobs one command may launch: a typo in a range could ask for 10^8
HYDRA_STATE = threading.Lock()  # Hydra's compose API keeps one global state per process


@dataclass(frozen=True)
class Job:
    """One job of a plan: what :func:`pipeline.app.job.execute` runs."""

    number: int | None  # its place in the sweep (Hydra's hydra.job.num); None in run mode
    overrides: tuple[str, ...]  # as given, in command order (hydra.* included)
    folder: Path
    cfg: DictConfig  # typed and validated
    catalogue: Catalogue | None  # None for an analysis without actuators
    problem: WorkspaceProblem  # built from cfg by its robot and analysis kinds, once
    config: DictConfig  # as Hydra composes it, without Hydra's node (.hydra/config.yaml)
    files: tuple[str, ...]  # the key of its composition in the plan
    robot_file: str  # the robot file it composes (robot=NAME): robot.name is its kind, ``points`` for many
    fused: bool = False  # its sweep pays, as a whole, for the compiled kernels (dispatch.fused_pays)


@dataclass
class Plan:
    """Every job of a command, checked, in launch order, and what :mod:`pipeline.app.run` needs
    to write Hydra's records of them (the compositions, by their files)."""

    jobs: list[Job]
    multirun: bool
    sweep_dir: Path | None  # the sweep's folder (None in run mode)
    workers: int  # jobs at a time (hydra.launcher.n_jobs)
    overrides: tuple[str, ...]  # the command's (sweeps unexpanded)
    files: tuple[str, ...]  # the key of the composition of its fixed part (the sweep's config)
    gather: bool  # the sweep summary (Hydra's callback sweep_summary, which ~hydra.callbacks.sweep_summary drops)
    compositions: dict
    by_hydra: bool  # the command names one of Hydra's launchers or sweepers: Hydra runs it (pipeline.app.cli)

    def record(self, job: Job) -> DictConfig:
        """The job's config with Hydra's node, as Hydra's run or launcher records it
        (``.hydra/hydra.yaml``, and the job's logging settings). Derived again when the job
        runs rather than kept from the plan: a sweep may have 100 000 jobs."""
        return self.compositions[job.files].record(parse(job.overrides), parse(list(self.overrides)),
                                                   job.number, job.folder, self.sweep_dir)

    def sweep_record(self) -> DictConfig:
        """The sweep's config with Hydra's node, as Hydra's sweeper records it (``multirun.yaml``):
        the command's overrides, its sweeps unexpanded, with the folder of the sweep."""
        command = parse(list(self.overrides))
        config = self.compositions[self.files].hydra_node(command, command)
        config.hydra.sweep.dir = str(self.sweep_dir)
        return config

    @property
    def task_overrides(self) -> list[str]:
        """The command's overrides but Hydra's (the sweep summary's record)."""
        return [o.input_line for o in parse(list(self.overrides)) if not o.is_hydra_override()]


@dataclass
class Reuse:
    """What :func:`plan` may keep across calls over the same config files and catalogues (a
    study's trials, planned one by one): each set of files composed and typed once, each
    catalogue read once."""

    compositions: dict = field(default_factory=dict)
    catalogues: dict = field(default_factory=dict)


def plan(argv: list[str], reuse: Reuse | None = None) -> Plan | None:
    """The checked plan of a command line (Hydra's grammar: ``-m``, ``--config-dir DIR``,
    overrides); None for a command that launches no job (``--cfg``, ``--info``: Hydra's).
    Raises ConfigError for the first job whose config cannot be composed or is invalid, or whose
    folder cannot be written."""
    overrides = _overrides(argv)
    if overrides is None:
        return None
    multirun = _is_multirun(argv)
    parsed = parse(overrides)
    for override in parsed:
        if override.key_or_group.startswith("hydra.callbacks") and not override.is_delete():
            raise ConfigError(f"{override.input_line}: a Hydra callback runs code; the command line may "
                              "remove the project's (~hydra.callbacks.sweep_summary), not add or change one")
    jobs = sweep_jobs(parsed) if multirun else [overrides]
    register()
    search_path = _search_path(argv)
    mode = "hydra.mode=MULTIRUN" if multirun else "hydra.mode=RUN"
    reuse = Reuse() if reuse is None else reuse
    base = [o for o in parsed if not o.is_sweep_override()]  # what Hydra composes the sweep's config from

    def composition(job_parsed: list[Override]) -> tuple[tuple[str, ...], Composition]:
        files = _files(search_path, job_parsed, mode)
        if files not in reuse.compositions:
            reuse.compositions[files] = _composition(files, job_parsed)
        return files, reuse.compositions[files]

    with HYDRA_STATE, initialize_config_dir(config_dir=str(CONF_DIR), version_base="1.3", job_name="pipeline"):
        base_files, first = composition(base)
        try:
            first.job(base)  # a bad key or value named first (Hydra composes a sweep's own config from these)
        except ConfigError as exc:
            swept = [o.key_or_group for o in parsed if o.is_sweep_override() and structural(o) and "/" not in o.key_or_group
                     and (CONF_DIR / o.key_or_group).is_dir()]
            if not swept:
                raise
            raise ConfigError(f"{exc}; the sweep of {swept[0]} shares these keys, which Hydra checks against the sweep's "
                              f"own config, the default {swept[0]}: set them in each {swept[0]} file, or run one sweep "
                              f"per {swept[0]}") from None
        hydra = first.hydra_node(base, parsed)
        choices = hydra.hydra.runtime.choices
        by_hydra = (choices.get("hydra/launcher"), choices.get("hydra/sweeper")) != ("cdpr", "basic")
        if not by_hydra:
            _check_launcher(hydra, base)
        sweep_dir = Path(str(hydra.hydra.sweep.dir)) if multirun else None
        planned, folders = [], []
        for number, job in enumerate(jobs):
            job_parsed = parse(job)
            files, composed = composition(job_parsed)
            cfg, config = composed.job(job_parsed)
            catalogue = None
            if "catalogue" in cfg:  # analyses with an actuator
                if cfg.catalogue not in reuse.catalogues:
                    reuse.catalogues[cfg.catalogue] = load_catalogue(cfg.catalogue)
                catalogue = reuse.catalogues[cfg.catalogue]
            _, problem = validate(cfg, catalogue, typed=True)
            folder = composed.folder(job_parsed, parsed, number if multirun else None, sweep_dir)
            folders.append(folder)
            planned.append(Job(number if multirun else None, tuple(job), folder, cfg, catalogue, problem,
                               config, files, composed.robot_file))
    _check_output_folders(folders, planned[0].cfg, len(planned))
    if len(planned) > 1:
        if fused_pays((job.cfg, job.problem, grid_size(job.cfg)) for job in planned):
            planned = [Job(**{**job.__dict__, "fused": True}) for job in planned]
    gather = "sweep_summary" in (OmegaConf.select(hydra, "hydra.callbacks") or {})
    return Plan(planned, multirun, sweep_dir, 1 if by_hydra else hydra.hydra.launcher.n_jobs, tuple(overrides),
                base_files, gather, reuse.compositions, by_hydra)


def _files(search_path: tuple[str, ...], parsed: list[Override], mode: str) -> tuple[str, ...]:
    """The key of a composition: the search path, the overrides that choose files, the mode."""
    return (*search_path, *(o.input_line for o in parsed if structural(o)), mode)


def composed(argv: list[str]) -> DictConfig:
    """The config of one job of ``argv`` as Hydra composes it (its files, then its plain
    overrides; no Hydra node), required keys (``???``) left as they are: what ``--help`` lists
    for a robot whose points the command does not give yet. ConfigError for what cannot compose."""
    parsed = parse(_overrides(argv) or [])
    files = _files(_search_path(argv), parsed, "hydra.mode=RUN")
    with HYDRA_STATE, initialize_config_dir(config_dir=str(CONF_DIR), version_base="1.3", job_name="pipeline"):
        plain = _composition(files, parsed).plain()
    for override in parsed:
        if not structural(override) and not override.is_hydra_override():
            _apply(plain, override)

    def shown(value):  # a required key's ??? as text a page can print
        if isinstance(value, dict):
            return {key: shown(item) for key, item in value.items()}
        return "??? (required)" if value == "???" else value
    return OmegaConf.create(shown(OmegaConf.to_container(plain, throw_on_missing=False)))


COMPOSITIONS_KEPT = 32  # compositions a process keeps for later plans (a notebook's, a study's cases)
_kept: OrderedDict[tuple, Composition] = OrderedDict()


def _composition(files: tuple[str, ...], parsed: list[Override]) -> Composition:
    """Hydra's composition of ``files`` (the overrides that choose files, and the mode),
    composed once a process while what it reads is unchanged: the bytes of every YAML file of
    the search path's folders (conf/, ``--config-dir``) and the working folder (which Hydra's
    node records). The last COMPOSITIONS_KEPT are kept."""
    key = (files, os.getcwd(), _files_digest(files))
    if key in _kept:
        _kept.move_to_end(key)
        return _kept[key]
    try:
        composed = compose(config_name="config", overrides=list(files), return_hydra_config=True)
    except MissingConfigException as exc:  # a group option with no file
        raise ConfigError(_missing_option(exc, parsed, _search_folders(files))) from exc
    except Exception as exc:  # composition errors come as Hydra and OmegaConf types
        text = one_line(exc)
        listed = re.match(r"In 'robot/([^']+)': ConfigTypeError .*Cannot merge DictConfig with ListConfig", text)
        if listed:  # a list where the base robot node (conf/config.yaml) holds keys
            raise ConfigError(f"robot={listed[1]}: the robot file gives no robot keys (a list, not a mapping of "
                              "keys): start your own with 'defaults: [points, _self_]'") from exc
        raise ConfigError(text) from exc
    made = Composition(composed)
    if key[2] is None:
        return made
    _kept[key] = made
    while len(_kept) > COMPOSITIONS_KEPT:
        _kept.popitem(last=False)
    return made


def _search_folders(files: tuple[str, ...]) -> list[Path]:
    """The config folders a composition of ``files`` reads: conf/ and each ``file://`` folder of
    a ``hydra.searchpath`` override (``--config-dir``)."""
    folders = [CONF_DIR]
    for override in parse(list(files)):
        if override.key_or_group != "hydra.searchpath" or override.is_delete():
            continue
        value = override.value()
        entries = value if isinstance(value, list) else [value]
        folders += [Path(str(e)[len("file://"):]).absolute() for e in entries if str(e).startswith("file://")]
    return folders


def _files_digest(files: tuple[str, ...]) -> str | None:
    """A digest of the YAML files a composition of ``files`` can read: conf/ and each
    ``file://`` folder of a ``hydra.searchpath`` override (Hydra's own files are its package's);
    None when one cannot be read (not kept: Hydra reports it, or reads it next time)."""
    digest = hashlib.blake2b(digest_size=16)
    for folder in _search_folders(files):
        digest.update(os.fsencode(folder) + b"\0")
        for path in sorted(folder.rglob("*.yaml")) if folder.is_dir() else ():
            digest.update(os.fsencode(path.relative_to(folder)) + b"\0")
            try:
                digest.update(hashlib.blake2b(path.read_bytes(), digest_size=16).digest())
            except OSError:
                return None
    return digest.hexdigest()


def _check_launcher(hydra: DictConfig, parsed: list[Override]) -> None:
    """The settings of the runner's launcher (``hydra/launcher=cdpr``, the default): the number
    of jobs at a time, and no other (naming one of Hydra's launchers, ``hydra/launcher=joblib``,
    hands the command to Hydra: ``pipeline.app.cli``)."""
    n_jobs = hydra.hydra.launcher.n_jobs
    if isinstance(n_jobs, bool) or not isinstance(n_jobs, int) or n_jobs < 1:
        raise ConfigError(f"hydra.launcher.n_jobs={n_jobs}: must be a whole number >= 1 (jobs at a time)")
    for override in parsed:
        key = override.key_or_group
        if key.startswith("hydra.launcher.") and key != "hydra.launcher.n_jobs":
            raise ConfigError(f"{override.input_line}: the pipeline's runner reads hydra.launcher.n_jobs only; "
                              "Hydra's own joblib launcher takes the others (hydra/launcher=joblib)")


def sweep_jobs(parsed: list[Override]) -> list[list[str]]:
    """The jobs of a sweep. A sweep another sweeper chooses the values of (Optuna: the command
    goes to Hydra, ``pipeline.app.cli``) is checked with its other overrides only: one job, the
    sweep's fixed part."""
    if other_sweeper(parsed):
        return [[o.input_line for o in parsed if not o.is_sweep_override()]]
    return expand_sweep(parsed)


def expand_sweep(parsed: list[Override]) -> list[list[str]]:
    """The basic sweeper's jobs: the cartesian product of every override's values, in command
    order. Counted first: more than MAX_JOBS is a ConfigError naming the sweeps, before any
    list is made."""
    counts = {o.get_key_element(): _sweep_count(o) for o in parsed if o.is_sweep_override()}
    if math.prod(counts.values()) > MAX_JOBS:
        sizes = " x ".join(f"{key}: {count:g}" for key, count in counts.items())
        raise ConfigError(f"-m: {math.prod(counts.values()):.3g} jobs ({sizes}); at most {MAX_JOBS} in "
                          "one command (split the sweep, or sweep fewer values)")
    values: dict[str, list[str]] = {}  # a repeated key keeps its place and takes its last values
    for override in parsed:
        key = override.get_key_element()
        if override.is_interval_sweep():
            raise ConfigError(f"{override.input_line}: interval sweeps need a sweeper that samples "
                              "them (e.g. hydra/sweeper=optuna)")
        if override.is_sweep_override():
            values[key] = [f"{key}={value}" for value in override.sweep_string_iterator()]
        else:
            values[key] = [f"{key}={override.get_value_element_as_str()}"]
    return [list(job) for job in itertools.product(*values.values())]


def _sweep_count(override: Override) -> float:
    """How many values a sweep override gives, without listing a range's."""
    value = override.value()
    if isinstance(value, RangeSweep):
        return max(0, math.ceil((value.stop - value.start) / value.step)) if value.step else math.inf
    return len(value.list) if isinstance(value, ChoiceSweep) else 1


def other_sweeper(parsed: list[Override]) -> bool:
    """The command picks a sweeper other than Hydra's basic one, which this runner expands."""
    return any(o.key_or_group == "hydra/sweeper" and o.value() != "basic" for o in parsed)


def _overrides(argv: list[str]) -> list[str] | None:
    overrides, skip = [], False
    for arg in argv:
        if skip:
            skip = False
        elif arg in NO_JOB_FLAGS:
            return None
        elif arg in FLAGS_WITH_VALUE:
            skip = True
        elif not arg.startswith("-"):
            overrides.append(arg)
    return overrides


def _is_multirun(argv: list[str]) -> bool:
    return "-m" in argv or "--multirun" in argv


def quoted(value) -> str:
    """``value`` as a quoted value of Hydra's override grammar, so a folder name may hold
    ``=``, ``,``, spaces and quotes (``hydra.run.dir=`` + ``quoted(folder)``)."""
    text = re.sub(r"(\\+)(?='|$)", r"\1\1", str(value))  # backslashes escape only before a quote
    return "'" + text.replace("'", "\\'") + "'"


def parse(overrides: list[str]) -> list[Override]:
    """Hydra's parse of each override; a grammar error names the override it is in."""
    return [override for text in overrides for override in _parse_one(text)]


@functools.lru_cache(maxsize=4096)
def _parse_one(text: str) -> tuple[Override, ...]:
    """One override parsed (the jobs of a sweep repeat the same ``key=value`` texts, read only,
    so each is parsed once by Hydra's grammar)."""
    try:
        return tuple(OverridesParser.create().parse_overrides([text]))
    except Exception as exc:  # Hydra's override grammar errors have several types
        raise ConfigError(f"{text}: {one_line(exc)}") from exc


class Copies:
    """Fresh copies of one config, each equal to what ``copy.deepcopy`` makes, at a fraction of
    its cost: the config is pickled once and each copy unpickled. The copies are of ``cfg`` as it is now. A config
    that pickle cannot write (a structured config whose class it cannot find by name) is
    deep-copied instead."""

    def __init__(self, cfg: DictConfig) -> None:
        try:
            self._pickled, self._cfg = pickle.dumps(cfg, protocol=pickle.HIGHEST_PROTOCOL), None
        except (pickle.PicklingError, AttributeError, TypeError):  # pickle's refusals
            self._pickled, self._cfg = None, copy.deepcopy(cfg)

    def __call__(self) -> DictConfig:
        return pickle.loads(self._pickled) if self._cfg is None else copy.deepcopy(self._cfg)


class Composition:
    """One set of config files, composed once by Hydra: the config with Hydra's node, the job
    config without it, and its typed version (:func:`pipeline.app.problem.typed_schema`, every
    declared key), from which each job is made by its plain overrides (:meth:`job`)."""

    def __init__(self, composed: DictConfig) -> None:
        plain = without_hydra(composed)
        self.hydra = Copies(composed)
        self.plain = Copies(plain)
        self.robot_file = str(OmegaConf.select(composed, "hydra.runtime.choices.robot"))  # the robot file's name
        full = typed_schema(plain)  # typed once per composition
        self._full = Copies(full)
        self._typed = _derivable(full, plain)
        missing = OmegaConf.missing_keys(plain)
        self._missing = [key for key in _leaf_keys(plain) if key in missing]  # in the files' order
        self._scratch = full  # where each override text is typed, once (:meth:`_typed_value`)
        self._converted: dict[str, Any] = {}

    def job(self, parsed: list[Override]) -> tuple[DictConfig, DictConfig]:
        """(the job's typed config, its config as Hydra composes it) for its parsed overrides,
        each plain one applied to both in command order: the first override that is not a key
        of this robot and analysis, or whose value is not of the key's declared type, raises,
        as does a required key (``???``) left without a value."""
        plain = self.plain()
        overrides = [o for o in parsed if not structural(o) and not o.is_hydra_override()]
        try:
            if self._typed is None or any(_not_derivable(o) for o in overrides):
                full = self._full()
                for override in overrides:
                    _apply(plain, override)  # a key this robot and analysis have
                    _apply(full, override)  # of the declared type
                return masked(full, plain), plain
            typed = self._typed()
            for override in overrides:
                _apply(plain, override)
                OmegaConf.update(typed, override.key_or_group, self._typed_value(override), merge=False)
            unset = next((key for key in self._missing if _unset(typed, key)), None)
            if unset is not None:
                _no_value(unset)
            return typed, plain
        except MissingMandatoryValue as exc:  # ??? in a file, and not given
            _no_value(exc.full_key)

    def _typed_value(self, override: Override) -> Any:
        """The override's value as its key's declared type makes it, typed once per override
        text: a value's type depends on its key only, in one composition."""
        if override.input_line not in self._converted:
            _apply(self._scratch, override)  # ConfigError for a value of the wrong type
            value = OmegaConf.select(self._scratch, override.key_or_group)
            self._converted[override.input_line] = (OmegaConf.to_container(value) if isinstance(
                value, (DictConfig, ListConfig)) else value)
        return self._converted[override.input_line]

    def hydra_node(self, parsed: list[Override], command: list[Override]) -> DictConfig:
        """The composition with every plain override of a job applied in command order (Hydra's
        node's too), and Hydra's records of them (``hydra.overrides``: the job's task overrides,
        the command's own Hydra overrides and mode; ``hydra.job.override_dirname``): what
        Hydra's config loader composes for the job of a command."""
        config = self.hydra()
        for override in parsed:
            if not structural(override):
                try:
                    OmegaConf.update(config, override.key_or_group, override.value(), merge=True)
                except Exception as exc:  # OmegaConf key and type errors of Hydra's node
                    raise ConfigError(f"{override.input_line}: {one_line(exc)}") from exc
        hydra = config.hydra
        task = [o for o in parsed if not o.is_hydra_override()]
        hydra.overrides.hydra = [*(o.input_line for o in command if o.is_hydra_override()), f"hydra.mode={hydra.mode.name}"]
        hydra.overrides.task = [o.input_line for o in task]
        hydra.job.override_dirname = override_dirname(task, hydra.job.config.override_dirname)
        return config

    def folder(self, parsed: list[Override], command: list[Override], number: int | None,
               sweep_dir: Path | None) -> Path:
        """The job's folder by Hydra's rules (``hydra.run.dir``; ``hydra.sweep.dir`` and
        ``hydra.sweep.subdir`` in a sweep), as written (relative to the working folder or not)."""
        return _folder(self._numbered(parsed, command, number, sweep_dir).hydra, number)

    def record(self, parsed: list[Override], command: list[Override], number: int | None,
               folder: Path | None, sweep_dir: Path | None) -> DictConfig:
        """The job's config with Hydra's node as Hydra records it: its number in a sweep, the
        sweep's folder (resolved once for the command), its output folder (absolute)."""
        config = self._numbered(parsed, command, number, sweep_dir)
        with read_write(config.hydra.runtime), open_dict(config.hydra.runtime):
            config.hydra.runtime.output_dir = os.path.abspath(folder or _folder(config.hydra, number))
        return config

    def _numbered(self, parsed: list[Override], command: list[Override], number: int | None,
                  sweep_dir: Path | None) -> DictConfig:
        config = self.hydra_node(parsed, command)
        if number is not None:
            config.hydra.job.id = config.hydra.job.num = number
            config.hydra.sweep.dir = str(sweep_dir)
        return config


def _folder(hydra: DictConfig, number: int | None) -> Path:
    """A job's folder from Hydra's node: ``hydra.run.dir``, or in a sweep (``number``)
    ``hydra.sweep.dir``/``hydra.sweep.subdir``."""
    try:
        return Path(str(hydra.run.dir) if number is None else os.path.join(str(hydra.sweep.dir), str(hydra.sweep.subdir)))
    except Exception as exc:  # an interpolation of the folder that cannot resolve
        raise ConfigError(f"hydra.{'run' if number is None else 'sweep'}: {one_line(exc)}") from exc


def without_hydra(config: DictConfig) -> DictConfig:
    """A deep copy of a composed config without Hydra's node (the task's config)."""
    task = copy.deepcopy(config)
    with read_write(task), open_dict(task):
        del task["hydra"]
    return task


def _no_value(key: str) -> NoReturn:
    raise ConfigError(f"{key}: no value given (a required key: set it in the file or on "
                      f"the command line, e.g. {key}=...)") from None


def _unset(cfg: DictConfig, key: str) -> bool:
    """The dotted ``key``'s value is ``???``."""
    parent, _, name = key.rpartition(".")
    return OmegaConf.is_missing(OmegaConf.select(cfg, parent) if parent else cfg, name)


def _derivable(full: DictConfig, plain: DictConfig) -> Copies | None:
    """The typed job config of no override (``full`` masked to ``plain``'s keys, a required value
    of the files left unset for the overrides to give), from which each job's is derived, when
    no value of the files is an interpolation (a typed config holds resolved values, which an
    override of another key could change); else None."""
    if "${" in to_yaml(plain):
        return None
    return Copies(masked(full, plain, missing_ok=True))


def _not_derivable(override: Override) -> bool:
    """A plain override whose typed value depends on more than its own text: an interpolation
    (resolved against the job's config). A dict value is merged by Hydra's composition
    (:func:`structural`)."""
    return "${" in str(override.value())


NAME_MAX = 255  # bytes in one folder name (Linux, macOS)
BYTES_PER_POSE = 200  # a points.parquet row with its margins, generously
BYTES_PER_JOB = 512 * 1024  # Hydra's files, the log and the summary of one job


def _check_output_folders(folders: list[Path], first: DictConfig, n_jobs: int) -> None:
    """The jobs' folders can be made and written and their disk has room: a path through a
    file, a folder name over 255 bytes, a read-only place or a full disk is one line naming the
    path, before anything is written. ``first``: the first job's valid config."""
    for folder in folders:
        _writable(folder)
    needed = n_jobs * (BYTES_PER_JOB + BYTES_PER_POSE * grid_size(first))  # a sweep varies values, not grids
    probe = _existing_ancestor(folders[0])
    free = shutil.disk_usage(probe).free
    if free < needed:
        raise ConfigError(f"{folders[0]}: needs about {needed / 2**20:.1f} MiB, {free / 2**20:.1f} MiB "
                          f"free on its disk ({probe})")


def override_dirname(parsed: list[Override], naming) -> str:
    """Hydra's ``hydra.job.override_dirname`` of a job (its config loader's rule): the task
    overrides but the excluded keys, sorted, joined with the item separator, every ``=``
    replaced by the key-value separator. ``naming``: ``hydra.job.config.override_dirname``."""
    lines = sorted(o.input_line for o in parsed
                   if not o.is_hydra_override() and o.key_or_group not in naming.exclude_keys)
    return naming.item_sep.join(lines).replace("=", naming.kv_sep)


def _writable(folder: Path) -> None:
    for part in folder.parts:
        if len(os.fsencode(part)) > NAME_MAX:
            raise ConfigError(f"{folder}: a folder name of {len(os.fsencode(part))} bytes (at most "
                              f"{NAME_MAX}): choose a shorter hydra.run.dir, or sweep fewer or shorter values")
    probe = _existing_ancestor(folder)
    if not probe.is_dir():
        raise ConfigError(f"{folder}: {probe} is a file, not a folder")
    if not os.access(probe, os.W_OK | os.X_OK):
        raise ConfigError(f"{folder}: {probe} is not writable")


def _existing_ancestor(folder: Path) -> Path:
    probe = folder.absolute()
    while not probe.exists() and probe != probe.parent:
        probe = probe.parent
    return probe


def _search_path(argv: list[str]) -> tuple[str, ...]:
    """``--config-dir DIR`` (``-cd DIR``, ``--config-dir=DIR``) as the override Hydra applies for
    it, so that the plan composes from the user's folder; its files are checked first
    (:func:`_check_user_files`)."""
    for i, arg in enumerate(argv):
        folder = None
        if arg in ("--config-dir", "-cd") and i + 1 < len(argv):
            folder = argv[i + 1]
        elif arg.startswith("--config-dir="):
            folder = arg.split("=", 1)[1]
        if folder is not None:
            path = Path(folder).expanduser().resolve()
            if not path.is_dir():
                raise ConfigError(f"--config-dir={folder}: no such folder")
            _check_user_files(path)
            return (f"hydra.searchpath=[file://{path}]",)
    return ()


USER_FILE_BYTES = 1 << 20  # a robot file of a thousand cables is about 100 kB


def _check_user_files(folder: Path) -> None:
    """The YAML files of a user's config folder (robot, analysis and tension files, often shared
    or imported) carry their own keys only: one that sets Hydra's node or picks a Hydra plugin
    (``hydra:``, ``override hydra/...``, whose callbacks, launchers and environment run code)
    is refused with one line naming it, as is a file too large or not YAML."""
    import yaml

    for path in sorted(folder.rglob("*.yaml")):
        where = path.relative_to(folder)
        if path.stat().st_size > USER_FILE_BYTES:
            raise ConfigError(f"--config-dir={folder}: {where}: {path.stat().st_size} bytes "
                              f"(a config file is at most {USER_FILE_BYTES} bytes)")
        try:
            text = path.read_text(encoding="utf-8")
            refuse_aliases(text, f"--config-dir={folder}: {where}")
            data = yaml.safe_load(text)
        except (yaml.YAMLError, UnicodeDecodeError) as exc:
            raise ConfigError(f"--config-dir={folder}: {where}: not YAML ({one_line(exc)})") from None
        if not isinstance(data, dict):
            continue
        defaults = data.get("defaults") if isinstance(data.get("defaults"), list) else []
        entries = [str(next(iter(d))) if isinstance(d, dict) and d else str(d) for d in defaults]
        if "hydra" in data or any(re.match(r"(override\s+)?/?hydra(/|$|_settings)", e) for e in entries):
            if ".hydra" in where.parts:  # a job's own record: the outputs were written into the config folder
                job = Path(*where.parts[:where.parts.index(".hydra")])
                raise ConfigError(f"--config-dir={folder}: {job}/ is a job's output folder, inside your config folder (its "
                                  f"{where} records Hydra's settings); write outputs elsewhere (hydra.run.dir=... for a "
                                  "job, --out for a study, or run from another folder) or keep your robot files in a "
                                  "folder of their own")
            raise ConfigError(f"--config-dir={folder}: {where} sets Hydra's own settings (callbacks, "
                              "launchers, environment: they run code); a robot, analysis or tension file "
                              "carries its own keys only")


def refuse_aliases(text: str, where: str) -> None:
    """ConfigError for YAML text with an alias (``*name``): a few lines of anchors and aliases
    expand to billions of nodes (the "billion laughs"), which would hang the composition; a
    config file a user writes or shares has no need of them. Read as a stream of events, which
    expands nothing; a YAML error is the caller's to report."""
    import yaml

    for event in yaml.parse(text):
        if isinstance(event, yaml.AliasEvent):
            raise ConfigError(f"{where}: line {event.start_mark.line + 1}: a YAML alias (*{event.anchor}); "
                              "write the values out (aliases are refused: a few can expand to billions)")


def _missing_option(exc: MissingConfigException, parsed: list[Override], folders: list[Path]) -> str:
    """'group=option: no such option (options: ...)' for the override that named it; the
    options of every config folder searched (``folders``: conf/ and the user's)."""
    for override in parsed:
        group = override.key_or_group
        if group.startswith("hydra/") and f"{group}/{override.value()}" in str(exc):  # a Hydra plugin's group
            found = re.search(r"Available options in '[^']+':(.*?)Config search path", str(exc), re.S)
            options = ", ".join(o for o in re.split(r"[\s:]+", found.group(1)) if o) if found else "?"
            plugin = {"hydra/launcher": "'cdpr-studies[cluster]' (hydra-submitit-launcher)",
                      "hydra/sweeper": "hydra-optuna-sweeper"}
            return (f"{override.input_line}: no such option of Hydra's {group} group (options: {options}; a "
                    f"Hydra plugin adds its own, e.g. pip install {plugin.get(group, 'the plugin')})")
        if (CONF_DIR / group).is_dir() and not group.startswith("hydra") and f"{group}/{override.value()}" in str(exc):
            options = sorted({f.stem for folder in folders for f in (folder / group).glob("*.yaml")})
            own = "" if len(folders) > 1 else f"; your own: --config-dir DIR with DIR/{group}/NAME.yaml"
            return f"{override.input_line}: no such option of the {group} group (options: {', '.join(options)}{own})"
    return one_line(exc)


def structural(override: Override) -> bool:
    """Overrides that change which config files are composed, or that Hydra must merge into
    them itself: config groups (Hydra's own included), ``+``, ``++``, ``~``, a package, Hydra's
    search path. Plain ``key=value`` overrides, Hydra's ``hydra.*`` keys too, apply after."""
    key = override.key_or_group
    return (
        override.is_add() or override.is_delete() or override.is_force_add()
        or override.is_sweep_override() or override.package is not None
        or key.startswith("hydra/") or key == "hydra.searchpath" or (CONF_DIR / key).is_dir()
        or isinstance(override.value(), dict)
    )


RENAMED = {"limits.s_max": "tension.t_max"}  # keys that went, and the one that took their place


def _leaf_keys(tree, prefix: str = ""):
    """The dotted keys of a config's values and mappings (``load.mass``, ``robot.search``)."""
    if isinstance(tree, DictConfig):
        tree = OmegaConf.to_container(tree, resolve=False, throw_on_missing=False)
    for key, value in tree.items():
        yield f"{prefix}{key}"
        if isinstance(value, dict):
            yield from _leaf_keys(value, f"{prefix}{key}.")


def nearest_key(name: str, cfg) -> str | None:
    """The key of ``cfg`` (a config or its plain container) a mistyped ``name`` most likely means."""
    close = difflib.get_close_matches(name, list(_leaf_keys(cfg)), n=1, cutoff=0.8)
    return close[0] if close else None


def _apply(cfg: DictConfig, override: Override) -> None:
    """``key=value`` merged into the typed config, as Hydra's own override does."""
    try:
        OmegaConf.update(cfg, override.key_or_group, override.value(), merge=True)
    except (ConfigAttributeError, ConfigKeyError):  # not a key of this job's robot and analysis
        close = RENAMED.get(override.key_or_group) or nearest_key(override.key_or_group, cfg)
        hint = f"; did you mean {close}?" if close else " (a key of another analysis or robot, or a typo)"
        raise ConfigError(f"{override.input_line}: no such key for robot={cfg.robot.name} with "
                          f"analysis={cfg.analysis}{hint}") from None
    except Exception as exc:  # OmegaConf raises key, type and validation errors
        raise ConfigError(f"{override.input_line}: {one_line(exc)}") from exc
