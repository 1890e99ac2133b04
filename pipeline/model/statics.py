"""Static equilibrium under an applied wrench: eqs. (7)-(10) of Hamed & Zohoor (IRPM paper).

The structure matrix A (6, m) has one column per cable, [u_i; a_i x u_i], where u_i is the unit
vector of l_i = r + R d_i - c_i (eq. 1, from the base point to the platform point) and a_i the
moment arm (eq. 8). Tensions s solve A s = f_ext (eq. 7); for the square 6-cable case this is
s = A^-1 f_ext (eq. 10), for other cable counts the minimum-norm least-squares solution.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import ClassVar
from functools import cached_property

import numpy as np

from pipeline.model.actuators import ActuatorModel, voltage_interval
from pipeline.model.dynamics import Load, inertial_wrenches, load_wrench_terms
from pipeline.model.linalg import batched_pinv, gram, gram_ratio
from pipeline.model.geometry import CableRobot, PoseGeometry, structure_matrix
from pipeline.model.path import Samples, angular_motion
from pipeline.model.tensions import TensionSpec, payload_ranges, ray_interval


@dataclass(frozen=True)
class StaticsSpec:
    """The load whose weight (and centre-of-mass moment) and external wrench the cables balance
    (``load.external`` plus the applied wrench f_ext of eq. (11), ``wrench.*``), and model options.

    ``moment_arm``: ``"platform"`` takes a_i = R d_i, moments about the platform's reference
    point O_M, where section IV applies the wrench; ``"base"`` takes eq. (9) literally,
    a_i = r + R d_i, moments about the base centre O_F (docs/evidence.md compares them).
    ``cable_direction``: ``"attachment"`` takes each cable from its anchor to its attachment
    point (eq. 1); ``"centre"`` from its anchor to the platform's reference point (directions and
    lengths of a point platform, moment arms kept): with no applied moment the moment rows of
    A s = f_ext are then r_end times rows that do not depend on r_end, so the tensions and the
    volume do not either (the IRPM paper's conclusions 1, 4 and 5; docs/evidence.md section 2).
    ``rank_rtol``: a pose is singular when the gram ratio of A (``PoseStatics.gram_ratio``)
    falls below it. ``wrench_set`` (K, 6): wrenches each added to the load's and every one
    required (``wrench.set``'s vertices, each once; none: the load's wrench alone), and
    ``vertex_numbers`` each one's number in the set as given (1 = its first). ``tension``:
    minimum-norm tensions (``pinv``, eq. 10) or pulling cables only (``feasible``,
    ``pipeline.model.tensions``; for six cables the same verdict). ``accelerations`` (A, 6),
    ``angular_velocities`` (O, 3) and ``velocities`` (V, 3): the platform's motion
    (``platform_motion``), every acceleration at every angular velocity and every velocity of the
    reference point required with every wrench (a velocity changes no wrench: it moves a drive's
    motors). ``winch_radius`` (m,): R of
    each cable's winch where a catalogue actuator drives the cables (``actuator``; None: no drive).
    """

    moment_arm: str = "platform"
    cable_direction: str = "attachment"
    rank_rtol: float = 1e-9
    tension: TensionSpec = field(default_factory=TensionSpec)
    load: Load = field(default_factory=Load)
    wrench_set: np.ndarray = field(default_factory=lambda: np.zeros((0, 6)))
    vertex_numbers: tuple[int, ...] = ()
    accelerations: np.ndarray = field(default_factory=lambda: np.zeros((0, 6)))
    angular_velocities: np.ndarray = field(default_factory=lambda: np.zeros((1, 3)))
    velocities: np.ndarray = field(default_factory=lambda: np.zeros((1, 3)))
    winch_radius: np.ndarray | None = None
    kind: ClassVar[str] = "statics"  # which compiled kernel evaluates it (pipeline.workspace.fused)
    summarised: ClassVar[tuple[str, ...]] = ()  # per-pose columns the summary gives min, median, max of

    def state(self, robot: CableRobot, positions: np.ndarray, orientation) -> "PoseStatics":
        return PoseStatics(robot, positions, orientation, self)

    @property
    def moves(self) -> bool:
        """Whether the platform moves (``platform_motion``): its momentum's rate joins every wrench."""
        return bool(len(self.accelerations)) or bool(np.any(self.angular_velocities)) or bool(np.any(self.velocities))

    def set_size(self) -> int:
        """Largest per-pose, per-cable set a criterion holds in memory: the wrench set's vertices
        times the accelerations' times the angular velocities' times the velocities'."""
        return (max(1, len(self.wrench_set)) * max(1, len(self.accelerations)) * len(self.angular_velocities)
                * len(self.velocities))

    def work(self) -> float:
        """A pose's work against the statics of one wrench (the cost model's reference,
        ``pipeline.workspace.compute``): each vertex of a wrench set adds about a sixth
        (benchmarks/LOG.md, 2026-11-26: 4 vertices x1.8, 64 vertices x12.8, both tension models)."""
        return 1.0 + self.set_size() / 6 if self.set_size() > 1 else 1.0

    def fused_unfit(self) -> str | None:
        """Why the compiled statics kernel cannot evaluate this spec, None when it can."""
        if len(self.wrench_set) or self.moves:
            return "it balances one wrench (no wrench.set, no platform_motion)"
        if self.winch_radius is not None:
            return "it checks the cables' own limits, not a drive's (actuator=null)"
        return None if self.tension.model == "pinv" else "it evaluates tension.model=pinv only"


@dataclass(frozen=True)
class StaticLimits:
    """Eq. (10) of the IRPM paper: tensions in [t_min, t_max] (N; the paper's s_max is
    ``tension.t_max``, inf = no rating, a scalar or one per cable); a pose is singular when the gram ratio of the
    structure matrix is below ``rank_rtol``. ``scale`` (N) is the unit of the slack margin:
    the largest rating, or without one the magnitude of the force the cables balance (at least
    1 N). Cable lengths are limited by the robot's own ``l_max``. ``n_wrenches``: the wrenches of
    a required wrench set (0: none)."""

    t_max: float | np.ndarray
    rank_rtol: float
    scale: float
    n_wrenches: int = 0

    def described(self) -> dict:
        """What a job's summary says of its limits besides the config: the number of wrenches
        a wrench set requires (``n_wrenches``), when there is one."""
        return {"n_wrenches": self.n_wrenches} if self.n_wrenches else {}


@dataclass(frozen=True)
class DrivenLimits(StaticLimits):
    """The statics' limits (at the poses of a grid or the samples of a path) and, with ``drive``
    (the catalogue actuator of every cable, ``pipeline.model.actuators.ActuatorModel``), the
    actuator's: its constants and limits (``G_v``, ``speed_limit``, ...) read through these
    limits, so that one limits object serves the statics' criteria and the actuator's."""

    drive: ActuatorModel | None = None

    def __getattr__(self, name: str):
        drive = self.__dict__.get("drive")
        if drive is None or name.startswith("__"):
            raise AttributeError(name)
        return getattr(drive, name)

    def described(self) -> dict:
        """The statics' description, and the actuator's name and power with a drive."""
        return {**super().described(), **(self.drive.described() if self.drive is not None else {})}


class PoseStatics(PoseGeometry):
    """Lazily evaluated structure matrix, conditioning and cable tensions of a chunk of poses."""

    kind = "statics"  # what a criterion reading it declares (``Criterion.reads``)

    def __init__(self, robot: CableRobot, positions: np.ndarray, orientation, spec: StaticsSpec):
        super().__init__(robot, positions, orientation)
        self.spec = spec

    @property
    def tension(self) -> TensionSpec:
        return self.spec.tension

    @property
    def load(self) -> Load:
        return self.spec.load

    @property
    def ranges_over_a_set(self) -> bool:
        """Whether the cables balance a wrench set (``wrench.set``, or the platform's motion), else
        one wrench."""
        return len(self.spec.wrench_set) > 0 or self.spec.moves

    @property
    def force_range(self) -> tuple[np.ndarray, np.ndarray]:
        """(n, m) the tensions of eq. (10), the largest and the smallest over the required
        wrenches (one wrench: the same)."""
        if not self.ranges_over_a_set:
            return self.tensions, self.tensions
        over_set = self.tensions_over_set
        return over_set.max(axis=1), over_set.min(axis=1)

    def forces_of(self, tensions: np.ndarray) -> np.ndarray:
        """The ``feasible`` model's variables are the tensions s themselves (N), both ways."""
        return tensions

    variables_of = forces_of

    @cached_property
    def vectors(self) -> np.ndarray:
        """(n, m, 3) cable vectors from each anchor to its attachment point (eq. 1) or, with
        ``cable_direction="centre"``, to the platform's reference point."""
        if self.spec.cable_direction == "centre":
            return self.positions[:, None, :] - self.exits
        return super().vectors

    @cached_property
    def structure_matrix(self) -> np.ndarray:
        """(n, k, m) A of eq. (8): columns [u_i; a_i x u_i], a_i = R d_i (``platform``) or
        r + R d_i (``base``), its rows those of the robot's k freedoms (all six for a free
        body: ``CableRobot.dofs``)."""
        arms = self.arms if self.spec.moment_arm == "platform" else self.arms + self.positions[:, None, :]
        return structure_matrix(self.unit, arms)[:, list(self.robot.dofs), :]

    @cached_property
    def wrench(self) -> np.ndarray:
        """(k,) the wrench the cables balance along the robot's freedoms: the load's weight, its
        moment about the reference point and the load's external wrench (which holds f_ext of
        eq. 11); a joint or a plane takes the other rows. (n, k) for a rotation per pose: the
        weight's moment turns with the platform."""
        return load_wrench_terms(self.spec.load, self.robot.up, self.rotation)[1][..., list(self.robot.dofs)]

    @property
    def structure(self) -> np.ndarray:
        """A of eq. (8), the S of ``pipeline.model.tensions``: A s = f_ext."""
        return self.structure_matrix

    @property
    def rows(self) -> tuple[int, ...]:
        """The freedoms (indices into ``FREEDOMS``) of the rows of :attr:`structure`."""
        return self.robot.dofs

    @cached_property
    def wrench_pinv(self) -> tuple[np.ndarray, np.ndarray]:
        """A^+ (n, m, k) and the rank of A (n,)."""
        return batched_pinv(self.structure_matrix, self.spec.rank_rtol)

    @cached_property
    def required_wrenches(self) -> np.ndarray:
        """(K, k) the wrenches the cables must balance: :attr:`wrench`, plus each wrench of the
        set (``wrench.set``) when there is one, each with the momentum's rate of each acceleration
        of the platform's motion at each of its angular velocities, for each of its velocities
        (``platform_motion``; K = their product, the wrenches outermost, then the velocities, the
        angular velocities and the accelerations); (n, K, k) for a rotation per pose."""
        rows = list(self.robot.dofs)
        wrenches = self.wrench[..., None, :]
        if len(self.spec.wrench_set):
            wrenches = wrenches + self.spec.wrench_set[:, rows]
        if not self.spec.moves:
            return wrenches
        accelerations = self.spec.accelerations if len(self.spec.accelerations) else np.zeros((1, 6))
        turning = np.concatenate([inertial_wrenches(self.spec.load, self.rotation, accelerations, omega)
                                  for omega in self.spec.angular_velocities], axis=-2)[..., rows]
        moving = np.concatenate([turning] * len(self.spec.velocities), axis=-2)  # no term in the linear velocity
        combined = wrenches[..., :, None, :] + moving[..., None, :, :]  # every wrench with every acceleration
        return combined.reshape(*combined.shape[:-3], -1, combined.shape[-1])

    @cached_property
    def gram_ratio(self) -> np.ndarray:
        """(n,) det(A A^T) / prod(diag(A A^T)) in [0, 1] (Hadamard's inequality): 1 when the k
        rows of A are orthogonal, 0 when A loses rank. Cheaper than an SVD per pose."""
        return gram_ratio(self._gram)

    @cached_property
    def singular(self) -> np.ndarray:
        """(n,) poses whose structure matrix is numerically rank-deficient (gram ratio < rtol)."""
        return self.gram_ratio < self.spec.rank_rtol

    @cached_property
    def tensions(self) -> np.ndarray:
        """(n, m) minimum-norm tensions with A s = f_ext (eq. 7), N: s = A^T (A A^T)^-1 f, which
        is A^-1 f for six cables (eq. 10). Singular poses get the least-squares s = A^+ f from an
        SVD, so every value is finite."""
        return self._minimum_norm(self.wrench[..., None, :])[:, 0]

    @cached_property
    def tensions_over_set(self) -> np.ndarray:
        """(n, K, m) the minimum-norm tensions of each required wrench (``wrench.set``)."""
        return self._minimum_norm(self.required_wrenches)

    def _minimum_norm(self, wrenches: np.ndarray) -> np.ndarray:
        """(n, K, m) s = A^T (A A^T)^-1 w for each of the wrenches (K, k), or each pose's own
        (n, K, k); A^+ w where singular."""
        a = self.structure_matrix
        every = np.broadcast_to(wrenches, (a.shape[0], *wrenches.shape[-2:]))
        out = np.empty((a.shape[0], wrenches.shape[-2], a.shape[2]))
        ok = ~self.singular
        if ok.any():
            y = np.linalg.solve(self._gram[ok], np.swapaxes(every[ok], 1, 2))  # (n, k, K)
            out[ok] = np.einsum("nkm,nkj->njm", a[ok], y)
        if (~ok).any():
            pinv, _ = batched_pinv(a[~ok], self.spec.rank_rtol)
            out[~ok] = np.einsum("nmk,njk->njm", pinv, every[~ok])
        return out

    @cached_property
    def _gram(self) -> np.ndarray:
        return gram(self.structure_matrix)

    # A drive (``StaticsSpec.winch_radius``; the actuator criteria of eqs. 30-34): each winch turns
    # by theta = l / R (eq. 18: theta > 0 pays the cable out), so its speed and acceleration are
    # the cable's over R, and it holds the load torque M = R t; at each required wrench's own motion.

    @property
    def kinds(self) -> tuple[str, ...]:
        return ("statics", "dynamics") if self.spec.winch_radius is not None else ("statics",)

    @cached_property
    def motion_rates(self) -> tuple[np.ndarray, np.ndarray]:
        """(n, K, m) each cable's speed and acceleration (``PoseGeometry.cable_rates``) in the motion
        of each required wrench (:attr:`required_wrenches`, the same order): the platform's
        reference point at each velocity, turning at each angular velocity and accelerating at each
        acceleration of ``platform_motion`` ((n, 1, m) zeros at rest)."""
        n, m = len(self.positions), self.robot.n_cables
        if not self.spec.moves:
            return np.zeros((n, 1, m)), np.zeros((n, 1, m))
        accelerations = self.spec.accelerations if len(self.spec.accelerations) else np.zeros((1, 6))
        rates = [self.cable_rates(np.broadcast_to(v, (n, 3)), np.broadcast_to(omega, (n, 3)),
                                  np.broadcast_to(a[:3], (n, 3)), np.broadcast_to(a[3:], (n, 3)))
                 for v in self.spec.velocities for omega in self.spec.angular_velocities for a in accelerations]
        repeats = (1, max(1, len(self.spec.wrench_set)), 1)  # every wrench with every motion, wrenches outer
        return (np.tile(np.stack([r[0] for r in rates], axis=1), repeats),
                np.tile(np.stack([r[1] for r in rates], axis=1), repeats))

    @cached_property
    def shaft_speed_range(self) -> tuple[np.ndarray, np.ndarray]:
        """(n, m) theta_dot = l_dot / R, the largest and the smallest over the required motions."""
        speed = self.motion_rates[0] / self.spec.winch_radius
        return speed.max(axis=1), speed.min(axis=1)

    @cached_property
    def shaft_acceleration(self) -> np.ndarray:
        """(n, K, m) theta_ddot = l_ddot / R in each required motion (with the cables' turn: exact)."""
        return self.motion_rates[1] / self.spec.winch_radius

    @property
    def shaft_acceleration_worst(self) -> np.ndarray:
        return np.abs(self.shaft_acceleration).max(axis=1)

    @cached_property
    def torque_range(self) -> tuple[np.ndarray, np.ndarray]:
        """(n, m) M = R t of the tensions (the largest and smallest over the required wrenches)."""
        high, low = self.force_range
        return self.spec.winch_radius * high, self.spec.winch_radius * low

    def voltage_of(self, act, torques: np.ndarray) -> np.ndarray:
        """(n, K, m) u = G_v theta_ddot + L_v theta_dot - S_v M of eq. (21) in each required motion,
        at load torques M (n, K, m)."""
        speed = self.motion_rates[0] / self.spec.winch_radius
        return act.G_v * self.shaft_acceleration + act.L_v * speed + act.load_gain * torques

    def voltage_worst(self, act) -> np.ndarray:
        """(n, m) the largest |u| over the required wrenches, each with its own motion's speed and
        acceleration and its own tensions."""
        tensions = self.tensions_over_set if self.ranges_over_a_set else self.tensions[:, None, :]
        return np.abs(self.voltage_of(act, self.spec.winch_radius * tensions)).max(axis=1)

    def torque_bounds(self, act) -> tuple:
        """|R t| <= M_mot N_M (eq. 32) on the ``feasible`` model's variables, the tensions t."""
        limit = act.torque_limit / self.spec.winch_radius
        return -limit, limit, limit

    def voltage_bounds(self, act) -> tuple:
        """The interval on t that keeps |u| <= U (eq. 34) in each required motion:
        :func:`pipeline.model.actuators.voltage_interval` on M = R t, over R; (n, K, m)."""
        other = self.voltage_of(act, 0.0)
        lower, upper, scale = voltage_interval(act, other, other)
        radius = self.spec.winch_radius
        return lower / radius, upper / radius, scale / radius[0]


class PathStatics(PoseStatics):
    """The statics of a path's samples (``analysis=trajectory``): each pose with its own rotation
    (n, 3, 3), velocity [v; omega] (n, 6) and acceleration [a; alpha] (n, 6) (m/s, rad/s, m/s^2,
    rad/s^2; the reference point's and the turn's, fixed axes). The wrench its cables balance is
    the static one (:attr:`PoseStatics.wrench`) minus the rate of change of the platform's
    momentum at the sample's own motion (:func:`pipeline.model.dynamics.inertial_wrenches`); with
    ``wrench.set`` each of its wrenches is added to that. At rest it is the static wrench exactly
    (plus zeros), so every verdict is the statics'."""

    def __init__(self, robot: CableRobot, positions: np.ndarray, rotations: np.ndarray, spec: StaticsSpec,
                 velocities: np.ndarray, accelerations: np.ndarray):
        super().__init__(robot, positions, rotations, spec)
        self.velocities, self.accelerations = velocities, accelerations

    @cached_property
    def full_wrench(self) -> np.ndarray:
        """(n, 6) [f; M] the cables balance at each sample (moments about the reference point)."""
        static = load_wrench_terms(self.spec.load, self.robot.up, self.rotation)[1]
        moving = inertial_wrenches(self.spec.load, self.rotation, self.accelerations[:, None, :], self.velocities[:, 3:])
        return static + moving[:, 0, :]

    @cached_property
    def wrench(self) -> np.ndarray:
        """(n, k) :attr:`full_wrench` along the robot's freedoms."""
        return self.full_wrench[:, list(self.robot.dofs)]

    @cached_property
    def rates(self) -> tuple[np.ndarray, np.ndarray]:
        """(n, m) each cable's speed and acceleration (``PoseGeometry.cable_rates``)."""
        return self.cable_rates(self.velocities[:, :3], self.velocities[:, 3:], self.accelerations[:, :3],
                                self.accelerations[:, 3:])

    @cached_property
    def motion_rates(self) -> tuple[np.ndarray, np.ndarray]:
        """(n, 1, m) each cable's speed and acceleration at its sample (:attr:`rates`)."""
        speed, acceleration = self.rates
        return speed[:, None, :], acceleration[:, None, :]


@dataclass(frozen=True)
class PathSpec(StaticsSpec):
    """``analysis=trajectory``: the statics of a path's ``samples`` (``pipeline.model.path.Samples``),
    their angles in ``convention`` (``orientation.convention``)."""

    samples: Samples | None = None
    convention: str = "zyx"
    kind: ClassVar[str] = "trajectory"

    def fused_unfit(self) -> str | None:
        return "it evaluates a grid; a path's samples are checked by the numpy criteria"

    def state_of(self, robot: CableRobot, rows: slice) -> PathStatics:
        """The :class:`PathStatics` of the samples ``rows``."""
        s = self.samples
        rotation, omega, alpha = angular_motion(s.q[rows, 3:], s.q_dot[rows, 3:], s.q_ddot[rows, 3:], self.convention)
        velocities = np.concatenate([s.q_dot[rows, :3], omega], axis=1)
        accelerations = np.concatenate([s.q_ddot[rows, :3], alpha], axis=1)
        return PathStatics(robot, s.q[rows, :3], rotation, self, velocities, accelerations)


PAYLOAD_LP_WORK = 2.7  # measured: 14 976 poses of an 8-cable robot, 2.15 s against 0.81 s for its statics


@dataclass(frozen=True)
class PayloadSpec(StaticsSpec):
    """``analysis=payload``: the statics of the platform (``load``: its own mass and centre of
    mass, the external and applied wrench) and, per pose, the largest payload at ``payload_com``
    (m, platform frame) the tensions can hold on top of it (:class:`PosePayload`); ``payload`` is
    the payload required (kg, ``load.mass``), the criterion ``payload`` its margin."""

    payload: float = 0.0
    payload_com: np.ndarray = field(default_factory=lambda: np.zeros(3))
    kind: ClassVar[str] = "payload"
    summarised: ClassVar[tuple[str, ...]] = ("max_payload_kg",)

    def state(self, robot: CableRobot, positions: np.ndarray, orientation) -> "PosePayload":
        return PosePayload(robot, positions, orientation, self)

    def fused_unfit(self) -> str | None:
        return "it does not compute payloads (analysis=payload)"

    def work(self) -> float:
        """The payload's LP per pose (pulling cables) costs about 2.7 statics poses; the closed
        form of the minimum-norm model about one (benchmarks/LOG.md, 2026-11-26)."""
        return PAYLOAD_LP_WORK if self.tension.model == "feasible" else 1.0


class PosePayload(PoseStatics):
    """The statics of a chunk with, per pose, the payloads it holds (kg): the weight is linear in
    the mass, w + mu d with d the load wrench of 1 kg at the payload's centre of mass, and the
    tensions' box convex, so the payloads held form one interval [least, largest], exact: LPs
    per pose (pulling cables, ``tensions.payload_ranges``) or, for the minimum-norm tensions
    t0 + mu A^+ d (eq. 10), the bounds each cable puts on mu. The least is above 0 where the
    platform alone cannot keep its cables at t_min: they need a payload's weight."""

    @cached_property
    def per_kg(self) -> np.ndarray:
        """(k,) the load wrench of 1 kg of payload at ``payload_com``, along the freedoms; (n, k)
        for a rotation per pose."""
        unit = Load(1.0, self.spec.load.gravity, np.asarray(self.spec.payload_com, float), np.zeros(6))
        return load_wrench_terms(unit, self.robot.up, self.rotation)[1][..., list(self.robot.dofs)]

    @cached_property
    def payload_range(self) -> np.ndarray:
        """(n, 2) the least and the largest payload (kg) each pose holds within [t_min, t_max];
        the largest inf when the cables never carry it; both NaN when no payload is held (or,
        under the minimum-norm model, the pose is singular) and where a cable has collapsed (no
        direction: the ``zero_length`` gate)."""
        t_min, t_max = self.tension.t_min, self.tension.t_max
        collapsed = self.lengths.min(axis=1) < self.robot.shortest_cable
        if self.tension.model != "pinv":
            payloads = payload_ranges(self.structure_matrix, self.wrench, self.per_kg, t_min, t_max)
            return np.where(collapsed[:, None], np.nan, payloads)
        upper = np.inf if t_max is None else t_max
        start = self.tensions
        pinv = self.wrench_pinv[0]
        slope = (np.einsum("nmk,k->nm", pinv, self.per_kg) if self.per_kg.ndim == 1
                 else np.einsum("nmk,nk->nm", pinv, self.per_kg))
        least, largest = ray_interval(start, slope, t_min, upper)
        held = (least <= largest) & ~self.singular & ~collapsed
        return np.where(held[:, None], np.column_stack([least, largest]), np.nan)

    @property
    def max_payload(self) -> np.ndarray:
        """(n,) the largest payload (kg) each pose holds (:attr:`payload_range`)."""
        return self.payload_range[:, 1]

    def diagnostics(self) -> dict[str, np.ndarray]:
        return {**super().diagnostics(), "max_payload_kg": self.max_payload,
                "min_payload_kg": self.payload_range[:, 0]}

