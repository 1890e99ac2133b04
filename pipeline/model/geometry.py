"""Generic cable-robot kinematics: anchors, attachment points, Euler angles, lengths, Jacobian.

A robot is data: frame anchor points ``a_i`` and platform attachment points ``b_i`` (body frame).
The cable vector of cable ``i`` at pose ``p = [x y z psi theta phi]`` is

    c_i = T + R(psi, theta, phi) b_i - a_i,     l_i = |c_i|

which is eqs. (1)-(17) of Filipovic & Kevac (2018) for the CPR-8 and eqs. (1)-(3) of Hamed & Zohoor
for the IRPM. ``R`` is eq. (9) of the CPR-8 paper (identical to eq. (2) of the IRPM paper):
R = Rz(phi) Ry(theta) Rx(psi).

One structure matrix serves every analysis (:func:`structure_matrix`): A (6, m) with columns
[u_i; (R b_i) x u_i], u_i = c_i / l_i, moments about the platform's reference point. A tension
t_i >= 0 pulls the platform along -u_i, so the cables balance a wrench w (everything else that
acts on the platform, in the fixed frame's axes) when A t = w: eq. (7) of the IRPM paper. The
CPR-8's shaft Jacobian of eq. (19) is the same matrix seen through Euler rates and winches,
J^T = blockdiag(I, E^T) A diag(1 / R_i), E the angular velocity per Euler rate
(:func:`euler_rate_axes`), because u_i . (dR/dq b_i) = e_q . ((R b_i) x u_i).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from pipeline.model.clearance import Obstacle, Polytope
from pipeline.model.pulleys import Pulleys, pulley_exits
from pipeline.model.stiffness import unstrained_lengths


@dataclass(frozen=True)
class CableRobot:
    """A cable robot as plain arrays; every kernel works from this and nothing else.

    anchors: (m, 3) frame points where cables leave the frame (hanging points), fixed frame, m.
    attachments: (m, 3) platform points in the body frame, m.
    box_lo, box_hi: (3,) corners of the region searched for the workspace, m.
    cable_names: m labels used in results and plots.
    up: (3,) unit vector of the fixed frame pointing up; gravity acts along -up (CPR-8: +z,
    IRPM: -Z, its Z axis points down from the base).
    l_max: the longest cable, m (None: no length limit); checked in every analysis.
    dofs: the platform's freedoms, indices into (x, y, z, rx, ry, rz) in that order: the rows of
    the structure matrix the cables balance (:data:`FREEDOMS`; a joint or a plane holds the others:
    a point platform in space (0, 1, 2), a planar point (0, 1), a planar body (0, 1, 5)).
    cable_radii: (m,) each cable's radius, m (None: cables are lines, no cable-cable check).
    platform_shape: the platform's body (``pipeline.model.clearance.Polytope``, platform frame)
    that no cable may enter, every attachment on its surface (None: not checked).
    obstacles: the cell's obstacles (``pipeline.model.clearance.Obstacle``) that no cable and not
    the platform may touch.
    pulleys: a swivelling pulley per cable at its anchor (``pipeline.model.pulleys.Pulleys``; None:
    each cable leaves its anchor itself).
    cable_ea: (m,) each cable's axial stiffness EA, N (None: rigid cables, no stiffness criterion);
    cable_mass: (m,) each cable's mass per length, kg/m (None: weightless cables, no sag criterion);
    winch_lengths: (m,) the cable between each anchor and its winch, in series, m.
    catenary: the sag each cable may take, a share of its chord, when its cables sag (Irvine's
    catenary, ``pipeline.model.sagging``; None: straight cables).
    """

    name: str
    anchors: np.ndarray
    attachments: np.ndarray
    box_lo: np.ndarray
    box_hi: np.ndarray
    cable_names: tuple[str, ...]
    up: np.ndarray = field(default_factory=lambda: np.array([0.0, 0.0, 1.0]))
    l_max: float | None = None
    dofs: tuple[int, ...] = (0, 1, 2, 3, 4, 5)
    cable_radii: np.ndarray | None = None
    platform_shape: Polytope | None = None
    obstacles: tuple[Obstacle, ...] = ()
    pulleys: Pulleys | None = None
    cable_ea: np.ndarray | None = None
    cable_mass: np.ndarray | None = None
    winch_lengths: np.ndarray | None = None
    catenary: float | None = None

    @property
    def n_cables(self) -> int:
        return self.anchors.shape[0]

    @property
    def fixed_point(self) -> bool:
        """Whether a joint holds the platform's reference point at the frame's origin (no freedom
        along x, y, z: a spherical, universal or revolute joint), so that its workspace is a set of
        orientations rather than positions."""
        return all(freedom >= 3 for freedom in self.dofs)

    @property
    def shortest_cable(self) -> float:
        """A cable shorter than this (m) has collapsed: its attachment point sits on its anchor
        and eq. (1) gives it no direction. ``ZERO_LENGTH_RTOL`` times the robot's extent (at
        least 1 m): far below any grid step, far above the round-off of a grid's positions."""
        return ZERO_LENGTH_RTOL * self.extent

    @property
    def extent(self) -> float:
        """The robot's size (m, at least 1): its farthest anchor or attachment coordinate."""
        return max(1.0, float(np.abs(self.anchors).max(initial=0.0)), float(np.abs(self.attachments).max(initial=0.0)))

    @cached_property
    def platform_body(self) -> Polytope:
        """The platform as the obstacles see it: its declared shape, else the convex hull of its
        attachment points (a plate, a segment or a point when they span no volume)."""
        return self.platform_shape or Polytope.hull(self.attachments, self.shortest_cable)

    @cached_property
    def attachment_faces(self) -> np.ndarray:
        """(m, f) whether attachment i lies on face f of :attr:`platform_shape` (within
        :attr:`shortest_cable`)."""
        shape = self.platform_shape
        return np.abs(self.attachments @ shape.normals.T - shape.offsets) <= self.shortest_cable

    @cached_property
    def cable_pairs(self) -> tuple[np.ndarray, np.ndarray]:
        """(i, j) index arrays, i < j, of the pairs of cables that may touch along their length:
        every pair but those sharing an anchor or an attachment point (within
        :attr:`shortest_cable`), which meet there by design (a point platform: every pair)."""
        i, j = np.triu_indices(self.n_cables, k=1)
        apart = ((np.linalg.norm(self.anchors[i] - self.anchors[j], axis=1) > self.shortest_cable)
                 & (np.linalg.norm(self.attachments[i] - self.attachments[j], axis=1) > self.shortest_cable))
        return i[apart], j[apart]


FREEDOMS = ("x", "y", "z", "rx", "ry", "rz")  # the rows of the structure matrix, in order
ZERO_LENGTH_RTOL = 1e-9  # a collapsed cable, relative to the robot's extent (CableRobot.shortest_cable)


def rotation_matrix(psi: float, theta: float, phi: float) -> np.ndarray:
    """Eq. (9): R = Rz(phi) Ry(theta) Rx(psi), angles in rad."""
    return _rz(phi) @ _ry(theta) @ _rx(psi)


def eq9_angles(a: float, b: float, c: float) -> tuple[float, float, float]:
    """The angles (psi, theta, phi) of eq. (9) of the rotation R = Rx(a) Ry(b) Rz(c) (XYZ Euler
    angles, CASPR's ``SPATIAL_EULER_XYZ``): the same rotation, so every model of this project
    applies (at theta = +-pi/2 the split between psi and phi is one of many, the rotation is not)."""
    r = _rx(a) @ _ry(b) @ _rz(c)
    theta = float(np.arcsin(np.clip(-r[2, 0], -1.0, 1.0)))
    if abs(r[2, 0]) < 1.0 - 1e-12:
        return float(np.arctan2(r[2, 1], r[2, 2])), theta, float(np.arctan2(r[1, 0], r[0, 0]))
    return float(np.arctan2(-r[1, 2], r[1, 1])), theta, 0.0  # gimbal lock: phi = 0


def rotation_partials(psi: float, theta: float, phi: float) -> np.ndarray:
    """(3, 3, 3) array: dR/dpsi, dR/dtheta, dR/dphi of eq. (9)."""
    rx, ry, rz = _rx(psi), _ry(theta), _rz(phi)
    return np.stack([rz @ ry @ _drx(psi), rz @ _dry(theta) @ rx, _drz(phi) @ ry @ rx])


def rotation_matrices(angles: np.ndarray, convention: str = "zyx") -> np.ndarray:
    """(n, 3, 3) one rotation per row of ``angles`` (n, 3) = (psi, theta, phi), rad: eq. (9)'s
    Rz(phi) Ry(theta) Rx(psi) (``zyx``), or CASPR's Rx(psi) Ry(theta) Rz(phi) (``xyz``)."""
    rx, ry, rz = elementary_rotations(angles)
    return rz @ ry @ rx if convention == "zyx" else rx @ ry @ rz


def elementary_rotations(angles: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(Rx(angles[:, 0]), Ry(angles[:, 1]), Rz(angles[:, 2])), each (n, 3, 3), for ``angles`` (n, 3), rad."""
    angles = np.asarray(angles, dtype=float)
    c, s = np.cos(angles), np.sin(angles)
    zero, one = np.zeros(len(angles)), np.ones(len(angles))
    rx = np.stack([one, zero, zero, zero, c[:, 0], -s[:, 0], zero, s[:, 0], c[:, 0]], axis=1).reshape(-1, 3, 3)
    ry = np.stack([c[:, 1], zero, s[:, 1], zero, one, zero, -s[:, 1], zero, c[:, 1]], axis=1).reshape(-1, 3, 3)
    rz = np.stack([c[:, 2], -s[:, 2], zero, s[:, 2], c[:, 2], zero, zero, zero, one], axis=1).reshape(-1, 3, 3)
    return rx, ry, rz


def attached_points(robot: CableRobot, rotation: np.ndarray) -> np.ndarray:
    """R b_i: (m, 3) for one rotation (3, 3), (n, m, 3) for one per pose (n, 3, 3)."""
    return robot.attachments @ np.swapaxes(rotation, -1, -2)


def cable_vectors(robot: CableRobot, positions: np.ndarray, rotation: np.ndarray) -> np.ndarray:
    """(n, m, 3) vectors from each anchor to its attachment point, for n positions (n, 3) at one
    rotation (3, 3) or one per pose (n, 3, 3)."""
    attached = attached_points(robot, rotation)
    return positions[:, None, :] + attached - robot.anchors[None, :, :]


def structure_matrix(unit: np.ndarray, arms: np.ndarray) -> np.ndarray:
    """(n, 6, m) A with columns [u_i; arm_i x u_i] from unit cable vectors (n, m, 3) and moment
    arms (n, m, 3): A t is the wrench the tensions t balance (eq. 8 of the IRPM paper)."""
    return np.transpose(np.concatenate([unit, np.cross(arms, unit)], axis=2), (0, 2, 1))


def euler_rate_axes(psi: float, theta: float, phi: float) -> np.ndarray:
    """(3, 3) E whose column q is the angular velocity of the platform per unit rate of Euler
    angle q of eq. (9): dR/dq = [e_q]x R, so e_q is the axial vector of dR/dq R^T."""
    skew = rotation_partials(psi, theta, phi) @ rotation_matrix(psi, theta, phi).T
    return np.stack([skew[:, 2, 1], skew[:, 0, 2], skew[:, 1, 0]], axis=0)


def length_jacobian(structure: np.ndarray, rate_axes: np.ndarray) -> np.ndarray:
    """(n, m, 6) dl_i/dp for p = [x y z psi theta phi] (eq. 19 without the 1/R_i of eq. 18),
    from the structure matrix (n, 6, m): translation columns u_i, Euler-angle columns
    ((R b_i) x u_i) . e_q. Columns 4-6 are derivatives with respect to the Euler angles
    themselves (the paper's p-dot holds Euler-angle rates, not the angular velocity)."""
    forces, moments = structure[:, :3, :], structure[:, 3:, :]
    angular = np.einsum("njm,jq->nmq", moments, rate_axes)
    return np.concatenate([np.transpose(forces, (0, 2, 1)), angular], axis=2)


def _rx(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def _ry(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def _rz(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _drx(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[0.0, 0.0, 0.0], [0.0, -s, -c], [0.0, c, -s]])


def _dry(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[-s, 0.0, c], [0.0, 0.0, 0.0], [-c, 0.0, -s]])


def _drz(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[-s, -c, 0.0], [c, -s, 0.0], [0.0, 0.0, 0.0]])


class PoseGeometry:
    """Cable vectors, lengths and directions for positions (n, 3) at one orientation: the base of
    the per-chunk states (``PoseDynamics`` for CPR-WWA, ``PoseStatics`` for the statics), which
    offer the criteria one interface, so that no criterion asks which state it was given:

    - ``tension``: the :class:`pipeline.model.tensions.TensionSpec` the forces are checked by;
    - ``load``: the :class:`pipeline.model.dynamics.Load` the cables carry (its gravity too);
    - ``force_range``: (high, low) (n, m), each cable's tension (N) under the minimum-norm model,
      the largest and smallest over the state's wrench set (one wrench for the statics);
    - ``forces_of(x)`` and ``variables_of(t)``: the tensions (N) of the variables x of the
      ``feasible`` model, and back (the criteria's ``bounds`` are intervals on x);
    - ``kind``: ``dynamics`` or ``statics``, what a criterion that reads it declares (``kinds``:
      every such kind it offers);
    - ``ranges_over_a_set``: whether the forces range over a set (per-cable min and max columns)
      or are one value per cable;
    - ``structure`` and ``rows``: the matrix S the forces balance the wrench with, and the freedoms
      of its rows;
    - ``diagnostics()``: per-pose columns beside the margins (the Jacobian's rank, the poses the
      ``feasible`` model's LPs solved, ``tension_lp``, and the closest cables, ``closest_pair``,
      set by the criteria that computed them).
    """

    tension_lp: np.ndarray | None = None
    closest_pair: np.ndarray | None = None
    closest_obstacle: np.ndarray | None = None
    stiffness_translational: np.ndarray | None = None
    stiffness_rotational: np.ndarray | None = None
    frequency: np.ndarray | None = None
    stiffness_weakest: np.ndarray | None = None

    def __init__(self, robot: CableRobot, positions: np.ndarray, orientation):
        self.robot = robot
        self.positions = np.asarray(positions, dtype=float)
        given = np.asarray(orientation, dtype=float)
        self.orientation = given if given.ndim == 3 else tuple(float(a) for a in orientation)

    @cached_property
    def rotation(self) -> np.ndarray:
        """(3, 3) R of eq. (9) at the chunk's one orientation (eq. 9's angles), or (n, 3, 3) one
        rotation per pose when the state was given them (an orientation grid: a spherical robot)."""
        return self.orientation if isinstance(self.orientation, np.ndarray) else rotation_matrix(*self.orientation)

    @cached_property
    def vectors(self) -> np.ndarray:
        """(n, m, 3) cable vectors anchor -> attachment point (eqs. 1-17), or from the point where
        it leaves its pulley (``exits``)."""
        if self.robot.pulleys is None:
            return cable_vectors(self.robot, self.positions, self.rotation)
        return self.attachment_points - self.exits

    @cached_property
    def _pulleys(self) -> tuple[np.ndarray, np.ndarray]:
        return pulley_exits(self.robot.anchors, self.robot.pulleys, self.attachment_points)

    @cached_property
    def exits(self) -> np.ndarray:
        """(n, m, 3) where each straight cable begins: its anchor, or where it leaves its pulley
        (``pipeline.model.pulleys``)."""
        if self.robot.pulleys is None:
            return np.broadcast_to(self.robot.anchors, (len(self.positions), self.robot.n_cables, 3))
        return self._pulleys[0]

    @cached_property
    def lengths(self) -> np.ndarray:
        """(n, m) lengths of the straight cables k, h, m, n, k', h', m', n' (eqs. 10-17): from the
        anchor, or from the pulley (the free length)."""
        return np.linalg.norm(self.vectors, axis=2)

    @cached_property
    def wrap_angles(self) -> np.ndarray:
        """(n, m) the angle each cable wraps around its pulley, rad (0 without one)."""
        if self.robot.pulleys is None:
            return np.zeros(self.lengths.shape)
        radii = self.robot.pulleys.radii
        return np.divide(self._pulleys[1], radii, out=np.zeros(self.lengths.shape), where=radii > 0)

    @cached_property
    def cable_lengths(self) -> np.ndarray:
        """(n, m) each cable's length from its anchor: the straight part, and the arc it wraps
        around its pulley (``lengths`` without pulleys)."""
        return self.lengths if self.robot.pulleys is None else self.lengths + self._pulleys[1]

    @cached_property
    def unit(self) -> np.ndarray:
        """(n, m, 3) unit cable directions; zero where a cable has zero length."""
        lengths = self.lengths[..., None]
        return np.divide(self.vectors, lengths, out=np.zeros_like(self.vectors), where=lengths > 0)

    @cached_property
    def arms(self) -> np.ndarray:
        """(n, m, 3) R b_i: attachment points from the platform's reference point, fixed axes."""
        return np.broadcast_to(attached_points(self.robot, self.rotation), (len(self.positions), self.robot.n_cables, 3))

    @cached_property
    def attachment_points(self) -> np.ndarray:
        """(n, m, 3) p + R b_i: where each cable meets the platform, fixed frame (whatever cable
        direction a model reads: the cable itself runs from its anchor to this point)."""
        return self.positions[:, None, :] + self.arms

    @cached_property
    def structure_matrix(self) -> np.ndarray:
        """(n, 6, m) A = [u_i; (R b_i) x u_i] (``geometry.structure_matrix``): A t balances the
        wrench on the platform, moments about its reference point."""
        return structure_matrix(self.unit, self.arms)

    def cable_rates(self, velocity: np.ndarray, omega: np.ndarray, acceleration: np.ndarray,
                    alpha: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(n, m) each cable's speed and acceleration, m/s and m/s^2 (paid out > 0), of the
        platform moving at ``velocity``, ``omega``, ``acceleration`` and ``alpha`` (n, 3 each:
        its reference point's, m/s and m/s^2, and its turn's, rad/s and rad/s^2, fixed axes).

        The cable's platform end B = exit + vector (the attachment point, or the reference point
        under ``cable_direction=centre``) moves at v_B = v + omega x r and accelerates at
        a_B = a + alpha x r + omega x (omega x r), r = B - p. Its length from the anchor changes
        at l' = u . v_B (with a pulley too: the arc's change cancels the exit point's motion),
        and u' = (I - u u^T)(v_B - v_C) / l_f, l_f the free length, so
        l'' = u . a_B + (|v_B|^2 - (u . v_B)^2 - (v_B . n)^2 c / rho) / l_f:
        C, the exit point, slides along u and turns with the pulley about its axis at
        (v_B . n) / rho, n the normal of the pulley's plane, rho the distance of B from the
        axis, c = r_p (1 - cos beta) the distance of C from the axis (0 without pulleys)."""
        ends = self.exits + self.vectors
        arm = ends - self.positions[:, None, :]
        spin = omega[:, None, :]
        v_end = velocity[:, None, :] + np.cross(spin, arm)
        a_end = acceleration[:, None, :] + np.cross(alpha[:, None, :], arm) + np.cross(spin, np.cross(spin, arm))
        along = np.einsum("nmk,nmk->nm", self.unit, v_end)
        across = np.einsum("nmk,nmk->nm", v_end, v_end) - along**2
        pulleys = self.robot.pulleys
        if pulleys is not None:
            offset = ends - self.robot.anchors
            radial = offset - np.einsum("nmk,mk->nm", offset, pulleys.axes)[..., None] * pulleys.axes
            rho = np.linalg.norm(radial, axis=2)
            normal = np.cross(pulleys.axes, radial)  # |a x radial| = rho
            sideways = np.divide(np.einsum("nmk,nmk->nm", v_end, normal), rho, out=np.zeros_like(rho), where=rho > 0)
            wrapped = np.einsum("nmk,nmk->nm", self.exits - self.robot.anchors, radial)  # c rho
            across = across - sideways**2 * np.divide(wrapped, rho**2, out=np.zeros_like(rho), where=rho > 0)
        curving = np.divide(across, self.lengths, out=np.zeros_like(across), where=self.lengths > 0)
        return along, np.einsum("nmk,nmk->nm", self.unit, a_end) + curving

    settles = False  # whether the forces decide the wrench they balance (sagging cables: settled_forces)

    @property
    def kinds(self) -> tuple[str, ...]:
        """What the criteria that read it may declare (``Criterion.reads``): its ``kind``; a
        path's samples with a drive are both statics and dynamics."""
        return (self.kind,)

    def balanced_wrenches(self, families) -> np.ndarray:
        """The wrenches the forces balance within the families' intervals: the required ones
        (``pipeline.model.sagging`` moves them by the cables' own weight, which the forces decide)."""
        return self.required_wrenches

    def shapes(self, variables: np.ndarray) -> dict[str, np.ndarray]:
        """(n, m) per quantity of the cables' own shape at the forces ``variables`` (n, m, the
        state's; ``output.cables``): elastic cables' unstrained length, ``unstrained`` (what each
        winch must have paid out, with the cable towards it in series); none for rigid ones."""
        if self.robot.cable_ea is None:
            return {}
        stretched = self.cable_lengths + self.robot.winch_lengths
        return {"unstrained": unstrained_lengths(self.robot.cable_ea, stretched, self.forces_of(variables))}

    def sag_tensions(self, ratio: float) -> np.ndarray:
        """(n, m) the least tension of each cable at its platform end that keeps its sag within
        ``ratio`` of its chord (criterion ``sag``): the parabolic rule, an approximation (docs/model.md
        section 8) of a taut string under its own weight, the load across the chord mu g cos(theta)
        per length over the chord l, whose mid-span sag is mu g cos(theta) l^2 / (8 t) at the
        tension t of its lower end; a cable's tension grows by mu g per metre it rises, so the
        platform's end, when it is the upper one, must pull mu g h more (h its height above the
        anchor): t >= mu g (l cos(theta) / (8 ratio) + max(0, h))."""
        rising = self.unit @ self.robot.up  # sin(theta), positive where the platform's end is the upper one
        across = np.sqrt(np.clip(1.0 - rising ** 2, 0.0, 1.0))
        weight = self.robot.cable_mass * self.load.gravity
        return weight * self.lengths * (across / (8.0 * ratio) + np.maximum(rising, 0.0))

    def diagnostics(self) -> dict[str, np.ndarray]:
        """Per-pose columns besides the margins, set by the criteria that computed them: the
        poses the feasible model's LPs solved, the closest pair of cables, the closest obstacle,
        the least translational and rotational stiffness."""
        found = {"lp_poses": self.tension_lp, "closest_pair": self.closest_pair,
                 "closest_obstacle": self.closest_obstacle,
                 "stiffness_translational_N_per_m": self.stiffness_translational,
                 "stiffness_rotational_Nm_per_rad": self.stiffness_rotational,
                 "stiffness_frequency_Hz": self.frequency}
        if self.stiffness_weakest is not None:  # the direction of the least translational stiffness
            found.update({f"stiffness_weakest_{axis}": self.stiffness_weakest[:, k] for k, axis in enumerate("xyz")})
        return {key: value for key, value in found.items() if value is not None}
