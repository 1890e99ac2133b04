"""Per-chunk kinematic and dynamic quantities of CPR-WWA, computed once and only when asked for.

A :class:`PoseDynamics` holds one chunk of n positions at one constant orientation. Each property
is an array over (pose, cable[, velocity | acceleration]) built with numpy batched operations: no
Python loop over poses. Criteria (``pipeline.workspace.criteria``) read the properties they need. The
geometric part and the interface every chunk state offers (:class:`pipeline.model.geometry.PoseGeometry`)
are shared with the statics of ``pipeline.model.statics``.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, field
from typing import ClassVar
from functools import cached_property

import numpy as np

from pipeline.model.linalg import batched_pinv
from pipeline.model.tensions import TensionSpec
from pipeline.model.actuators import ActuatorModel, voltage_interval
from pipeline.model.geometry import CableRobot, PoseGeometry, euler_rate_axes, length_jacobian, rotation_matrix


@dataclass(frozen=True)
class Load:
    """What the cables carry besides inertia: a load of ``mass`` (kg) under gravity of magnitude
    ``gravity`` (m/s^2, along -up of the robot) with its centre of mass at ``com`` (m, platform
    frame), and a constant ``external`` wrench [f; M] (N, N m; fixed axes, moments about the
    platform's reference point); ``inertia`` (3, 3), kg m^2, the body's about its centre of mass,
    platform frame (None: not given)."""

    mass: float = 0.0
    gravity: float = 9.81
    com: np.ndarray = field(default_factory=lambda: np.zeros(3))
    external: np.ndarray = field(default_factory=lambda: np.zeros(6))
    inertia: np.ndarray | None = None


def inertia_tensor(xx: float, yy: float, zz: float, xy: float = 0.0, xz: float = 0.0, yz: float = 0.0) -> np.ndarray:
    """(3, 3) [[Ixx, Ixy, Ixz], [Ixy, Iyy, Iyz], [Ixz, Iyz, Izz]], kg m^2: the moments and
    products of inertia as CASPR's bodies files and ``robot.platform.inertia`` give them."""
    return np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]], dtype=float)


TRIANGLE_RTOL = 0.01  # of the largest moment: a thin plate's printed moments, rounded, may break I_z <= I_x + I_y by that


def inertia_fault(matrix: np.ndarray) -> str | None:
    """Why ``matrix`` (3, 3, kg m^2) cannot be a rigid body's inertia about its centre of mass, None
    when it can: finite, its principal moments I_1 <= I_2 <= I_3 >= 0 (to 1e-12 of the largest
    entry) and I_3 <= I_1 + I_2 (in principal axes I_1 + I_2 - I_3 = 2 sum m z^2 >= 0; to
    TRIANGLE_RTOL of I_3), except a planar platform's Izz alone (every other entry 0), whose
    turn about z is all that is read."""
    if not np.isfinite(matrix).all():
        return "must be finite"
    moments = np.linalg.eigvalsh(matrix)
    if not moments[0] >= -1e-12 * max(1.0, float(np.abs(matrix).max())):
        return f"has a negative principal moment ({moments[0]:.6g} kg m^2)"
    planar = not np.any(matrix.ravel()[:8])
    if not planar and moments[2] > (moments[0] + moments[1]) + TRIANGLE_RTOL * moments[2]:
        return (f"has principal moments {', '.join(f'{m:.6g}' for m in moments)} kg m^2, the largest more than the sum "
                "of the other two: no rigid body has them (a planar platform: Izz alone)")
    return None


REFERENCE_SET = 12  # the velocities evaluated per pose at the paper's N = 6: the 12 extremes of eq. (23)'s 93
# A pose's work grows by this share of the paper's for each velocity evaluated beyond REFERENCE_SET
# (benchmarks/LOG.md, 2026-11-26: 936 extremes at grid.n_vel=60 cost 3.9x the paper's pose under the
# minimum-norm model, numpy, and 4.5x fused; 1.7x under the feasible model, whose LPs dominate).
WORK_PER_VELOCITY = {"pinv": 0.0032, "feasible": 0.0007}


@dataclass(frozen=True)
class MotionSpec:
    """What the carrier must do at every pose: velocity set, acceleration set, load, model options.

    ``pinv_columns``: ``"full"`` uses all six columns of eq. (19), so the moments balance too
    (the default: the best fit to all the published evidence, docs/evidence.md section 1);
    ``"translational"`` solves eq. (20) with the three position columns of J (orientation held
    constant, no moment balance; the best fit to Table 2 alone).
    ``rank_rtol``: singular values below ``rank_rtol * sigma_max`` are treated as zero in the
    pseudo-inverse (the CPR-8 Jacobian has rank 5 at zero orientation).
    ``jdot``: add the centripetal term (J-dot p-dot) of the shaft acceleration.
    ``velocity_extremes``: the velocities among which every linear function of the velocity
    takes its extremes (``motion.extreme_points``); null = the whole set.
    ``tension``: which torques the torque and voltage criteria check (``pipeline.model.tensions``);
    the wrench rows follow ``pinv_columns`` (forces only, or forces and moments).
    ``load``: mass, gravity, centre of mass and external wrench of F in eq. (31) (:class:`Load`;
    the paper: 2 kg at the reference point, no external wrench).
    """

    velocities: np.ndarray
    accelerations: np.ndarray
    load: Load
    winch_radius: np.ndarray
    pinv_columns: str = "full"
    rank_rtol: float = 1e-9
    jdot: bool = False
    velocity_extremes: np.ndarray | None = None
    tension: TensionSpec = field(default_factory=TensionSpec)
    kind: ClassVar[str] = "cpr_wwa"  # which compiled kernel evaluates it (pipeline.workspace.fused)
    summarised: ClassVar[tuple[str, ...]] = ()  # per-pose columns the summary gives min, median, max of

    def state(self, robot: CableRobot, positions: np.ndarray, orientation) -> "PoseDynamics":
        return PoseDynamics(robot, positions, orientation, self)

    def set_size(self) -> int:
        """Largest per-pose, per-cable set a criterion holds in memory: the velocities it
        evaluates (their extremes, unless J-dot, which is not linear in v, needs every one) or
        the accelerations."""
        held = self.velocities if self.jdot or self.velocity_extremes is None else self.velocity_extremes
        return max(len(held), len(self.accelerations))

    def work(self) -> float:
        """A pose's work against the cost model's reference, the paper's pose (``grid.n_vel=6``):
        it grows with the velocities evaluated (WORK_PER_VELOCITY)."""
        return 1.0 + WORK_PER_VELOCITY[self.tension.model] * max(0, self.set_size() - REFERENCE_SET)

    def fused_unfit(self) -> str | None:
        """Why the compiled CPR-WWA kernel (``pipeline.workspace.fused``) cannot evaluate this
        spec, None when it can: the minimum-norm model without J-dot (the extreme velocities, a
        product acceleration set, both readings of eqs. 27-29)."""
        if self.tension.model != "pinv":
            return "it evaluates tension.model=pinv only"
        return "it evaluates model.jdot=false only" if self.jdot else None


class PoseDynamics(PoseGeometry):
    """Lazily evaluated CPR-WWA quantities (eqs. 18-22) for a chunk of poses."""

    ranges_over_a_set = True  # the forces range over the acceleration set
    kind = "dynamics"  # what a criterion reading it declares (``Criterion.reads``)

    def __init__(self, robot: CableRobot, positions: np.ndarray, orientation, motion: MotionSpec):
        super().__init__(robot, positions, orientation)
        self.motion = motion

    @property
    def tension(self) -> TensionSpec:
        return self.motion.tension

    @property
    def load(self) -> Load:
        return self.motion.load

    @cached_property
    def force_range(self) -> tuple[np.ndarray, np.ndarray]:
        """(n, m) largest and smallest cable tension t = M / R over the acceleration set, M the
        minimum-norm load torques of eq. (20)."""
        high, low = self.acceleration_range(*self.torque_affine)
        return self.forces_of(high), self.forces_of(low)

    def forces_of(self, torques: np.ndarray) -> np.ndarray:
        """Cable tensions t = M / R_i of load torques M (the ``feasible`` model's variables)."""
        return torques / self.motion.winch_radius

    def variables_of(self, tensions):
        """The ``feasible`` model's variables M = R_i t of cable tensions t (eq. 20)."""
        return self.motion.winch_radius * tensions

    def voltage_bounds(self, act: ActuatorModel) -> tuple:
        """The interval on M = R t per required acceleration a_k that keeps the voltage within
        its limit for every velocity of the set, |G_v J a_k + L_v theta_dot - S_v M| <= U
        (eqs. 21, 34; :func:`pipeline.model.actuators.voltage_interval`)."""
        high, low = self.voltage_from_velocity(act)  # (n, m)
        accelerations = np.broadcast_to(self.wrench_accelerations, (len(high), *self.wrench_accelerations.shape[-2:]))
        accel = act.G_v * np.einsum("nmj,nkj->nkm", self.jacobian[:, :, :3], accelerations)
        return voltage_interval(act, accel + high[:, None, :], accel + low[:, None, :])

    def voltage_from_velocity(self, act: ActuatorModel) -> tuple[np.ndarray, np.ndarray]:
        """(max, min) (n, m) of the velocity part of eq. (21), L_v theta_dot (+ G_v J-dot p-dot)."""
        if self.motion.jdot:
            values = act.L_v * self.shaft_speed + act.G_v * self.shaft_accel_from_velocity
            return values.max(axis=-1), values.min(axis=-1)
        high, low = self.shaft_speed_range
        return act.L_v * high, act.L_v * low

    @cached_property
    def torque_range(self) -> tuple[np.ndarray, np.ndarray]:
        """(n, m) largest and smallest load torque M of eq. (20) over the acceleration set."""
        return self.acceleration_range(*self.torque_affine)

    def torque_bounds(self, act: ActuatorModel) -> tuple:
        """|M| <= M_mot N_M (eq. 32) on the ``feasible`` model's variables, M themselves."""
        return -act.torque_limit, act.torque_limit, act.torque_limit

    @cached_property
    def shaft_acceleration_worst(self) -> np.ndarray:
        """(n, m) the largest |theta_ddot| of eq. (33) over every (velocity, acceleration) pair:
        J p_ddot (+ J-dot p_dot with ``motion.jdot``), the two parts separable."""
        velocity = self.shaft_accel_from_velocity
        from_velocity = (velocity.max(axis=-1), velocity.min(axis=-1)) if self.motion.jdot else (0.0, 0.0)
        return max_abs_sum_of_ranges(from_velocity, self.acceleration_range(self.jacobian[:, :, :3], 0.0))

    def voltage_worst(self, act: ActuatorModel) -> np.ndarray:
        """(n, m) the largest |u| of eq. (21) over every (velocity, acceleration) pair: the
        velocity part L_v theta_dot (+ G_v J-dot p_dot) and the acceleration part
        G_v J a - S_v M (affine in a) are separable; without J-dot the velocity part's range is
        L_v times theta_dot's, known from eq. (30)."""
        torque_coefficients, torque_offset = self.torque_affine
        from_acceleration = self.acceleration_range(  # G_v J a - S_v M, affine in a
            act.G_v * self.jacobian[:, :, :3] + act.load_gain * torque_coefficients, act.load_gain * torque_offset
        )
        return max_abs_sum_of_ranges(self.voltage_from_velocity(act), from_acceleration)

    def diagnostics(self) -> dict[str, np.ndarray]:
        """The rank of J^T per pose, and the base's columns."""
        return {"jacobian_rank": self.jacobian_rank.astype(np.int8), **super().diagnostics()}

    @cached_property
    def jacobian(self) -> np.ndarray:
        """(n, m, 6) shaft Jacobian J of eq. (19): theta_dot = J p_dot, rows divided by R_i (18);
        J^T = blockdiag(I, E^T) A diag(1 / R_i) with A the structure matrix."""
        dl_dp = length_jacobian(self.structure_matrix, euler_rate_axes(*self.orientation))
        return dl_dp / self.motion.winch_radius[None, :, None]

    @cached_property
    def shaft_speed(self) -> np.ndarray:
        """(n, m, k_v) theta_dot for every velocity of the set, Euler rates zero (eq. 19); one
        BLAS product over the whole chunk."""
        n, m, _ = self.jacobian.shape
        flat = np.ascontiguousarray(self.jacobian[:, :, :3]).reshape(n * m, 3)
        return (flat @ self.motion.velocities.T).reshape(n, m, -1)

    @cached_property
    def shaft_speed_range(self) -> tuple[np.ndarray, np.ndarray]:
        """(n, m) largest and smallest theta_dot over the velocity set. theta_dot is linear in
        the velocity, so only ``motion.velocity_extremes`` need to be evaluated."""
        extremes = self.motion.velocity_extremes
        if extremes is None:
            return self.shaft_speed.max(axis=2), self.shaft_speed.min(axis=2)
        speed = np.einsum("nmj,vj->nmv", self.jacobian[:, :, :3], extremes)
        return speed.max(axis=2), speed.min(axis=2)

    @cached_property
    def _acceleration_box(self) -> tuple[np.ndarray, np.ndarray] | None:
        return acceleration_box(self.motion.accelerations)

    def acceleration_range(self, coefficients: np.ndarray, offset) -> tuple[np.ndarray, np.ndarray]:
        """(n, m) largest and smallest value of ``coefficients . a + offset`` over the
        acceleration set. On a product set (a box's grid) a linear function ranges over
        c . centre +- |c| . half-width, with no enumeration; otherwise every a is evaluated."""
        box = self._acceleration_box
        if box is None:
            values = np.einsum("nmj,aj->nma", coefficients, self.motion.accelerations)
            values = values + np.asarray(offset)[..., None]
            return values.max(axis=2), values.min(axis=2)
        centre, half = box
        middle = coefficients @ centre + offset
        spread = np.abs(coefficients) @ half
        return middle + spread, middle - spread

    @cached_property
    def torque_affine(self) -> tuple[np.ndarray, np.ndarray]:
        """M = (J^T)^+ F is affine in the acceleration (eqs. 20, 31: F = L a + F_0, the inertial
        force -m a acting at the centre of mass, the weight and the external wrench in F_0):
        M = C a + d with C (n, m, 3) and d (n, m) = M at rest."""
        pinv = self.wrench_pinv[0]
        rows = pinv.shape[2]
        slope, at_rest = generalized_load_terms(self.motion.load, self.robot.up, self.orientation)
        return pinv @ slope[:rows], pinv @ at_rest[:rows]

    @cached_property
    def shaft_accel_from_velocity(self) -> np.ndarray:
        """(n, m, k_v) J-dot p_dot = (|v|^2 - (u.v)^2) / (l R) at constant orientation; zeros
        unless ``motion.jdot``."""
        v = self.motion.velocities
        if not self.motion.jdot:
            return np.zeros(self.shaft_speed.shape)
        along = np.einsum("nmj,vj->nmv", self.unit, v)
        speed2 = np.einsum("vj,vj->v", v, v)[None, None, :]
        return centripetal(speed2, along, self.lengths[..., None], self.motion.winch_radius[None, :, None])

    @property
    def rows(self) -> tuple[int, ...]:
        """The freedoms (indices into ``FREEDOMS``) of the rows of :attr:`structure`."""
        return tuple(range(3 if self.motion.pinv_columns == "translational" else 6))

    @cached_property
    def structure(self) -> np.ndarray:
        """(n, c, m) J^T of eq. (20), c = 3 (``translational``) or 6 (``full``) rows."""
        columns = 3 if self.motion.pinv_columns == "translational" else 6
        return np.transpose(self.jacobian[:, :, :columns], (0, 2, 1))

    @cached_property
    def wrench_pinv(self) -> tuple[np.ndarray, np.ndarray]:
        """(J^T)^+ (n, m, c) and the rank of J^T (n,)."""
        return batched_pinv(self.structure, self.motion.rank_rtol)

    @cached_property
    def wrench_accelerations(self) -> np.ndarray:
        """(K, 3) accelerations whose wrenches decide the ``feasible`` model: the 8 vertices of
        the box on a product set (the wrench-feasible set is convex), else the whole set."""
        box = self._acceleration_box
        if box is None:
            return self.motion.accelerations
        centre, half = box
        return centre + half * np.array(list(itertools.product((-1.0, 1.0), repeat=3)))

    @cached_property
    def required_wrenches(self) -> np.ndarray:
        """(K, c) F of eq. (31) at ``wrench_accelerations``, the rows of ``structure``."""
        wrenches = load_wrenches(self.motion, self.wrench_accelerations, self.robot.up, self.orientation)
        return wrenches[:, : self.structure.shape[1]]

    @cached_property
    def jacobian_rank(self) -> np.ndarray:
        """(n,) numerical rank of the J^T used in eq. (20)."""
        return self.wrench_pinv[1]



class SampleDynamics(PoseDynamics):
    """The CPR-WWA quantities of a trajectory's samples: each pose with its own velocity and
    acceleration (n, 3), a set of one, so every criterion of the registry reads a sample as it
    reads a grid pose over its sets (section 3.1.3's straight lines, ``pipeline.workspace.lines``)."""

    def __init__(self, robot: CableRobot, positions: np.ndarray, orientation, motion: MotionSpec,
                 velocities: np.ndarray, accelerations: np.ndarray):
        super().__init__(robot, positions, orientation, motion)
        self.velocities, self.accelerations = np.asarray(velocities, float), np.asarray(accelerations, float)

    @cached_property
    def shaft_speed(self) -> np.ndarray:
        """(n, m, 1) theta_dot = J p_dot of each sample's own velocity (eq. 19)."""
        return np.einsum("nmj,nj->nm", self.jacobian[:, :, :3], self.velocities)[..., None]

    @cached_property
    def shaft_speed_range(self) -> tuple[np.ndarray, np.ndarray]:
        return self.shaft_speed[..., 0], self.shaft_speed[..., 0]

    def acceleration_range(self, coefficients: np.ndarray, offset) -> tuple[np.ndarray, np.ndarray]:
        """``coefficients . a + offset`` at each sample's own acceleration (its largest and smallest)."""
        values = np.einsum("nmj,nj->nm", coefficients, self.accelerations) + offset
        return values, values

    @cached_property
    def shaft_accel_from_velocity(self) -> np.ndarray:
        """(n, m, 1) J-dot p_dot of each sample's velocity; zeros unless ``motion.jdot``."""
        if not self.motion.jdot:
            return np.zeros(self.shaft_speed.shape)
        along = np.einsum("nmj,nj->nm", self.unit, self.velocities)
        speed2 = np.einsum("nj,nj->n", self.velocities, self.velocities)[:, None]
        return centripetal(speed2, along, self.lengths, self.motion.winch_radius)[..., None]

    @cached_property
    def wrench_accelerations(self) -> np.ndarray:
        """(n, 1, 3) each sample's acceleration."""
        return self.accelerations[:, None, :]

    @cached_property
    def required_wrenches(self) -> np.ndarray:
        """(n, 1, c) F of eq. (31) at each sample's acceleration."""
        wrenches = load_wrenches(self.motion, self.accelerations, self.robot.up, self.orientation)
        return wrenches[:, None, : self.structure.shape[1]]


def load_wrench_terms(load: Load, up: np.ndarray, rotation: np.ndarray):
    """The wrench w the cables balance (A t = w) as L a + F_0: L (6, 3) and F_0 (6,) (L (n, 6, 3)
    and F_0 (n, 6) for a rotation per pose, ``rotation`` (n, 3, 3)).

    Newton's law for the load (mass m, centre of mass R com from the platform's reference point),
    pulled by the cables with -A t (each tension along -u_i): m a = -A t + m g (-up) + external,
    so A t = m g (-up) - m a + external: the weight and d'Alembert's inertial force -m a, both at
    the centre of mass, plus ``load.external``. This is eq. (31) read consistently: with z up its
    g is the signed gravity component (-9.81), F = [m xdd, m ydd, m (zdd + 9.81)] is the force
    the cables exert, -A t, and eq. (20)'s M = (J^T)^+ F is then the motor torque -R t that the
    printed eq. (21) adds as +S_v M (docs/model.md section 2 derives the chain). With a = 0 it
    is the wrench of eq. (7) of the IRPM paper that the weight adds to f_ext."""
    arm = rotation @ np.asarray(load.com, dtype=float)  # (3,), or (n, 3) for one rotation per pose
    zero = np.zeros(arm.shape[:-1])
    cross = np.stack([np.stack([zero, -arm[..., 2], arm[..., 1]], axis=-1),
                      np.stack([arm[..., 2], zero, -arm[..., 0]], axis=-1),
                      np.stack([-arm[..., 1], arm[..., 0], zero], axis=-1)], axis=-2)
    slope = -load.mass * np.concatenate([np.broadcast_to(np.eye(3), cross.shape), cross], axis=-2)
    weight = -load.mass * load.gravity * np.asarray(up, dtype=float)
    return slope, np.concatenate([np.broadcast_to(weight, arm.shape), cross @ weight], axis=-1) + load.external


def inertial_wrenches(load: Load, rotation: np.ndarray, accelerations: np.ndarray, omega: np.ndarray) -> np.ndarray:
    """(A, 6), or (n, A, 6) for a rotation per pose (n, 3, 3): what moving the platform adds to
    the wrench its cables balance (A t = w, :func:`load_wrench_terms`), minus the rate of change
    of its momentum (Newton-Euler about the reference point O, fixed axes, moments about O):

        -[m a_c;  m c x a_c + I alpha + omega x (I omega)],   a_c = a + alpha x c + omega x (omega x c),

    for each acceleration [a; alpha] (A, 6), or each pose's own (n, A, 6), of O (m/s^2) and of
    the platform's turn (rad/s^2), at the angular velocity ``omega`` (3,), or each pose's (n, 3),
    rad/s; c = R com and I = R I_c R^T, I_c the inertia about the centre of mass
    (``load.inertia``; None: a point mass). Affine in [a; alpha]: the vertices of a box of
    accelerations decide the whole box (the set of wrenches the cables balance is convex);
    quadratic in omega."""
    arm = rotation @ np.asarray(load.com, dtype=float)  # (3,) or (n, 3)
    inertia = np.zeros((3, 3)) if load.inertia is None else load.inertia
    turned = rotation @ inertia @ np.swapaxes(rotation, -1, -2)  # (3, 3) or (n, 3, 3)
    linear, angular = accelerations[..., :3], accelerations[..., 3:]
    arm_ = arm[..., None, :]
    centre = linear + np.cross(angular, arm_) + np.cross(omega, np.cross(omega, arm))[..., None, :]
    momentum = np.einsum("...ij,...j->...i", turned, omega)  # I omega
    spin = np.einsum("...ij,...aj->...ai", turned, angular) + np.cross(omega, momentum)[..., None, :]
    force = -load.mass * centre
    return np.concatenate([force, np.cross(arm_, force) - spin], axis=-1)


def generalized_load_terms(load: Load, up: np.ndarray, orientation) -> tuple[np.ndarray, np.ndarray]:
    """:func:`load_wrench_terms` in the coordinates of eq. (19), p = [x y z psi theta phi]: the
    generalized force [f; E^T tau] that J^T M must equal in eq. (20). By virtual work a moment tau
    does tau . omega = tau . E q_dot, so its component along Euler angle q is tau . e_q (E of
    ``geometry.euler_rate_axes``); J^T M = [f; E^T tau] is A t = [f; tau] wherever E is invertible.
    L (6, 3) and F_0 (6,) at one orientation (psi, theta, phi)."""
    slope, at_rest = load_wrench_terms(load, up, rotation_matrix(*orientation))
    blocks = np.eye(6)
    blocks[3:, 3:] = euler_rate_axes(*orientation).T
    return blocks @ slope, blocks @ at_rest


def load_wrenches(motion: MotionSpec, accelerations: np.ndarray, up: np.ndarray, orientation) -> np.ndarray:
    """(k, 6) the generalized force F of eqs. (20), (31) for accelerations (k, 3):
    :func:`generalized_load_terms` evaluated."""
    slope, at_rest = generalized_load_terms(motion.load, up, orientation)
    return accelerations @ slope.T + at_rest


def acceleration_box(accelerations: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """Centre and half-width per axis when the acceleration set (k, 3) is the full product of
    its per-axis values (both readings of eqs. 27-29 are); None otherwise."""
    axes = [np.unique(accelerations[:, j]) for j in range(3)]
    if len(np.unique(accelerations, axis=0)) != np.prod([len(a) for a in axes]):
        return None
    lo, hi = np.array([a[0] for a in axes]), np.array([a[-1] for a in axes])
    return (lo + hi) / 2, (hi - lo) / 2


def max_abs_sum_of_ranges(a: tuple, b: tuple) -> np.ndarray:
    """max over (j, k) of |a_j + b_k| from the (max, min) of each term over its own set, without
    forming the j x k product: max(max_j a_j + max_k b_k, -(min_j a_j + min_k b_k)), because
    |x| = max(x, -x) and a maximum of a sum of independent terms is the sum of maxima."""
    return np.maximum(a[0] + b[0], -(a[1] + b[1]))


def centripetal(speed2, along, length, radius):
    """J-dot p-dot of one cable at constant orientation: (|v|^2 - (u.v)^2) / (l R) (rad/s^2),
    the rate of change of the cable direction times the velocity, behind the winch."""
    return (speed2 - along**2) / (length * radius)
