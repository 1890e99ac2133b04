"""Validate every job of a command line before Hydra creates any output folder.

Hydra makes the run (or sweep) folder before the task function starts, so a bad value found
inside a job would leave folders behind. The preflight expands the command's sweep exactly as
Hydra's basic sweeper does (with Hydra's public override parser), builds each job's config, validates it, and stops at the first
problem with a one-line message naming the key and value.

Composing a config costs about 80 ms, so a sweep of a thousand jobs is not composed a thousand
times: jobs that share their structural overrides (config groups, ``+``/``~``, ``hydra.*``) share
one composition (:class:`Composition`), and each job's plain ``key=value`` overrides are applied
to a copy of it with the same typed merge Hydra uses (the dataclass schema still rejects a bad
key or type). The typed config of a job is derived from the composition's, typed once, and the
typed value of each override text, typed once: about 10 ms a job instead of 21.
"""

from __future__ import annotations

import copy
import functools
import itertools
import math
import os
import pickle
import re
import shutil
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from hydra import compose, initialize_config_dir
from hydra.errors import MissingConfigException
from hydra.core.override_parser.overrides_parser import OverridesParser
from hydra.core.override_parser.types import ChoiceSweep, Override, RangeSweep
from omegaconf import DictConfig, ListConfig, OmegaConf, open_dict, read_write
from omegaconf.errors import ConfigAttributeError, ConfigKeyError, MissingMandatoryValue

from pipeline.model.catalogue import load_catalogue
from pipeline.app.config import job_dir_name, masked, register, typed_schema, validate
from pipeline.errors import ConfigError, one_line
from pipeline.app.resources import CONF_DIR
from pipeline.app.yamltext import to_yaml
NO_JOB_FLAGS = {"--help", "-h", "--hydra-help", "--info", "-i", "--cfg", "-c", "--version",
                "--shell-completion", "-sc", "--resolve", "-p", "--package"}
FLAGS_WITH_VALUE = {"--config-path", "-cp", "--config-name", "-cn", "--config-dir", "-cd",
                    "--experimental-rerun"}


def job_overrides(argv: list[str]) -> list[list[str]] | None:
    """The override list of every job the command would launch; None when it launches none.

    The expansion is the basic sweeper's: the cartesian product of every override's values, in
    command order. A sweep it cannot enumerate (``interval(...)``, or another sweeper such as
    Optuna choosing the values) is checked with its other overrides only: one job, the sweep's
    fixed part, so such sweepers are not refused."""
    overrides = _overrides(argv)
    if overrides is None or not _is_multirun(argv):
        return None if overrides is None else [overrides]
    parsed = parse(overrides)
    if any(o.is_interval_sweep() for o in parsed) or _other_sweeper(parsed):
        return [[o.input_line for o in parsed if not o.is_sweep_override()]]
    return expand_sweep(parsed)


MAX_JOBS = 100_000  # jobs one command may launch: a typo in a range could ask for 10^8


def expand_sweep(parsed: list[Override]) -> list[list[str]]:
    """The basic sweeper's jobs: the cartesian product of every override's values, in command
    order (``pipeline.sweeper`` launches exactly these). Counted first: more than MAX_JOBS is a
    ConfigError naming the sweeps, before any list is made."""
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


def _other_sweeper(parsed: list[Override]) -> bool:
    """The command picks a sweeper other than Hydra's basic one."""
    return any(o.key_or_group == "hydra/sweeper" and o.value() not in ("basic", "cdpr") for o in parsed)


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


def _multirun_base(argv: list[str]) -> list[str] | None:
    """A multirun's non-sweep overrides, in order: Hydra applies them all (a repeated key
    included) when it composes the sweep config, before the jobs."""
    if not _is_multirun(argv):
        return None
    return [o.input_line for o in parse(_overrides(argv)) if not o.is_sweep_override()]


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
    """One override parsed (about 0.3 ms with Hydra's grammar; the jobs of a sweep repeat the
    same ``key=value`` texts, read only, so each is parsed once)."""
    try:
        return tuple(OverridesParser.create().parse_overrides([text]))
    except Exception as exc:  # Hydra's override grammar errors have several types
        raise ConfigError(f"{text}: {one_line(exc)}") from exc


RUN_FOLDERS = ("hydra.run.dir", "hydra.sweep.dir")


class Copies:
    """Fresh copies of one config, each equal to what ``copy.deepcopy`` makes, at a fraction of
    its cost: the config is pickled once and each copy unpickled (about 1.0 ms against 4.8 ms
    for a composed config with Hydra's node, which a sweep copies once per job). The copies are
    of ``cfg`` as it is now: a later change to it is not in them. A config that pickle cannot
    write (a structured config whose class it cannot find by name, e.g. one defined in a
    function) is deep-copied instead."""

    def __init__(self, cfg: DictConfig) -> None:
        try:
            self._pickled, self._cfg = pickle.dumps(cfg, protocol=pickle.HIGHEST_PROTOCOL), None
        except (pickle.PicklingError, AttributeError, TypeError):  # pickle's refusals
            self._pickled, self._cfg = None, copy.deepcopy(cfg)

    def __call__(self) -> DictConfig:
        return pickle.loads(self._pickled) if self._cfg is None else copy.deepcopy(self._cfg)


class Composition:
    """One set of config files, composed once: Hydra's node, the job config as Hydra composes
    it, and its typed version (:func:`pipeline.app.config.typed_schema`, every declared key),
    from which each job's config is made by its plain ``key=value`` overrides (:meth:`job`)."""

    def __init__(self, hydra: DictConfig) -> None:
        plain = without_hydra(hydra)
        self.hydra = Copies(hydra)
        self.plain = Copies(plain)
        full = typed_schema(plain)  # typed once per composition
        self._full = Copies(full)
        self._typed = _derivable(full, plain)
        self._scratch = full  # where each override text is typed, once (:meth:`_typed_value`)
        self._converted: dict[str, Any] = {}


    def job(self, parsed: list[Override]) -> tuple[DictConfig, DictConfig]:
        """(the job's typed config, its config as Hydra composes it) for its parsed overrides,
        each plain one applied to both in command order: the first override that is not a key
        of this robot and analysis, or whose value is not of the key's declared type, raises."""
        plain = self.plain()
        overrides = [o for o in parsed if not structural(o)]
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
        return typed, plain

    def _typed_value(self, override: Override) -> Any:
        """The override's value as its key's declared type makes it (what :func:`masked` takes
        from the typed config), typed once per override text: a value's type depends on its
        key only, in one composition."""
        if override.input_line not in self._converted:
            _apply(self._scratch, override)  # ConfigError for a value of the wrong type
            value = OmegaConf.select(self._scratch, override.key_or_group)
            self._converted[override.input_line] = (OmegaConf.to_container(value) if isinstance(
                value, (DictConfig, ListConfig)) else value)
        return self._converted[override.input_line]


def without_hydra(config: DictConfig) -> DictConfig:
    """A deep copy of a composed config without Hydra's node (the task's config, as Hydra's
    ``run_job`` makes it)."""
    task = copy.deepcopy(config)
    with read_write(task), open_dict(task):
        del task["hydra"]
    return task


def _derivable(full: DictConfig, plain: DictConfig) -> Copies | None:
    """The typed job config of no override (``full`` masked to ``plain``'s keys), from which each
    job's is derived, when every value of the files is set and none is an interpolation (a
    typed config holds resolved values, which an override of another key could change); else
    None."""
    if "${" in to_yaml(plain):
        return None
    try:
        return Copies(masked(full, plain))
    except MissingMandatoryValue:  # ??? in the files: the overrides give it
        return None


def _not_derivable(override: Override) -> bool:
    """A plain override whose typed value depends on more than its own text: a dict (merged
    into the key's current value) or an interpolation (resolved against the job's config)."""
    value = override.value()
    return isinstance(value, dict) or "${" in str(value)


@dataclass
class Reuse:
    """What :func:`check` may keep across calls over the same config files and catalogues (a
    study's trials, checked one by one): each set of files composed and typed once
    (:class:`Composition`), each catalogue read once, the run folder (``RUN_FOLDERS``, the
    caller's own) set afterwards. The configs are copied before any override is applied."""

    compositions: dict = field(default_factory=dict)
    catalogues: dict = field(default_factory=dict)
    folders_after: bool = True  # False: the run folder is composed with the files, as Hydra does


def check(argv: list[str], reuse: Reuse | None = None) -> dict[str, tuple[DictConfig, Any]]:
    """Raise ConfigError for the first job whose config cannot be composed or is invalid. Returns
    every job's typed, validated config and catalogue (None without an actuator), by the YAML of
    its composed config (``pipeline.app.job.PREPARED``: a job run in this process is not typed twice).
    ``reuse``: kept by a caller that checks many commands over the same files (:class:`Reuse`)."""
    try:
        jobs = job_overrides(argv)
        multirun_base = _multirun_base(argv) if jobs is not None else None
    except Exception as exc:  # Hydra's override grammar errors have several types
        raise ConfigError(one_line(exc)) from exc
    if jobs is None:
        return {}
    for override in parse(_overrides(argv)):
        if override.key_or_group.startswith("hydra.callbacks") and not override.is_delete():
            raise ConfigError(f"{override.input_line}: a Hydra callback runs code; the command line may "
                              "remove the project's (~hydra.callbacks.sweep_summary), not add or change one")
    register()
    search_path = _search_path(argv)
    # a caller's trials differ in their folder too: that value is set on Hydra's node afterwards
    after = RUN_FOLDERS if reuse is not None and reuse.folders_after else ()
    reuse = Reuse() if reuse is None else reuse
    composed: dict[tuple[str, ...], Composition] = reuse.compositions
    catalogues = reuse.catalogues
    prepared = {}

    def composed_for(overrides: list[str]) -> tuple[list[Override], Composition]:
        """The job's parsed overrides, and the composition of its files."""
        parsed = parse(overrides)
        files = _files(search_path, parsed, after, multirun_base is None)
        if files not in composed:
            try:
                hydra = compose(config_name="config", overrides=list(files), return_hydra_config=True)
            except MissingConfigException as exc:  # a group option with no file
                raise ConfigError(_missing_option(exc, parsed)) from exc
            except Exception as exc:  # composition errors come as Hydra and OmegaConf types
                raise ConfigError(one_line(exc)) from exc
            composed[files] = Composition(hydra)
        return parsed, composed[files]

    def build(overrides: list[str]) -> tuple[DictConfig, DictConfig]:
        """(the job's typed config, its config as Hydra composes it)"""
        parsed, composition = composed_for(overrides)
        try:
            return composition.job(parsed)
        except MissingMandatoryValue as exc:  # ??? in a file, and not given
            raise ConfigError(f"{exc.full_key}: no value given (a required key: set it in the file or on "
                              f"the command line, e.g. {exc.full_key}=...)") from None

    def hydra_node(overrides: list[str]) -> DictConfig:
        parsed, composition = composed_for(overrides)
        hydra = composition.hydra()
        for override in parsed:
            if not structural(override) or override.key_or_group in after:
                _apply(hydra, override)
        return hydra.hydra

    with initialize_config_dir(config_dir=str(CONF_DIR), version_base="1.3", job_name="preflight"):
        if multirun_base is not None:
            build(multirun_base)  # Hydra composes the sweep's own config from these first
        for overrides in jobs:
            cfg, plain = build(overrides)
            catalogue = None
            if "catalogue" in cfg:  # analyses with an actuator
                if cfg.catalogue not in catalogues:
                    catalogues[cfg.catalogue] = load_catalogue(cfg.catalogue)
                catalogue = catalogues[cfg.catalogue]
            validate(cfg, None if catalogue is None else catalogue.ids, typed=True)
            prepared[to_yaml(plain)] = cfg, catalogue
        hydra = hydra_node(jobs[0] if multirun_base is None else multirun_base)
    first = next(iter(prepared.values()))[0]
    _check_launcher(hydra.launcher)
    _check_output_folders(jobs, first, hydra, multirun_base is not None)
    return prepared


def _files(search_path: tuple[str, ...], parsed: list[Override], after, run: bool) -> tuple[str, ...]:
    """What a job's composition is made of: the search path and the structural overrides (but
    the folders set ``after``), and for a command of run mode the override Hydra's ``run`` adds
    last when the command names no mode, so that Hydra's node is the one that run composes."""
    own = tuple(o.input_line for o in parsed if structural(o) and o.key_or_group not in after)
    named = any(o.key_or_group == "hydra.mode" for o in parsed)
    return (*search_path, *own, *(("hydra.mode=RUN",) if run and not named else ()))


def hydra_run(argv: list[str], reuse: Reuse) -> tuple[DictConfig, DictConfig] | None:
    """For a command of run mode made of overrides only, none of which Hydra must merge into
    the files itself (``+``, ``++``, ``~``, a dict value) nor sets the mode or ``hydra.verbose``
    (whose report of the composition only Hydra's loader prints): the config Hydra's
    ``run`` composes, and the same without Hydra's node, derived (:func:`derived`) from the
    composition :func:`check` made and kept in ``reuse`` (``folders_after`` False); None for
    any other command, which Hydra composes. Hydra's run composes twice (its ``get_mode``,
    then the run): about 0.15 s of a job's 0.6 s."""
    if reuse.folders_after or any(arg.startswith("-") for arg in argv):
        return None
    parsed = parse(argv)
    if not all(applies_after_composing(o) and o.key_or_group not in ("hydra.mode", "hydra.verbose")
               for o in parsed):
        return None
    composition = reuse.compositions[_files(_search_path(argv), parsed, (), True)]
    return derived(composition.hydra(), composition.plain(), parsed)


def applies_after_composing(override: Override) -> bool:
    """An override that a job's config can take after its files are composed (the loader's
    ``OmegaConf.update(..., merge=True)``): not ``+``, ``++``, ``~`` nor a dict value."""
    return not (override.is_add() or override.is_delete() or override.is_force_add()
                or isinstance(override.value(), dict))


def derived(config: DictConfig, task: DictConfig, parsed: list[Override]) -> tuple[DictConfig, DictConfig]:
    """A job's config as Hydra's config loader composes it from its files' composition
    (``config``, with Hydra's node, and ``task``, without; both changed here): the plain
    overrides applied in command order as the loader applies them, ``hydra.overrides.task``
    and ``hydra.job.override_dirname`` by the loader's rules."""
    for override in parsed:
        if not structural(override):
            for node in (config, task):
                OmegaConf.update(node, override.key_or_group, override.value(), merge=True)
    task_overrides = [o for o in parsed if not o.is_hydra_override()]
    config.hydra.overrides.task = [o.input_line for o in task_overrides]
    config.hydra.job.override_dirname = override_dirname(task_overrides, config.hydra.job.config.override_dirname)
    return config, task


def _check_launcher(launcher: DictConfig) -> None:
    """The ``cdpr`` launcher's setting (its own rule), before Hydra instantiates it."""
    if str(launcher.get("_target_", "")).startswith("hydra_plugins.cdpr."):
        from hydra_plugins.cdpr.launcher import n_jobs_rule

        broken = n_jobs_rule(launcher.get("n_jobs"))
        if broken:
            raise ConfigError(f"hydra.launcher.n_jobs={launcher.get('n_jobs')}: {broken}")


NAME_MAX = 255  # bytes in one folder name (Linux, macOS)
BYTES_PER_POSE = 200  # a points.parquet row with its margins, generously
BYTES_PER_JOB = 512 * 1024  # Hydra's files, the log and the summary of one job


def _check_output_folders(jobs: list[list[str]], first: DictConfig, hydra: DictConfig,
                          multirun: bool) -> None:
    """The folders Hydra will make (run dir, or one per job of a sweep) can be made and written
    and their disk has room: a path through a file, a folder name over 255 bytes, a read-only
    place or a full disk is one line naming the path, before anything is written. ``first``:
    the first job's valid config; ``hydra``: Hydra's node of the run or sweep config."""
    from pipeline.workspace.compute import grid_size

    folders = [Path(hydra.run.dir)]
    if multirun:
        naming = hydra.job.config.override_dirname
        folders = [Path(hydra.sweep.dir) / job_dir_name(override_dirname(parse(job), naming), number)
                   for number, job in enumerate(jobs)]
    for folder in folders:
        _writable(folder)
    needed = len(jobs) * (BYTES_PER_JOB + BYTES_PER_POSE * grid_size(first))  # a sweep varies values, not grids
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
    it, so that the preflight composes from the user's folder as the job will; its files are
    checked first (:func:`_check_user_files`)."""
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
            data = yaml.safe_load(path.read_text(encoding="utf-8"))
        except (yaml.YAMLError, UnicodeDecodeError) as exc:
            raise ConfigError(f"--config-dir={folder}: {where}: not YAML ({one_line(exc)})") from None
        if not isinstance(data, dict):
            continue
        defaults = data.get("defaults") if isinstance(data.get("defaults"), list) else []
        entries = [str(next(iter(d))) if isinstance(d, dict) and d else str(d) for d in defaults]
        if "hydra" in data or any(re.match(r"(override\s+)?/?hydra(/|$|_settings)", e) for e in entries):
            raise ConfigError(f"--config-dir={folder}: {where} sets Hydra's own settings (callbacks, "
                              "launchers, environment: they run code); a robot, analysis or tension file "
                              "carries its own keys only")


def _missing_option(exc: MissingConfigException, parsed: list[Override]) -> str:
    """'group=option: no such option (options: ...)' for the override that named it."""
    for override in parsed:
        group = override.key_or_group
        if (CONF_DIR / group).is_dir() and f"{group}/{override.value()}" in str(exc):
            options = sorted(f.stem for f in (CONF_DIR / group).glob("*.yaml"))
            return (f"{override.input_line}: no such option of the {group} group "
                    f"(options: {', '.join(options)}; your own: --config-dir DIR with DIR/{group}/NAME.yaml)")
    return one_line(exc)


def structural(override: Override) -> bool:
    """Overrides that change which config files are composed, or that Hydra must interpret."""
    key = override.key_or_group
    return (
        override.is_add() or override.is_delete() or override.is_force_add()
        or override.is_sweep_override() or override.package is not None
        or re.split(r"[./]", key)[0] == "hydra" or (CONF_DIR / key).is_dir()
    )


def _apply(cfg: DictConfig, override: Override) -> None:
    """``key=value`` merged into the typed config, as Hydra's own override does."""
    try:
        OmegaConf.update(cfg, override.key_or_group, override.value(), merge=True)
    except (ConfigAttributeError, ConfigKeyError):  # not a key of this job's robot and analysis
        raise ConfigError(f"{override.input_line}: no such key for robot={cfg.robot.name} with "
                          f"analysis={cfg.analysis} (a key of another analysis or robot, or a typo)") from None
    except Exception as exc:  # OmegaConf raises key, type and validation errors
        raise ConfigError(f"{override.input_line}: {one_line(exc)}") from exc
