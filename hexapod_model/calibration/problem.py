"""The least-squares problem of a calibration: measured poses, residuals and their exact Jacobian.

The unknowns are the free scaled corrections ``z`` (the geometry is ``delta = D z``, ``D`` the
identifiability basis times the parameter scales, so held parameters stay exactly nominal) and
the right twists of the measuring and marker frames (in units of :data:`FRAME_SCALE`, through
``pin.Jexp6``). Rows are the whitened pose residuals of
:mod:`~hexapod_model.calibration.frames` (6 per measured row), then, when the parameter set
has the extra sensors' unknowns, the whitened residuals of the extra readings (``m`` per
measured row): ``W_k (h(P_k) - z_k)``, ``h`` the readings the model predicts at the pose
solved from the six legs, ``z_k`` the measured ones, and ``W_k`` the inverse Cholesky factor
of their covariance ``diag(sigma^2) + sigma_enc^2 H_k H_k^T``: each sensor's stated noise
(as ``Hexapod.forward`` weighs it) and the six legs' encoder noise carried through the pose
(``H_k`` the derivative of ``h(P_k)`` w.r.t. the six readings), so that each row is in units
of its standard deviation. ``W`` is taken at the geometry the problem starts from and held
(:func:`sensor_whitening`). A trial geometry that is not valid or cannot solve a row gets
:data:`PENALTY` residuals, so the step is rejected.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..exceptions import HexapodError, InputError
from .derivatives import CalibrationModel
from .frames import frame_jacobian, predict, residual, twist_jacobian
from .sensors import SensorModel, reading_sigmas

FRAME_SCALE = 1e-3  # m and rad: expected size of the frame corrections after the initial alignment
SENSOR_STEPS = 10  # Gauss-Newton steps of the sensors' start (fit_sensors)
PENALTY = 1e8  # residual (stated sigmas) of a row a trial geometry cannot solve: the step is always rejected


@dataclass(frozen=True)
class MeasuredPoses:
    """Readings (N, 6 + e) and measured poses (N, 4, 4).

    The readings are the six legs' (m), then the ``e`` extra sensors' in the geometry's
    reading order (m for measuring legs, rad for tilts), if any. The measured poses are those
    of the marker frame in the measuring device's frame; ``lines`` names each row in messages
    (CSV line numbers).
    """

    readings: np.ndarray
    measured: np.ndarray
    source: str = "<data>"
    lines: tuple[int, ...] | None = None

    def __post_init__(self) -> None:
        r, M = np.asarray(self.readings, dtype=float), np.asarray(self.measured, dtype=float)
        if r.ndim != 2 or r.shape[1] < 6 or M.shape != (len(r), 4, 4):
            raise InputError("measured poses", (r.shape, M.shape), "need readings (N, 6 or more) and poses (N, 4, 4)")
        if not (np.all(np.isfinite(r)) and np.all(np.isfinite(M))):
            raise InputError("measured poses", self.source, "readings and poses must be finite")
        if self.lines is not None and len(self.lines) != len(r):
            raise InputError("lines", len(self.lines), f"need one line number per row ({len(r)})")
        object.__setattr__(self, "readings", r)
        object.__setattr__(self, "measured", M)

    @property
    def extra(self) -> int:
        """Number of extra readings a row carries (beyond the six legs')."""
        return self.readings.shape[1] - 6

    def six(self) -> MeasuredPoses:
        """The same rows with the six legs' readings only."""
        return MeasuredPoses(self.readings[:, :6], self.measured, self.source, self.lines)

    def line(self, k: int) -> str:
        """How row ``k`` is named in messages."""
        return f"line {self.lines[k]}" if self.lines is not None else f"row {k + 1}"

    def subset(self, rows: np.ndarray) -> MeasuredPoses:
        """The rows ``rows`` only."""
        lines = None if self.lines is None else tuple(self.lines[k] for k in rows)
        return MeasuredPoses(self.readings[rows], self.measured[rows], self.source, lines)


class Problem:
    """The least-squares problem in the free scaled corrections ``z`` and the frame twists.

    Args:
        ps: the parameter set.
        data: the measured poses.
        noise: the stated noise (row weights).
        basis: (P, n) basis of the free scaled corrections.
        frames: ``(T_mb, T_pm)`` the frame twists are relative to.
        guesses: configurations to start each row's direct kinematics from (or ``None``).
        whitening: (N, m, m) the extra readings' whitening (:func:`sensor_whitening`), or
            ``None`` without the sensors' unknowns.
    """

    def __init__(self, ps, data, noise, basis, frames, guesses, whitening=None):
        self.ps, self.data, self.noise, self.basis = ps, data, noise, basis
        self.whitening = whitening
        self.m = 0 if whitening is None else whitening.shape[1]
        self.T_mb0, self.T_pm0 = frames
        self.D = basis * ps.scales[:, None]  # delta = D @ z
        self.D[np.linalg.norm(basis, axis=1) < 1e-12] = 0.0  # held parameters stay exactly nominal
        self.guesses = guesses
        self.cache: dict = {}
        self.evaluations = 0

    def unpack(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``(delta, T_mb, T_pm, twist_mb, twist_pm)`` of the unknowns ``x``."""
        n = self.D.shape[1]
        mb, pm = x[n : n + 6] * FRAME_SCALE, x[n + 6 :] * FRAME_SCALE
        return self.D @ x[:n], self.T_mb0 @ pin.exp6(mb).homogeneous, self.T_pm0 @ pin.exp6(pm).homogeneous, mb, pm

    def state(self, x: np.ndarray) -> tuple:
        """Model, poses, configurations, Jacobians, ok mask and frames at ``x`` (cached: the last ``x``)."""
        key = x.tobytes()
        if key not in self.cache:
            delta, T_mb, T_pm, _, _ = self.unpack(x)
            try:
                model = CalibrationModel(self.ps, delta)
            except HexapodError:  # a trial step to no valid geometry (a negative offset): rejected
                n = len(self.data.readings)
                self.cache = {key: (None, np.full((n, 4, 4), np.nan), [None] * n, [None] * n, np.zeros(n, bool))}
                self.cache[key] += (T_mb, T_pm)
                return self.cache[key]
            P, qs, Gs, ok = model.forward(self.data.readings, self.guesses)
            self.evaluations += 1
            if ok.all():
                self.guesses = qs
            self.cache = {key: (model, P, qs, Gs, ok, T_mb, T_pm)}
        return self.cache[key]

    def rows(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Whitened residuals at ``x``: (N, 6) of the poses and (N, m) of the extra readings."""
        model, P, _, _, ok, T_mb, T_pm = self.state(x)
        r = np.full((len(P), 6), PENALTY)
        r[ok] = residual(predict(T_mb, P[ok], T_pm), self.data.measured[ok], self.noise)
        e = np.full((len(P), self.m), PENALTY)
        if self.m and ok.any():
            e[ok] = extra_residual(model, P[ok], self.data.readings[ok, 6:], self.whitening[ok])
        return r, e

    def fun(self, x: np.ndarray) -> np.ndarray:
        """(6N + mN,) whitened residuals at ``x``: the poses' rows, then the extra readings'."""
        r, e = self.rows(x)
        return np.concatenate([r.reshape(-1), e.reshape(-1)])

    def jac(self, x: np.ndarray) -> np.ndarray:
        """(6N + mN, n) their exact derivative at ``x`` (raises when a row cannot be solved there)."""
        model, P, qs, Gs, ok, T_mb, T_pm = self.state(x)
        if not ok.all():
            raise InputError(
                "measured data",
                self.data.source,
                "no geometry near nominal explains the readings: the fit reached a geometry that cannot "
                "solve every row; check NOMINAL, the leg order and the units (m)",
            )
        _, _, _, mb, pm = self.unpack(x)
        Jg, Jf = jacobians(model, P, qs, Gs, T_mb, T_pm, self.data.measured, self.noise, self.whitening)
        Jf = Jf.copy()
        Jf[:, :6] = Jf[:, :6] @ pin.Jexp6(mb) * FRAME_SCALE
        Jf[:, 6:] = Jf[:, 6:] @ pin.Jexp6(pm) * FRAME_SCALE
        return np.hstack([Jg @ self.D, Jf])


def jacobians(model, P, qs, Gs, T_mb, T_pm, measured, noise, whitening=None) -> tuple[np.ndarray, np.ndarray]:
    """Whitened residual derivatives w.r.t. the corrections (6N + mN, P) and the frames (6N + mN, 12).

    The frame columns are right twists of the measuring frame, then the marker frame; the
    extra readings' rows (with ``whitening``, see :func:`sensor_whitening`) do not depend on them.
    """
    n = len(P)
    A = T_mb @ P
    Jpose = twist_jacobian(A, np.broadcast_to(T_pm, (n, 4, 4)), measured, noise)
    dP = np.array([model.pose_jacobian(qs[k], Gs[k]) for k in range(n)])  # (N, 6, P)
    Jg = np.concatenate([Jpose[k] @ dP[k] for k in range(n)])
    Jf = frame_jacobian(T_mb, P, T_pm, measured, noise).reshape(6 * n, 12)
    if whitening is None or not whitening.shape[1]:
        return Jg, Jf
    Je = (whitening @ model.extra_jacobian(P, dP)).reshape(-1, Jg.shape[1])
    return np.vstack([Jg, Je]), np.vstack([Jf, np.zeros((len(Je), 12))])


def extra_residual(model: CalibrationModel, P: np.ndarray, readings: np.ndarray, whitening: np.ndarray) -> np.ndarray:
    """(N, m) whitened residuals ``W_k (h(P_k) - z_k)`` of the extra readings ``readings`` (N, m)."""
    return np.einsum("nij,nj->ni", whitening, model.extra_readings(P) - readings)


def sensor_whitening(model: CalibrationModel, P: np.ndarray, qs: list, Gs: list) -> np.ndarray:
    """(N, m, m) inverse Cholesky factors of the extra readings' covariance at each row (module doc).

    The sensors' stated sigmas and the six legs' ``encoder_sigma`` of ``model.geometry``.
    """
    geom = model.geometry
    sigma2 = np.diag(reading_sigmas(geom) ** 2)
    dP = np.array([model.pose_jacobian(qs[k], Gs[k]) for k in range(len(P))])
    pose = model.sensors.derivatives(P)[0] if model.sensors is not None else np.zeros((len(P), 0, 6))
    H = pose @ np.array([model.reading_jacobian(J) for J in dP])  # (N, m, 6) per six-leg reading
    C = sigma2 + geom.encoder_sigma**2 * H @ np.swapaxes(H, 1, 2)
    return np.linalg.inv(np.linalg.cholesky(C))


def fit_sensors(
    ps, home: np.ndarray, P: np.ndarray, readings: np.ndarray, whitening: np.ndarray, held: tuple[int, ...]
) -> np.ndarray:
    """Corrections (P,) of the extra sensors' free unknowns alone that fit their ``readings`` (N, m).

    At the platform poses ``P`` (N, 4, 4) solved by the nominal geometry from the six legs
    (``home``: its 4x4 home pose), with the rows' ``whitening`` (:func:`sensor_whitening`);
    every other correction stays zero. Gauss-Newton in the scaled unknowns (minimum norm where
    the data do not determine them): the start of the whole fit, whose sensors' residuals are
    otherwise hundreds of standard deviations at nominal (an inclinometer's mounting error of
    0.3 deg is 260 of its 20 urad).
    """
    free = np.array([k for k in ps.sensor_index if k not in set(held)], dtype=int)
    delta = np.zeros(ps.size)
    if not free.size:
        return delta
    cols = ps.sensor_columns[np.isin(ps.sensor_index, free)]
    for _ in range(SENSOR_STEPS):
        model = SensorModel(ps.geometry(delta), home, ps.mount(delta))
        r = np.einsum("nij,nj->ni", whitening, model.readings(P) - readings).reshape(-1)
        J = (whitening @ model.derivatives(P)[1][:, :, cols]).reshape(len(r), -1) * ps.scales[free]
        step = np.linalg.lstsq(J, -r, rcond=None)[0] * ps.scales[free]
        delta[free] += step
        if np.max(np.abs(step) / ps.scales[free]) < 1e-10:
            break
    return delta
