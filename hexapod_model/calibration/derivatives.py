"""The hexapod of one parameter vector and the exact derivative of its solved poses.

Direct kinematics of the corrected geometry, and the derivative of each solved platform pose
with respect to every parameter. The derivative follows from the implicit function theorem on the closure equations
``r(q_free, q_prismatic(theta), theta) = 0`` (the solver's reduced residual, 6 rows per leg):

    dq_free/dtheta = -G_free^-1 (dr/dtheta + G_prismatic dq_prismatic/dtheta),

with ``G`` the exact constraint Jacobian of :class:`~hexapod_model.kinematics.newton.solver.NewtonSolver`
(``Solution.jacobian`` for the free columns; a prismatic joint's column is its axis);
the platform rows of ``dq_free`` are the body twist of the platform pose (Pinocchio's free-flyer
velocity). ``dr/dtheta`` comes from where each parameter moves the URDF's joint placements: a
placement ``M`` changed to ``M exp(xi)`` moves every frame after it by the world twist
``Ad(S) xi`` (``S`` the placement's world frame), which enters the residual like a joint
velocity there. ``dxi/dtheta`` is the complex-step derivative of the leg's home construction
(:mod:`hexapod_model.description.legs`): exact to rounding. Readings enter through the encoder
model ``q = (reading - zero) / (1 + scale)``.

A geometry with redundant sensors (measuring legs, an inclinometer) is solved from its six
legs' readings (the hexapod of the six legs). When the parameter set has the sensors'
unknowns, :meth:`CalibrationModel.extra_readings` predicts the extra readings at those poses
and :meth:`CalibrationModel.extra_jacobian` gives their derivative: through the pose (the
six legs' parameters) and directly (the sensors' own, :mod:`.sensors`); otherwise the sensors
are carried into the corrected geometry as the nominal one has them.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pinocchio as pin

from ..description.legs import leg_axes
from ..exceptions import HexapodError
from ..kinematics.hexapod import Hexapod
from .parameters import LEG_SIZE, ParameterSet
from .sensors import SensorModel

COMPLEX_STEP = 1e-30
SITES = ("cardan_base_1", "cardan_base_2", "roll", "cardan_platform_1", "cardan_platform_2", "tip", "anchor")


def site_placements(ps: ParameterSet, i: int, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rotations (..., 7, 3, 3) and translations (..., 7, 3) of leg ``i``'s URDF placements.

    In the order of :data:`SITES`, for its correction slots ``v`` (..., 14), real or complex.
    """
    v = np.asarray(v)
    a = ps.leg_arrays(i, v)
    ax = leg_axes(a["b"], ps.nominal.home_translation + a["p"], a["a_b"], a["a_p"], a["e_b"], a["e_p"])
    assert ax.platform is not None and ax.platform_rel is not None
    eye = np.broadcast_to(np.eye(3, dtype=v.dtype), ax.base.shape)
    z = np.array([0.0, 0.0, 1.0])
    eb, ep, rest = a["e_b"][..., None], a["e_p"][..., None], np.asarray(ax.rest)[..., None]
    R = [ax.base, eye, ax.roll, ax.platform_rel, eye, eye, ax.platform]
    t = [ax.start, z * eb, 0 * z * eb, z * rest, z * ep, -z * ep / 2, a["p"]]
    return np.stack(R, axis=-3), np.stack(np.broadcast_arrays(*t), axis=-2)


def site_derivatives(ps: ParameterSet, i: int, v: np.ndarray) -> np.ndarray:
    """(7, 6, 14) body twists ``[R^T dt; vex(R^T dR)]`` of leg ``i``'s placements per slot.

    Per unit change of each correction slot, by complex steps (exact to rounding; all slots in
    one batch).
    """
    steps = np.asarray(v, dtype=float) + 1j * COMPLEX_STEP * np.eye(LEG_SIZE)
    R, t = site_placements(ps, i, steps)  # (14, 7, 3, 3), (14, 7, 3)
    R0, dR, dt = R[0].real, R.imag / COMPLEX_STEP, t.imag / COMPLEX_STEP
    out = np.empty((len(SITES), 6, LEG_SIZE))
    out[:, :3, :] = np.einsum("sji,ksj->sik", R0, dt)
    W = np.einsum("sji,ksjl->kisl", R0, dR)  # (14, 3, 7, 3): R0^T dR per slot and site
    out[:, 3, :] = W[:, 2, :, 1].T
    out[:, 4, :] = W[:, 0, :, 2].T
    out[:, 5, :] = W[:, 1, :, 0].T
    return out


class CalibrationModel:
    """The hexapod of the corrections ``delta`` (see :class:`ParameterSet`), with pose derivatives.

    Attributes:
        geometry: the corrected geometry.
        hexapod: the :class:`~hexapod_model.kinematics.hexapod.Hexapod` of its six legs (generated URDF).
    """

    def __init__(self, ps: ParameterSet, delta: np.ndarray):
        self.ps = ps
        self.delta = np.array(delta, dtype=float)
        self.geometry = ps.geometry(self.delta)
        # the six legs' readings are the rows' (measuring legs and an inclinometer stay nominal)
        six = dataclasses.replace(self.geometry, measuring_legs=(), inclinometer=None)
        self.hexapod = Hexapod.from_geometry(six)
        clm = self.hexapod.closed_loop
        if any(len(leg.joints) != 6 for leg in clm.legs):  # pragma: no cover - cardan legs are generated
            raise AssertionError("calibration expects the generated cardan leg chain")
        self._twists = np.array([site_derivatives(ps, i, ps.leg_vector(i, self.delta)) for i in range(6)])
        pris = set(clm.prismatic_v.tolist())
        free = np.array([c for c in range(clm.nv) if c not in pris])  # the forward solver's columns
        self._ff = np.flatnonzero(np.isin(free, np.arange(clm.platform_v, clm.platform_v + 6)))
        m = clm.model
        self._joints = [[leg.joints[k] for k in (0, 1, 2, 4, 5)] for leg in clm.legs]
        self._parents = [[m.parents[j] for j in js] for js in self._joints]
        #: the extra sensors' reading model (``None`` unless the parameter set has their unknowns)
        self.sensors = (
            SensorModel(self.geometry, self.hexapod.home_pose, ps.mount(self.delta)) if ps.sensor_index.size else None
        )

    def forward(self, readings: np.ndarray, guesses: list | None = None) -> tuple[np.ndarray, list, list, np.ndarray]:
        """Solve every row of ``readings`` (N, 6 or more; m) from its first six (the six legs').

        Returns poses (N, 4, 4), configurations and reduced constraint Jacobians (``None``
        where the solve failed) and the (N,) ok mask. ``guesses``: configurations to start from
        (home when ``None`` or when that start fails).
        """
        n = len(readings)
        poses, ok = np.full((n, 4, 4), np.nan), np.zeros(n, bool)
        qs: list[np.ndarray | None] = [None] * n
        jacs: list[np.ndarray | None] = [None] * n
        for k in range(n):
            starts = [None] if guesses is None or guesses[k] is None else [guesses[k], None]
            for start in starts:
                try:
                    sol = self.hexapod.forward(readings[k, :6], guess=start, check=False)
                except HexapodError:  # readings outside this geometry's stroke: the row fails
                    break
                if sol.converged and sol.jacobian is not None:
                    poses[k], qs[k], jacs[k], ok[k] = sol.pose, sol.q, sol.jacobian, True
                    break
        return poses, qs, jacs, ok

    def pose_jacobian(self, q: np.ndarray, G_free: np.ndarray) -> np.ndarray:
        """(6, P) derivative of the platform pose at the solved configuration ``q``.

        With respect to the corrections: body twist ``[v; w]`` of the platform frame (m, rad)
        per unit parameter. ``G_free`` is the reduced constraint Jacobian there
        (``Solution.jacobian``).
        """
        hexa = self.hexapod
        clm, m, d = hexa.closed_loop, hexa.model, hexa.data
        pin.forwardKinematics(m, d, q)
        pin.updateFramePlacements(m, d)
        sel = np.zeros((G_free.shape[0], 6))
        sel[self._ff, np.arange(6)] = 1.0
        Z = np.linalg.solve(G_free.T, sel).T  # platform rows of G_free^-1
        ad = np.empty((6, len(SITES), 6, 6))  # body -> world twist maps of every site
        tips, anchors = [], []
        for i, leg in enumerate(clm.legs):
            for s, (j, par) in enumerate(zip(self._joints[i], self._parents[i])):
                ad[i, s] = (d.oMi[par] * m.jointPlacements[j]).action
            tips.append(d.oMf[leg.tip_frame])
            anchors.append(d.oMf[leg.anchor_frame])
            ad[i, 5], ad[i, 6] = tips[-1].action, anchors[-1].action
        world = ad @ self._twists  # (6 legs, 7 sites, 6, 14)
        R_tip, R_anchor = np.array([M.rotation for M in tips]), np.array([M.rotation for M in anchors])
        E = R_tip @ np.swapaxes(R_anchor, 1, 2)
        op_tip = _operators(np.array([M.translation for M in tips]), E)
        op_anchor = _operators(np.array([M.translation for M in anchors]), np.swapaxes(E, 1, 2))
        block = op_tip @ world[:, :6].sum(axis=1) - op_anchor @ world[:, 6]  # (6, 6, 14)
        # the prismatic joint moves the tip along its axis: residual column [axis; 0]
        axis = np.array([d.oMi[leg.prismatic].rotation[:, 2] for leg in clm.legs])
        gain = 1.0 + np.array([leg.encoder_scale for leg in self.geometry.legs])
        block[:, :3, 12] -= axis / gain[:, None]  # q = (reading - zero) / (1 + scale)
        block[:, :3, 13] -= axis * (q[clm.prismatic_q] / gain)[:, None]
        dr = np.zeros((G_free.shape[0], self.ps.size))
        for i in range(6):
            cols = self.ps.legs[i]
            dr[6 * i : 6 * i + 6, cols] = block[i, :, : len(cols)]
        return -Z @ dr

    def extra_readings(self, P: np.ndarray) -> np.ndarray:
        """(N, m) the extra sensors' readings at platform poses ``P`` (N, 4, 4), reading order (m, rad)."""
        assert self.sensors is not None
        return self.sensors.readings(P)

    def extra_jacobian(self, P: np.ndarray, pose_jacobians: np.ndarray) -> np.ndarray:
        """(N, m, P) derivative of :meth:`extra_readings` w.r.t. the corrections.

        ``pose_jacobians``: (N, 6, P) :meth:`pose_jacobian` of each row (the six legs'
        parameters move the pose the readings are taken at).
        """
        assert self.sensors is not None
        pose, own = self.sensors.derivatives(P)
        out = pose @ pose_jacobians
        out[:, :, self.ps.sensor_index] += own[:, :, self.ps.sensor_columns]
        return out

    def reading_jacobian(self, pose_jacobian: np.ndarray) -> np.ndarray:
        """(6, 6) derivative of the solved pose (body twist) w.r.t. the six legs' readings (m).

        From :meth:`pose_jacobian`: a reading enters as ``reading - zero``.
        """
        zeros = [self.ps.index(f"leg{i + 1}.encoder_zero_m") for i in range(6)]
        return -pose_jacobian[:, zeros]


def _operators(points: np.ndarray, E: np.ndarray) -> np.ndarray:
    """(n, 6, 6) ``[I, -[p]x; 0, (tr(E) I - E) / 2]`` of each closure side.

    How that side's residual changes when its frame (origin ``p``) moves by a world twist
    ``[v; w]``.
    """
    out = np.zeros((len(points), 6, 6))
    out[:, :3, :3] = np.eye(3)
    x, y, z = points.T
    out[:, 0, 4], out[:, 0, 5], out[:, 1, 5] = z, -y, x
    out[:, 1, 3], out[:, 2, 3], out[:, 2, 4] = -z, y, -x
    out[:, 3:, 3:] = 0.5 * (np.trace(E, axis1=1, axis2=2)[:, None, None] * np.eye(3) - E)
    return out
