"""The actuator model of eqs. (21)-(22), (30)-(34): one catalogue row (motor + gearbox + winch,
``pipeline.model.catalogue``) in SI units, behind the gearbox.

:func:`actuator_model` is the only place where catalogue units become SI and where the model
constants and limits are derived. numpy only: the kernel's worker processes import it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

G_CM2_TO_KG_M2 = 1e-7
RPM_TO_RAD_S = np.pi / 30.0  # the paper's 1/9.5493 in eq. (30)


@dataclass(frozen=True)
class ActuatorModel:
    """One catalogue actuator in SI units, seen behind the gearbox (output shaft).

    Model constants of eq. (22): ``G_v`` (V s^2/rad), ``L_v`` (V s/rad), ``S_v`` (V/(N m)), all
    positive, with u = G_v * theta_ddot + L_v * theta_dot - S_v * M (eq. 21 with the physical
    sign of the load term, :attr:`load_gain`; M = R t the cable's load torque). Limits: ``speed_limit`` (rad/s,
    eq. 30), ``torque_limit`` (N m, eq. 32), ``accel_limit`` (rad/s^2, eq. 33), ``voltage_limit``
    (V, eq. 34). ``winch_radius`` R_i (m) of eq. (18). ``R_r`` (ohm) and ``C_E`` (V s/rad, behind
    the gearbox) give the armature current i = (u - C_E theta_dot) / R_r of a path's samples.
    """

    id: int
    name: str
    power: float
    G_v: float
    L_v: float
    S_v: float
    R_r: float
    C_E: float
    speed_limit: float
    torque_limit: float
    accel_limit: float
    voltage_limit: float
    winch_radius: float

    def described(self) -> dict:
        """What a job's summary says of its actuator."""
        return {"actuator_name": self.name, "actuator_power_W": self.power}

    @property
    def load_gain(self) -> float:
        """Volts per N m of the cable's load torque M = R t (eq. 20) in eq. (21): -S_v.

        theta > 0 pays the cable out (eq. 18), so a pulling cable turns the drum forwards and the
        motor must hold it back: the drum's torque balance J_r theta_ddot = C_M i - B_C theta_dot + M
        and the armature's u = R_r i + C_E theta_dot give u = G_v theta_ddot + L_v theta_dot - S_v M
        (eq. 22's constants). Paying out under tension is the braking quadrant (u below the
        back-EMF), hoisting the motoring one (docs/model.md section 2)."""
        return -self.S_v

    @property
    def scale(self) -> float:
        """The unit of the slack margin under the ``feasible`` model (N m): the torque limit, as
        ``StaticLimits.scale`` is the statics' (N)."""
        return self.torque_limit


def actuator_model(
    row: dict,
    winch_radius: float | None = None,
    gear_ratio: float | None = None,
    xi_in_torque_limit: bool = True,
) -> ActuatorModel:
    """Turn one catalogue row (:meth:`pipeline.model.catalogue.Catalogue.row`) into SI model
    constants and limits (section 3, eqs. 22, 30-34).

    N_M = N_V xi; C_E = C_e N_V; C_M = C_m N_M; B_C = B_c N_V N_M; J_r = J_M N_V N_M.
    ``winch_radius`` and ``gear_ratio`` replace the catalogue's R_i and N_V when given.
    ``xi_in_torque_limit=False`` reads eq. (32) with the gear ratio N_V instead of N_M.
    """
    n_v = row["gear_ratio"] if gear_ratio is None else gear_ratio
    n_m = n_v * row["efficiency"]
    c_e = row["back_emf_V_per_rad_s"] * n_v
    c_m = row["torque_constant_Nm_per_A"] * n_m
    b_c = row["viscous_friction_Nm_per_rad_s"] * n_v * n_m
    j_r = row["inertia_g_cm2"] * G_CM2_TO_KG_M2 * n_v * n_m
    r_r = row["resistance_ohm"]
    torque_limit = row["torque_Nm"] * (n_m if xi_in_torque_limit else n_v)
    return ActuatorModel(
        id=int(row["id"]),
        name=str(row["name"]),
        power=float(row["power_W"]),
        G_v=j_r * r_r / c_m,
        L_v=b_c * r_r / c_m + c_e,
        S_v=r_r / c_m,
        R_r=float(r_r),
        C_E=float(c_e),
        speed_limit=row["speed_rpm"] * RPM_TO_RAD_S / n_v,
        torque_limit=torque_limit,
        accel_limit=row["torque_Nm"] * n_m / j_r,
        voltage_limit=float(row["voltage_V"]),
        winch_radius=float(row["winch_radius_m"] if winch_radius is None else winch_radius),
    )


def voltage_interval(act: ActuatorModel, high, low) -> tuple:
    """(lower, upper, scale) of the load torque M that keeps eq. (34) |other - S_v M| <= U (eq. 21,
    the motor holds M, ``ActuatorModel.load_gain``) for every value of ``other`` (the
    G_v theta_ddot + L_v theta_dot part) in [low, high]: (high - U) / S_v <= M <= (low + U) / S_v,
    in units of U / S_v."""
    volts, s_v = act.voltage_limit, act.S_v
    return (high - volts) / s_v, (low + volts) / s_v, volts / s_v


def rest_tension_cap(act: ActuatorModel) -> float:
    """The largest cable tension (N) the actuator holds at rest: eq. (32)'s |M| <= M_mot N_M and
    eq. (34)'s |u| <= U at theta_dot = theta_ddot = 0, where u = -S_v M (eq. 21), so |M| <= U / S_v;
    M = R t (eq. 20)."""
    return min(act.torque_limit, voltage_interval(act, 0.0, 0.0)[1]) / act.winch_radius
