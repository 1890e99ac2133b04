"""Structured configuration: the keys of every config group, their types and value rules.

The dataclasses give every key a type and its value rules, and no value: every default lives
once, in the YAML files of ``conf/`` (``conf/config.yaml`` and its groups), which are what a
user reads, overrides and DVC tracks as parameters (``tests/test_config_schema.py`` checks that
no field declares a default and that every declared key of each robot x analysis x tension
combination gets one). A wrong key or a non-numeric value fails while the config is typed
(:func:`pipeline.app.problem.typed_config`); :func:`check_values` then applies the declared
rules (positive masses, a carrier that fits in its frame) and raises :class:`ConfigError`
naming the offending key and value. ``pipeline.app.problem`` names the robot and analysis
kinds and builds the problem.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field, fields, is_dataclass
from enum import Enum
from typing import Any, Optional

from omegaconf import MISSING, DictConfig, ListConfig, OmegaConf
from omegaconf.errors import MissingMandatoryValue, OmegaConfBaseException

from pipeline.errors import ConfigError, one_line, text_number
from pipeline.model.catalogue import GEAR_RATIOS, WINCH_RADII

INF = float("inf")
JOBLIB_BACKENDS = ("loky", "threading", "multiprocessing", "sequential", "dask")


# Value rules sit next to the fields they constrain (scikit-learn's declared parameter
# constraints): ``rule(check, default)`` declares a field, :func:`check_values` applies every
# declared rule of a typed config once, and a schema's ``check_fields`` holds its rules between
# fields. A check returns None when the value is fine, else what it must be.
def rule(check, **default):
    """A dataclass field whose (non-null) value must pass ``check``; its value comes from the
    YAML files (no default here: one source of each default), except for the optional fields
    of a study file (``default=`` or ``default_factory=``)."""
    return field(**(default or {"default": MISSING}), metadata={"check": check})


def positive(value):
    return None if 0 < value < INF else "must be > 0 and finite"


def non_negative(value):
    return None if 0 <= value < INF else "must be >= 0 and finite"


def finite(value):
    return None if abs(value) < INF else "must be finite"


def sampler_seed(value):
    return None if isinstance(value, int) and 0 <= value < 2**32 else "must be an integer in [0, 2^32 - 1] (a sampler's seed)"


def sag_share(value):
    return None if 0 < value <= 0.1 else "must be in (0, 0.1]: the sag a cable may take, a share of its chord"


# Largest force or moment (N, N m) and mass (kg) a config may give: far beyond any cable robot,
# and well inside the range where the LP solver's coefficients stay finite (HiGHS reads 1e20 as
# infinite), so a mistyped exponent is one line rather than a solver failure.
MAX_FORCE = 1e9
MAX_REACH = 1e4  # m: a centre of mass or a way-point past any cable robot's frame, a unit typed wrong
MAX_MASS = 1e8


def reach(value):
    return None if 0 <= value <= MAX_REACH else f"must be in [0, {MAX_REACH:g}] m"


def force(value):
    return None if abs(value) <= MAX_FORCE else f"must be finite and at most {MAX_FORCE:g} in magnitude (N, N m)"


def mass_kg(value):
    return None if 0 <= value <= MAX_MASS else f"must be >= 0 and at most {MAX_MASS:g} kg"


def at_least(bound: int):
    return lambda value: None if value >= bound else f"must be >= {bound}"


def vector(size: int, meaning: str, bound: float = INF):
    """``size`` finite numbers, each at most ``bound`` in magnitude."""
    def check(values):
        values = list(values)
        if not all(isinstance(v, (int, float)) and abs(v) < INF for v in values):
            return "every value must be a finite number" + text_number(values)
        if not all(abs(v) <= bound for v in values):
            return f"every value must be at most {bound:g} in magnitude"
        return None if len(values) == size else f"needs {size} values ({meaning})"
    return check


class PinvColumns(Enum):
    """Which columns of J enter the pseudo-inverse of eq. (20): all six (full, the default) or
    the three position columns (translational); docs/evidence.md section 1."""

    translational = "translational"
    full = "full"


class Kernel(Enum):
    """Which code evaluates the criteria: ``auto`` (the compiled kernels where they apply and
    the cost model says they pay, for the job or its sweep), ``numpy`` (always the numpy
    criteria) or ``fused`` (the compiled kernels of ``pipeline.workspace.fused``, refused where
    they do not apply)."""

    auto = "auto"
    numpy = "numpy"
    fused = "fused"


class VelocityBoundary(Enum):
    """Whether grid velocities with |v| = V_cmax exactly belong to the set of eq. (26)."""

    exclude = "exclude"
    include = "include"


class AccelerationSet(Enum):
    """Reading of eqs. (27)-(29): box corners, or MATLAB's literal colon with step 1."""

    corners = "corners"
    colon = "colon"


class MomentArm(Enum):
    """Moment arm of eq. (8) of the IRPM paper: R d_i (about O_M) or r + R d_i (eq. 9 literal)."""

    platform = "platform"
    base = "base"


class CableDirection(Enum):
    """Where a cable of the IRPM statics pulls: from its anchor towards its attachment point
    (physical) or towards the platform's reference point (the platform a point for the cables'
    directions and lengths, moment arms R d_i kept; docs/evidence.md section 2)."""

    attachment = "attachment"
    centre = "centre"


class Distribution(Enum):
    """Which tensions the ``feasible`` model writes with ``output.cables=true``: the least 2-norm
    within the limits (as CASPR and WireX give them) or the vertex its LPs end on."""

    min_norm = "min_norm"
    lp = "lp"


class Convention(Enum):
    """How the three orientation angles make a rotation: eq. (9)'s R = Rz(phi) Ry(theta) Rx(psi)
    (zyx) or R = Rx(psi) Ry(theta) Rz(phi) (xyz, CASPR's SPATIAL_EULER_XYZ)."""

    zyx = "zyx"
    xyz = "xyz"


class TensionModel(Enum):
    """Cable forces the criteria check: minimum-norm (the papers' eq. 20 / eq. 10, any sign) or
    pulling cables only, chosen by linear programming (``pipeline.model.tensions``)."""

    pinv = "pinv"
    feasible = "feasible"


class Spacing(Enum):
    """Where the N grid points of an axis sit in the geometric workspace."""

    linspace = "linspace"
    centred = "centred"


class LineSamples(Enum):
    """Which straight lines' samples ``analysis=lines`` writes to samples.parquet: the first
    (line O''-F'', the one Fig. 6 draws; 0.13 MB a job) or all 72 (5.4 MB a job)."""

    first = "first"
    all = "all"


class TimeLaw(Enum):
    """How ``analysis=trajectory`` moves between way-points (``pipeline.model.path``): rest to rest
    by a quintic per segment, one cubic spline through every way-point (at rest at both ends),
    or the CPR-8 paper's trapezoidal speed profile per straight segment."""

    quintic = "quintic"
    spline = "spline"
    trapezoid = "trapezoid"


@dataclass
class FrameConfig:
    """Frame d * s * v (m): the theoretical workspace of Fig. 2."""

    d: float = rule(positive)
    s: float = rule(positive)
    v: float = rule(positive)


@dataclass
class CarrierConfig:
    """Load carrier l * w * h_o (m), eqs. (1)-(8)."""

    l: float = rule(positive)
    w: float = rule(positive)
    h: float = rule(positive)


@dataclass
class PlatformConfig:
    """The robot's own moving platform: its mass (kg) and centre of mass (m, platform frame, at most 1e4).
    With the payload (``load.*``) it is the mass m of eq. (31) and the weight every analysis
    balances (CPR-8: the paper's carrier with its load, 2 kg; IRPM: 0, as its paper puts the
    weight in f_ext; a robot of points: 0 unless its file gives one). ``shape``: its body, which
    no cable may enter (criterion ``cable_platform``) and obstacles see: ``hull`` (the convex hull
    of the attachment points), a box ``{lo: [x, y, z], hi: [x, y, z]}`` (m, platform frame) with
    every attachment on its surface, or null (not checked; obstacles see the attachments' hull).
    ``inertia``: about its centre of mass, kg m^2, [Ixx, Iyy, Izz] or with [Ixy, Ixz, Iyz] after
    them (null: not given; the natural frequency of criterion ``stiffness`` needs it)."""

    mass: float = rule(mass_kg)
    com: list[float] = rule(vector(3, "x y z, m, platform frame", MAX_REACH))
    shape: Any = MISSING
    inertia: Any = MISSING


@dataclass
class RobotConfig:
    """What every robot has, declared once (values: the ``robot`` node of conf/config.yaml; each
    robot kind's schema extends it and its file sets what differs): ``name``, the robot kind;
    ``platform``, its moving platform; ``cable_diameter``, m, one or one per cable: cables
    closer than the sum of their radii interfere (criterion ``cable_cable``; null: not
    checked); ``l_max``, the longest cable, m (criterion ``length``; null: no limit); ``pulleys``,
    a swivelling pulley per cable at its anchor ({axis, radius}, one or one per cable; null:
    the cables leave the anchors); ``cable_ea``, each cable's axial stiffness EA, N (criterion
    ``stiffness``; null: rigid), ``winch_length``, m, the cable between anchor and winch, and
    ``cable_mass``, kg/m, each cable's mass per length (criterion ``sag``; null: weightless);
    ``catenary``, the largest sag a cable may take as a share of its chord, when the cables sag
    (Irvine's elastic catenary, analysis=statics, criterion ``catenary``; null: straight). The cell's
    ``obstacles`` and the tension limits (``tension.*``, one or one per cable) are keys of the
    job, checked against the robot as it is built."""

    name: str = MISSING
    platform: PlatformConfig = field(default_factory=PlatformConfig)
    cable_diameter: Any = MISSING
    l_max: Optional[float] = rule(positive)
    pulleys: Any = MISSING
    cable_ea: Any = MISSING
    winch_length: Any = MISSING
    cable_mass: Any = MISSING
    catenary: Optional[float] = rule(sag_share)


@dataclass
class Cpr8Config(RobotConfig):
    """CPR-8 robot (Fig. 1). ``lower_anchor_drop``: depth of O', F', G', H' below O, F, G, H
    (null = h_o as eqs. 14-17)."""

    frame: FrameConfig = field(default_factory=FrameConfig)
    carrier: CarrierConfig = field(default_factory=CarrierConfig)
    lower_anchor_drop: Optional[float] = rule(non_negative)

    @staticmethod
    def check_fields(robot: DictConfig) -> None:
        from pipeline.model.robots import carrier_half_diagonal

        de = carrier_half_diagonal(robot.carrier.l, robot.carrier.w, robot.carrier.h)
        for axis in ("d", "s", "v"):
            size = robot.frame[axis]
            if size <= 2 * de:
                raise ConfigError(
                    f"robot.frame.{axis}={size}: carrier does not fit "
                    f"(needs > 2 d_e = {2 * de:.4g} m for carrier {robot.carrier.l} x "
                    f"{robot.carrier.w} x {robot.carrier.h} m)"
                )


@dataclass
class SearchConfig:
    """Searched box (m) and grid step (m): points lo + k step up to hi on every axis."""

    lo: list[float] = rule(vector(3, "x, y, z"))
    hi: list[float] = rule(vector(3, "x, y, z"))
    step: float = rule(positive)

    @staticmethod
    def check_fields(search: DictConfig) -> None:
        for axis, lo, hi in zip("xyz", search.lo, search.hi):
            if not lo <= hi:
                raise ConfigError(f"robot.search: {axis} from {lo} to {hi}: must be finite with lo <= hi")


@dataclass
class Irpm6Config(RobotConfig):
    """6-cable IRPM (Hamed & Zohoor, Figs. 1-4): base and platform radii (m), pair angle gamma
    (deg), the search box of section III (its file sets l_max = 15 m)."""

    r_base: float = rule(positive)
    r_end: float = rule(positive)
    gamma_deg: float = rule(lambda v: None if 0 <= v < 120 else "must be in [0, 120) (pairs would overlap)")
    search: SearchConfig = field(default_factory=SearchConfig)


@dataclass
class PointsSearchConfig(SearchConfig):
    """Searched box and step (m), required unless the job lists its poses (``poses``);
    ``spacing``: ``faces`` (lo + k step up to hi, as the IRPM) or ``centres`` (lo + (k + 1/2)
    step, the centres of the cells of side step inside the box)."""

    lo: Optional[list[float]] = rule(vector(3, "x, y, z"))
    hi: Optional[list[float]] = rule(vector(3, "x, y, z"))
    step: Optional[float] = rule(positive)
    spacing: str = MISSING

    @staticmethod
    def check_fields(search: DictConfig) -> None:
        if search.lo is not None and search.hi is not None:
            SearchConfig.check_fields(search)


@dataclass
class PointsConfig(RobotConfig):
    """A robot given by its points (``pipeline.model.robots.PointsRobot.from_config`` checks them
    where it builds the robot): anchors (fixed frame) and attachments (platform frame), lists of
    [x, y, z] in m; optional cable names; the up direction; the search box; ``dofs``, the
    platform's freedoms among x, y, z, rx, ry, rz (the wrench rows the cables balance; a joint
    or a plane takes the others): all six for a free
    body, [x, y, z] for a point platform in space, [x, y] for a planar point, [x, y, rz] for a
    body in the x-y plane, [rx, ry, rz] for a platform on a spherical joint at the origin, whose
    search box is then of angles (psi, theta, phi in rad, in ``orientation.convention``)."""

    anchors: Any = MISSING
    attachments: Any = MISSING
    cable_names: Optional[list[str]] = MISSING
    up: list[float] = MISSING
    dofs: list[str] = MISSING
    search: PointsSearchConfig = field(default_factory=PointsSearchConfig)


@dataclass
class TotalOrientationConfig:
    """Total-orientation workspace: every orientation (psi, theta, phi) + offsets, with the
    offsets on a grid of ``n`` values per angle in [-bound, bound] rad (n = 1: constant
    orientation)."""

    bound: float = rule(non_negative)
    n: int = rule(at_least(1))


@dataclass
class OrientationConfig:
    """Carrier orientation, three Euler angles in rad; ``convention``: zyx, eq. (9)'s R =
    Rz(phi) Ry(theta) Rx(psi), or xyz, R = Rx(psi) Ry(theta) Rz(phi) (CASPR's SPATIAL_EULER_XYZ:
    its angles unchanged); ``total`` widens it to the total-orientation workspace around it
    (offsets to the angles of the convention)."""

    psi: float = rule(finite)
    theta: float = rule(finite)
    phi: float = rule(finite)
    convention: Convention = MISSING
    total: TotalOrientationConfig = field(default_factory=TotalOrientationConfig)


@dataclass
class WrenchConfig:
    """Applied wrench f_ext of eq. (11) of the IRPM paper, N and N m (the paper gives kN), added to
    the load's weight and ``load.external`` in every analysis (``robot=irpm6`` sets the paper's
    f_z = 100 kN: the platform's weight, Z down). ``set``: a required wrench set (statics), each of
    its wrenches added to that one and every one to be balanced (Gouttefarde's wrench-feasible
    workspace; the set is convex, so its vertices decide): a box ``{min: [6], max: [6]}``
    (fx fy fz mx my mz, its vertices those coordinates that differ) or a list of vertices
    ``[[fx, fy, fz, mx, my, mz], ...]``; null = the one wrench."""

    fx: float = rule(force)
    fy: float = rule(force)
    fz: float = rule(force)
    mx: float = rule(force)
    my: float = rule(force)
    mz: float = rule(force)
    set: Any = MISSING


@dataclass
class TensionConfig:
    """The config group ``tension=pinv|feasible`` and its keys. ``model``: pinv (the papers'
    minimum-norm forces, any sign) or feasible (cables only pull: hyperplane shifting, LPs where
    it cannot settle). ``t_min``: smallest tension (N; pinv checks it in statics only).
    ``t_max``: cable rating (N) in every analysis; each a number or one per cable, null = none
    (CPR-WWA: the motor torque limit / R_i only; ``robot=irpm6`` sets the paper's 55 kN, its
    s_max of eq. 10). ``residual_rtol``: a required wrench is unreachable when the
    equilibrium residual exceeds this fraction of it (feasible model). ``pinv_residual``: the
    same for the minimum-norm forces of CPR-WWA, which balance only the part of F in the range
    of J^T (the CPR-8 at the zero orientation has rank 5 and misses up to 1.4 % of F; a robot
    that cannot hold its load misses most of it; docs/model.md section 1). ``distribution`` (read by the feasible
    model): the tensions written with ``output.cables=true``, ``min_norm`` (the least 2-norm within the
    limits, exact by enumeration of faces, docs/model.md section 5) or ``lp`` (the vertex the LPs end
    on); the verdicts do not depend on it."""

    model: TensionModel = MISSING
    t_min: Any = MISSING
    t_max: Any = MISSING
    residual_rtol: float = rule(positive)
    distribution: Distribution = MISSING
    pinv_residual: float = rule(positive)


@dataclass
class GridConfig:
    """N points per axis of the CPR-8's geometric workspace (section 3; the paper uses N = 6);
    ``spacing``: linspace puts them on both faces (step (d - 2 d_e) / (N - 1)), centred at the N
    cell centres. ``n_vel``: N of the velocity grid of eqs. (23)-(25); null ties it to ``n`` as
    in the paper (6 for robots without ``grid.n``). Set it for dense position grids: n_vel = n =
    40 would test 33 371 velocities per pose; at least 2 (N = 1 leaves the cube's 8 corners, all
    outside |v| <= V_cmax of eq. 26)."""

    n: int = rule(at_least(2))
    n_vel: Optional[int] = rule(at_least(2))
    spacing: Spacing = MISSING


MAX_ACCELERATION = 1e4  # m/s^2, rad/s^2 and rad/s: past any cable robot's, a unit typed wrong
SPEEDS = (1e-6, 1e3)  # m/s: a carrier's top speed between a micrometre a second and a kilometre a second


TRAPEZOID_KEYS = ("v_max", "t_acc", "t_dec")  # a trapezoidal speed profile's (motion, trajectory, certified)


def trapezoid_speeds(node: DictConfig, key: str) -> tuple[float, float, float]:
    """A trapezoid's v_max, t_acc and t_dec (``key``: motion, trajectory or certified), each given,
    with v_max / t_acc and v_max / t_dec in (0, MAX_ACCELERATION] (1e-300 m/s over 1e300 s is 0)."""
    missing = [name for name in TRAPEZOID_KEYS if node[name] is None]
    if missing:
        raise ConfigError(f"{key}.{missing[0]}: {key}.law=trapezoid needs v_max (m/s), t_acc and t_dec (s)")
    v_max, t_acc, t_dec = (float(node[name]) for name in TRAPEZOID_KEYS)
    for name, time in (("t_acc", t_acc), ("t_dec", t_dec)):
        if not 0 < v_max / time <= MAX_ACCELERATION:
            raise ConfigError(f"{key}.{name}={time:g}: v_max / {name} = {v_max / time:.3g} m/s^2 at v_max={v_max:g} m/s; "
                              f"must be > 0 and at most {MAX_ACCELERATION:g} (a unit typed wrong, or {name} too short or "
                              "too long)")
    return v_max, t_acc, t_dec


@dataclass
class MotionConfig:
    """Trapezoidal reference motion: V_cmax (m/s, from 1e-6 to 1e3), t_acc and t_dec (s); the
    accelerations V_cmax / t_acc and V_cmax / t_dec at most 1e4 m/s^2."""

    v_max: float = rule(lambda v: None if SPEEDS[0] <= v <= SPEEDS[1] else
                        f"must be in [{SPEEDS[0]:g}, {SPEEDS[1]:g}] m/s (past either end, a unit typed wrong)")
    t_acc: float = rule(positive)
    t_dec: float = rule(positive)

    @staticmethod
    def check_fields(motion: DictConfig) -> None:
        if set(TRAPEZOID_KEYS) <= set(motion.keys()):  # a node of another analysis may hold some of them only
            trapezoid_speeds(motion, "motion")


@dataclass
class LoadConfig:
    """The payload on the robot's platform: its mass (kg, added to ``robot.platform.mass`` in
    eq. (31)) and centre of mass (m, platform frame); the gravitational acceleration g (m/s^2,
    along -up of the robot) and a constant external wrench [f_x f_y f_z M_x M_y M_z] (N, N m)
    the cables must also balance: the weight of platform and payload, its moment and the
    external wrench enter every analysis. Masses are bounded at 1e8 kg, forces at 1e9 N (N m),
    the centre of mass at 1e4 m and gravity at 1e4 m/s^2: far past any cable robot, where a
    mistyped exponent would reach the LP solver."""

    mass: float = rule(mass_kg)
    gravity: float = rule(lambda v: None if 0 <= v <= MAX_ACCELERATION else
                          f"must be in [0, {MAX_ACCELERATION:g}] m/s^2 (past any planet's, a unit typed wrong)")
    com: list[float] = rule(vector(3, "x y z, m, platform frame", MAX_REACH))
    external: list[float] = rule(vector(6, "fx fy fz mx my mz", MAX_FORCE))


@dataclass
class DriveConfig:
    """Design overrides of the catalogue's drive train, for every cable: winch radius R_i (m, 1e-4
    to 10) and gear ratio N_V (1e-3 to 1e5: past any gearbox, where the drive's constants of
    eq. 22 would overflow or divide by zero). null keeps each actuator's catalogue value."""

    winch_radius: Optional[float] = rule(lambda v: None if WINCH_RADII[0] <= v <= WINCH_RADII[1] else
                                         f"must be >= {WINCH_RADII[0]:g} and at most {WINCH_RADII[1]:g} m")
    gear_ratio: Optional[float] = rule(lambda v: None if GEAR_RATIOS[0] <= v <= GEAR_RATIOS[1] else
                                       f"must be >= {GEAR_RATIOS[0]:g} and at most {GEAR_RATIOS[1]:g}")


@dataclass
class ChoiceConfig:
    """CPR-ACM (section 4): an actuator is accepted when its feasible share x(i_a) >= required_pct."""

    required_pct: float = rule(lambda v: None if 0 < v <= 100 else "must be in (0, 100]")


@dataclass
class PlatformMotionConfig:
    """``analysis=statics``: the motion the cables must hold the platform in at every pose (issue
    56: the dynamic workspace). ``acceleration``: the accelerations required, each with every
    wrench, a box ``{min: [6], max: [6]}`` (its vertices decide: the wrench is affine in the
    acceleration), a list of ``[ax, ay, az, alpha_x, alpha_y, alpha_z]`` (m/s^2 of the
    platform's reference point and rad/s^2 of its turn, fixed axes), or balls
    ``{linear: r, angular: r}`` (each by the icosahedron around it); null: at rest.
    ``angular_velocity``: [wx, wy, wz], rad/s, the platform's (its centripetal and gyroscopic
    terms, quadratic in it), or a list of them, each required (exact at each listed velocity, not
    between them). ``velocity``: [vx, vy, vz], m/s, the reference point's, or a list of them, each
    required: it changes no wrench, only a drive's motors (``actuator``; refused without one).
    The platform's mass, centre of mass and inertia are ``robot.platform`` and ``load``'s."""

    acceleration: Any = MISSING
    angular_velocity: Any = MISSING
    velocity: Any = MISSING


@dataclass
class ModelConfig:
    """Readings of the ambiguous equations; each default is the best fit to all the published
    evidence (studies evidence_cpr8 and evidence_irpm), except ``cable_direction``, whose better
    fit describes another robot (docs/evidence.md sections 1-2 give every reading's numbers).
    ``pinv_columns``: eq. (20) with all six columns of J (full) or forces only (translational);
    ``velocity_boundary``: |v| = V_cmax in the set of eq. (26) or not;
    ``acceleration_set``: the box's corners or MATLAB's colon (eqs. 27-29); ``jdot``: the centripetal term of the shaft
    acceleration; ``xi_in_torque_limit``: xi in eq. (32); ``moment_arm`` and ``cable_direction``:
    the IRPM's eqs. (8)-(9) (moments about the platform or the base; cables towards their
    attachment points or the platform's centre). ``rank_rtol``: singular values below it (times
    the largest) count as zero (1e-12 to 0.1). ``margin_atol``: margins within it of zero are exactly 0 and
    satisfied (``pipeline.workspace.verdict``), so a pose on a limit gets the same verdict on every CPU."""

    pinv_columns: PinvColumns = MISSING
    velocity_boundary: VelocityBoundary = MISSING
    acceleration_set: AccelerationSet = MISSING
    moment_arm: MomentArm = MISSING
    cable_direction: CableDirection = MISSING
    jdot: bool = MISSING
    xi_in_torque_limit: bool = MISSING
    rank_rtol: float = rule(lambda v: None if 1e-12 <= v <= 0.1 else (
        "must be in [1e-12, 0.1]: below, rounding (about 1e-16) hides a singular matrix from the "
        "rank test; above, well-conditioned poses count as singular"))
    margin_atol: float = rule(lambda v: None if 0 <= v <= 1e-3 else "must be in [0, 1e-3]")


@dataclass
class ComputeConfig:
    """Parallel execution: joblib backend (``threading``: the chunks on worker threads of the
    job's process, whose compiled loops and numpy release the GIL; ``loky``: on worker processes,
    about 190 MiB each), workers (capped at the machine's cores, except on a
    Dask scheduler elsewhere), poses per chunk (null: by the cost model, 20 000 and on Dask at
    least 0.2 s of kernel; a number is taken as given; either is lowered so that a chunk's
    largest array stays under 4 MB). ``backend=dask`` runs the chunks on the Dask scheduler at
    ``scheduler`` (null: a local cluster of n_jobs workers, one for a sweep's jobs run one after
    another). ``max_poses``: the most pose x orientation evaluations a
    job may take (checked before any work; raise it knowingly). ``kernel``: auto (the compiled
    kernels where they apply and the numpy kernel would take over 0.4 s, about 80 000 poses, or
    the job's sweep together would), numpy, or fused (refused where they do not apply:
    tension=feasible, model.jdot=true, output.cables=true). The verdicts are the same either
    way; the summary's ``kernel`` says which ran (docs/performance.md)."""

    n_jobs: int = rule(lambda v: None if v != 0 else "must be a positive count or negative (joblib style)")
    backend: str = rule(lambda v: None if v in JOBLIB_BACKENDS else f"must be one of {', '.join(JOBLIB_BACKENDS)}")
    chunk_size: Optional[int] = rule(positive)
    scheduler: Optional[str] = MISSING
    max_poses: int = rule(at_least(1))
    kernel: Kernel = MISSING


@dataclass
class TrajectoryConfig:
    """``analysis=trajectory`` (``pipeline.app.paths``): the platform's path. ``points``: its
    way-points, [[x, y, z], ...] (m, at ``orientation.*``) or [[x, y, z, psi, theta, phi], ...]
    (rad, ``orientation.convention``; a robot on a joint: [[psi, theta, phi], ...]); or ``file``, a
    CASPR trajectories file (.xml; ``name``: its trajectory's id) or a CSV of timed way-points
    (.csv: t,x,y,z[,psi,theta,phi]). ``law``: quintic (rest to rest per segment) or spline
    (through every way-point, at rest at both ends), each segment in ``times`` (s: one value, or one
    per segment); trapezoid (the CPR-8 paper's profile per straight segment: ``v_max`` m/s, ``t_acc``
    and ``t_dec`` s). ``dt``: s between samples (null: 0.01, or a CASPR file's time_step)."""

    points: Any = MISSING
    times: Any = MISSING
    law: TimeLaw = MISSING
    v_max: Optional[float] = rule(positive)
    t_acc: Optional[float] = rule(positive)
    t_dec: Optional[float] = rule(positive)
    dt: Optional[float] = rule(positive)
    file: Optional[str] = MISSING
    name: Optional[str] = MISSING


@dataclass
class CertifiedConfig:
    """``analysis=certified`` (``pipeline.workspace.paving``): branch and prune from the robot's
    search box, at most ``depth`` levels of bisection and ``time`` seconds; with ``path`` (way-points
    [[x, y, z], ...], m) the straight segments between them instead, each piece proven feasible at
    every point or at none: at rest, or moving rest to rest along each segment, each piece with the
    accelerations it has, by ``law``: ``quintic`` with ``times`` (s per segment: one value, or one
    per segment), or ``trapezoid`` with ``v_max`` (m/s), ``t_acc`` and ``t_dec`` (s), the laws of
    ``analysis=trajectory`` (``pipeline.app.paths.certified_motion``). ``orientations``: ``listed``,
    each orientation of ``orientation.total``'s grid required (n angles per axis); ``box``, every
    orientation of its box (within ``bound`` of the nominal angles), cut into n boxes per axis
    (``pipeline.app.problem.orientation_cells``)."""

    depth: int = rule(lambda value: None if 0 <= value <= MAX_DEPTH else f"must be in [0, {MAX_DEPTH}]")
    time: float = rule(positive)
    path: Any = rule(lambda value: _path_error(value))
    times: Any = MISSING
    law: str = rule(lambda value: None if value in ("quintic", "trapezoid") else "must be quintic or trapezoid")
    v_max: Optional[float] = rule(positive)
    t_acc: Optional[float] = rule(positive)
    t_dec: Optional[float] = rule(positive)
    orientations: str = rule(lambda value: None if value in ("listed", "box") else "must be listed or box")


def _path_error(value) -> str | None:
    """Why ``certified.path`` is not at least two way-points of three finite coordinates, each
    apart from the one before it."""
    points = list(value) if isinstance(value, (list, ListConfig)) else None
    if points is None or len(points) < 2:
        return "at least two way-points [[x, y, z], [x, y, z], ...] (m)"
    for number, point in enumerate(points, 1):
        broken = vector(3, "x, y, z, m", MAX_REACH)(point) if isinstance(point, (list, ListConfig)) else "needs 3 values"
        if broken:
            return f"way-point {number}: {broken}"
    for number in range(1, len(points)):
        if list(points[number]) == list(points[number - 1]):
            return f"way-point {number + 1} repeats way-point {number}: a segment needs two ends"
    return None


MAX_DEPTH = 40  # levels of bisection: 2^40 boxes, past any memory


@dataclass
class RobustConfig:
    """``analysis=certified``: build tolerances, each the half-width of a box around the nominal
    value on every coordinate (m; kg for ``mass``): a box is inside when every pose in it is feasible
    for every robot within them (``pipeline.workspace.paving``); lengths at most 1e4 m."""

    anchors: float = rule(reach)
    attachments: float = rule(reach)
    mass: float = rule(non_negative)
    com: float = rule(reach)


@dataclass
class LinesConfig:
    """Straight-line simulations (analysis=lines, section 3.1.3 of the CPR-8 paper): samples =
    first writes the samples of line O''-F'' only (what Fig. 6 draws, 0.13 MB a job), all those
    of every line (5.4 MB a job). The verdicts of every line are in points.parquet either way."""

    samples: LineSamples = MISSING


@dataclass
class OutputConfig:
    """``cables``: add per-pose ``length_<cable>`` (m) and ``tension_<cable>`` (statics) or
    ``tension_min_/tension_max_<cable>`` over the acceleration set (CPR-WWA), N, to
    points.parquet: the forces the checked model uses (``pipeline.workspace.quantities``).
    ``points``: write the per-pose table points.parquet (false: the summary only, for sweeps
    whose figures read summaries; a study that draws clouds or compares poses refuses it).
    ``mesh``: write the boundary of the feasible set, boundary.stl and boundary.ply (m, fixed
    frame; ``pipeline.workspace.boundary``). ``metrics``: add per-pose ``tension_factor`` (Pham et al.'s),
    ``tension_ratio``, ``capacity_margin`` (Guay et al.'s) and ``wrench_max_<w>``,
    ``wrench_min_<w>`` (the largest external wrench along each freedom the pose holds on top of
    its load; ``pipeline.model.metrics``), ``analysis=statics``."""

    cables: bool = MISSING
    points: bool = MISSING
    mesh: bool = MISSING
    metrics: bool = MISSING


@dataclass
class WorkspaceConfig:
    """Connected reach (``pipeline.workspace.reach``): ``home``, a pose [x, y, z] (m; for a
    robot on a joint, its angles in rad) whose connected component of the feasible grid the job
    reports (summary ``connected_pct``, column ``connected``; null: not computed);
    ``neighbourhood``: grid nodes are neighbours when their cells share a face (6), also an edge
    (18) or also a corner (26)."""

    home: Optional[list[float]] = rule(vector(3, "x y z, m"))
    neighbourhood: int = rule(lambda value: None if value in (6, 18, 26) else "must be 6, 18 or 26")


@dataclass
class Config:
    """The job: ``analysis``, a config group (cpr_wwa: dynamics and actuator limits; statics:
    wrench and tensions; lines: the paper's straight lines; payload: the largest payload per
    pose; trajectory: the platform along a path; certified: boxes of poses proven feasible or not;
    ``robot=irpm6`` and ``points`` pick statics), ``actuator`` (the id of a catalogue row; a
    static pose's or a path's may be null: no drive), ``catalogue`` (a CSV or Parquet path; null =
    Table 1 of the CPR-8 paper, shipped in pipeline/data), ``poses`` (a list of [x, y, z]
    positions in m checked instead of the robot's grid, e.g. ``poses=[[0,0,5]]``; null = the
    grid; the summary's volume_m3 is then NaN),
    ``obstacles`` (the cell's obstacles no cable and not the platform may touch, criterion
    ``cable_obstacle``: a list of boxes ``{name: table, lo: [x, y, z], hi: [x, y, z]}`` and
    half-spaces ``{name: floor, point: [x, y, z], normal: [x, y, z]}``, the obstacle behind the
    plane, m, fixed frame), ``criteria`` (the keys of the criteria that declare their own,
    ``{name: {key: value}}``: ``pipeline.workspace.criteria``, each checked where they are given). A
    job has the keys of conf/config.yaml plus those of its tension, analysis and robot files,
    and only those (checked against this schema by ``pipeline.app.problem.typed_config``; the
    robot and analysis kinds are named there)."""

    robot: Any = MISSING
    analysis: str = MISSING
    actuator: Optional[int] = MISSING
    catalogue: Optional[str] = MISSING
    orientation: OrientationConfig = field(default_factory=OrientationConfig)
    grid: GridConfig = field(default_factory=GridConfig)
    motion: MotionConfig = field(default_factory=MotionConfig)
    load: LoadConfig = field(default_factory=LoadConfig)
    wrench: WrenchConfig = field(default_factory=WrenchConfig)
    tension: TensionConfig = field(default_factory=TensionConfig)
    drive: DriveConfig = field(default_factory=DriveConfig)
    choice: ChoiceConfig = field(default_factory=ChoiceConfig)
    model: ModelConfig = field(default_factory=ModelConfig)
    compute: ComputeConfig = field(default_factory=ComputeConfig)
    output: OutputConfig = field(default_factory=OutputConfig)
    workspace: WorkspaceConfig = field(default_factory=WorkspaceConfig)
    lines: LinesConfig = field(default_factory=LinesConfig)
    platform_motion: PlatformMotionConfig = field(default_factory=PlatformMotionConfig)
    trajectory: TrajectoryConfig = field(default_factory=TrajectoryConfig)
    certified: CertifiedConfig = field(default_factory=CertifiedConfig)
    robust: RobustConfig = field(default_factory=RobustConfig)
    poses: Any = MISSING
    obstacles: Any = MISSING
    criteria: Any = MISSING

    @staticmethod
    def check_fields(cfg: DictConfig) -> None:
        from pipeline.workspace.criteria import checked_settings

        if "criteria" in cfg:  # the keys each criterion declares beside it, by its rules
            checked_settings(OmegaConf.to_container(cfg.criteria) if isinstance(cfg.criteria, DictConfig) else cfg.criteria)


def register() -> None:
    """The resolver of sweep job folder names. The YAML files in conf/ are composed untyped; the
    schemas here type and check the result (:func:`pipeline.app.problem.typed_config`)."""
    OmegaConf.register_new_resolver("cdpr.jobdir", job_dir_name, replace=True)


def job_dir_name(override_dirname: str, job_num: int) -> str:
    """A sweep job's folder: its overrides (``actuator=3``), or ``job<N>`` when it has none."""
    return override_dirname.replace("/", "_") or f"job{job_num}"




def unknown_keys(node: DictConfig, schema, prefix: str = "") -> None:
    """ConfigError for the first key of ``node`` that ``schema`` (a dataclass) does not declare:
    a ``+key`` override adds keys past Hydra's struct check, and would otherwise be ignored."""
    declared = {f.name: f for f in fields(schema)}
    for key in node:
        if key not in declared:
            raise ConfigError(f"{prefix}{key}: not a key of {schema.__name__} "
                              f"(keys: {', '.join(declared)})")
        default = declared[key].default_factory() if callable(declared[key].default_factory) else None
        if is_dataclass(default) and isinstance(node[key], DictConfig):
            unknown_keys(node[key], type(default), f"{prefix}{key}.")


def merged(schema, node: DictConfig, prefix: str) -> DictConfig:
    """``node`` merged into ``schema``'s typed defaults; a value of the wrong type is a
    ConfigError naming the key and the value."""
    try:
        return OmegaConf.merge(_structured(schema), node)  # merge copies, never changes, its inputs
    except OmegaConfBaseException as exc:
        message = one_line(exc).split(": full_key")[0]
        raise ConfigError(f"{prefix}{exc.full_key}={exc.value}: {message}") from None


@functools.cache
def _structured(schema) -> DictConfig:
    """The typed defaults of a schema, built once per process."""
    return OmegaConf.structured(schema)


def masked(full: DictConfig, present: DictConfig, missing_ok: bool = False) -> DictConfig:
    """``full``'s typed values at the keys of ``present`` only (struct: no key can be added); a
    value that resolves to the wrong type (an interpolation) is a ConfigError as in :func:`merged`.
    A required value left unset (``???``) raises MissingMandatoryValue, or with ``missing_ok``
    stays unset (a base the overrides complete)."""
    try:
        typed = _masked(full, present, missing_ok)
    except MissingMandatoryValue:  # its callers say which value is missing
        raise
    except OmegaConfBaseException as exc:
        raise ConfigError(f"{exc.full_key}={exc.value}: {one_line(exc).split(': full_key')[0]}") from None
    OmegaConf.set_struct(typed, True)
    return typed


def _masked(full: DictConfig, present: DictConfig, missing_ok: bool) -> dict:
    kept = {}
    for key in present:
        if missing_ok and OmegaConf.is_missing(full, key):
            kept[key] = "???"
            continue
        value = full[key]
        if isinstance(present[key], DictConfig) and isinstance(value, DictConfig):
            value = _masked(value, present[key], missing_ok)
        kept[key] = value
    return OmegaConf.create(kept)


def check_values(node: DictConfig, schema, prefix: str = "") -> None:
    """Apply the rules ``schema`` declares (``rule`` fields, ``check_fields``) to the keys
    ``node`` has, nested schemas first: ConfigError '<key>=<value>: <rule>' on the first
    failure."""
    present = set(node.keys())  # `in node` raises and catches inside OmegaConf for an absent key
    for declared in fields(schema):
        if declared.name not in present:
            continue
        value = node[declared.name]
        default = declared.default_factory() if callable(declared.default_factory) else None
        if is_dataclass(default) and isinstance(value, DictConfig):
            check_values(value, type(default), f"{prefix}{declared.name}.")
        elif value is not None and "check" in declared.metadata:
            broken = declared.metadata["check"](value)
            if broken:
                raise ConfigError(f"{prefix}{declared.name}={shown(value)}: {broken}")
    if hasattr(schema, "check_fields"):
        schema.check_fields(node)


def check_declared(obj, where: str, label: str = "") -> None:
    """The rules a file's dataclass instance (a study, its figures, its optimise and search
    blocks) declares: each ``rule`` field's check, nested dataclasses and lists of them first,
    then its ``check_across(where)`` (the rules that join fields). ConfigError
    '<where>: <label><key>[=<value>]: <rule>' on the first failure; an item of a list names
    itself by its ``label`` (a figure: its file)."""
    for declared in fields(obj):
        value = getattr(obj, declared.name)
        for item in value if isinstance(value, list) else [value]:
            if is_dataclass(item):
                named = getattr(item, "label", "")
                check_declared(item, where, f"{label}{declared.name}: " + (f"{named}: " if named else ""))
        broken = value is not None and "check" in declared.metadata and declared.metadata["check"](value)
        if broken:
            given = f"={value!r}" if isinstance(value, (str, int, float)) else ""
            raise ConfigError(f"{where}: {label}{declared.name}{given}: {broken}")
    if hasattr(obj, "check_across"):
        obj.check_across(where)


def shown(value):
    return OmegaConf.to_container(value) if isinstance(value, ListConfig) else value


