"""Identify a hexapod's joint geometry from measured poses (nonlinear least squares).

Unknowns: the per-leg corrections of :class:`~hexapod_model.calibration.parameters.ParameterSet`
and the measuring and marker frames (:mod:`~hexapod_model.calibration.frames`); when the
measured rows carry a redundant hexapod's extra readings, also its extra sensors' unknowns
(:mod:`~hexapod_model.calibration.sensors`), with those readings as equations.
``scipy.optimize.least_squares`` (Levenberg-Marquardt) minimises the whitened residuals
(:mod:`~hexapod_model.calibration.problem`) with the exact Jacobian:
:class:`~hexapod_model.calibration.derivatives.CalibrationModel` for the geometry (implicit
function theorem on the closures), closed forms for the frames and the sensors.

Before the fit, :func:`~hexapod_model.calibration.identifiability.analyse` fixes the
gauge and holds at nominal every parameter the data cannot determine; after it, the analysis
is repeated at the solution. With extra sensors, the fit starts from their unknowns fitted
alone to their readings at the nominal poses
(:func:`~hexapod_model.calibration.problem.fit_sensors`). The 1-sigma of each identified
parameter is from the covariance ``s0^2 (J^T J)^-1`` (``s0`` the a-posteriori noise factor,
1 when the stated noise is right) plus what the held parameters, known only to their expected
magnitude, do to it: ``S S^T`` with ``S = (J^T J)^-1 J^T J_held diag(scale_held)`` (a "consider" covariance).
"""

from __future__ import annotations

import fnmatch
import math
from dataclasses import dataclass, replace

import numpy as np
from scipy.optimize import least_squares

from ..description.geometry import HexapodGeometry
from ..exceptions import HexapodError, InputError
from .derivatives import CalibrationModel
from .frames import Noise, fit_frames, predict
from .identifiability import Combination, analyse
from .parameters import ParameterSet
from .problem import FRAME_SCALE, MeasuredPoses, Problem, fit_sensors, jacobians, sensor_whitening

EQUATIONS_PER_UNKNOWN = 2  # at least this many residual rows per unknown
OUTLIER_RMS = 5.0  # a row this many stated sigmas off (RMS over its 6 rows) ...
OUTLIER_MEDIAN = 5.0  # ... and this many times the median row is an outlier
EXPLAINED_RMS = 20.0  # the median row must end below this many stated sigmas
NEAR_NOMINAL = 20.0  # corrections beyond this many expected magnitudes are not "near nominal"


@dataclass(frozen=True)
class Identification:
    """What :func:`identify` found.

    Attributes:
        parameters: the unknowns (names, scales, nominal geometry).
        delta: (P,) identified corrections (SI; 0 where held at nominal).
        sigma: (P,) 1-sigma of each correction (NaN where held).
        identifiable: (P,) False where held at nominal.
        measuring_frame: 4x4 base frame in the measuring device's frame.
        marker_frame: 4x4 measured (marker) frame in the platform frame.
        frame_sigma: (12,) 1-sigma of the two frames' twists (m, rad; measuring then marker).
        combinations: the unidentifiable combinations (and the parameter held for each).
        spectrum: singular values of the scaled identification Jacobian, gauge fixed.
        noise_factor: a-posteriori factor ``s0`` on the stated noise.
        evaluations: model evaluations of the least squares.
        sensor_rms: RMS of the extra readings' whitened residuals (their standard deviations,
            :mod:`~hexapod_model.calibration.problem`) after the fit; ``None`` when the extra
            readings were not equations of the fit.
    """

    parameters: ParameterSet
    delta: np.ndarray
    sigma: np.ndarray
    identifiable: np.ndarray
    measuring_frame: np.ndarray
    marker_frame: np.ndarray
    frame_sigma: np.ndarray
    combinations: tuple[Combination, ...]
    spectrum: np.ndarray
    noise_factor: float
    evaluations: int
    sensor_rms: float | None = None

    @property
    def sensors(self) -> bool:
        """Whether the extra sensors' readings were equations of the fit (and their unknowns identified)."""
        return bool(self.parameters.sensor_index.size)

    @property
    def geometry(self) -> HexapodGeometry:
        """The calibrated geometry."""
        return self.parameters.geometry(self.delta, name=f"{self.parameters.nominal.name}_calibrated")

    def predict(self, readings: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Measured-frame poses (N, 4, 4) the calibrated model predicts for ``readings``, and the ok mask.

        Each pose is solved from the row's six legs' readings (further columns are not used).
        """
        P, _, _, ok = CalibrationModel(self.parameters, self.delta).forward(np.asarray(readings, dtype=float))
        return predict(self.measuring_frame, P, self.marker_frame), ok


def solve_nominal(ps: ParameterSet, data: MeasuredPoses) -> tuple[CalibrationModel, np.ndarray, list, list]:
    """The nominal model and its poses of every row; a row it cannot solve is an :class:`InputError`."""
    model = CalibrationModel(ps, np.zeros(ps.size))
    P, qs, Gs, ok = model.forward(data.readings)
    if not ok.all():
        k = int(np.flatnonzero(~ok)[0])
        try:
            sol = model.hexapod.forward(data.readings[k], check=False)
            why = sol.message or sol.status
        except HexapodError as exc:
            why = str(exc)
        raise InputError(
            "measured row",
            data.line(k),
            f"{data.source}: readings {np.round(data.readings[k], 6).tolist()} m give no "
            f"pose of the nominal hexapod inside its workspace ({why})",
        )
    return model, P, qs, Gs


def _held(ps: ParameterSet, hold: tuple[str, ...]) -> tuple[int, ...]:
    out = []
    for pattern in hold:
        found = [k for k, name in enumerate(ps.names) if fnmatch.fnmatchcase(name, pattern)]
        if not found:
            raise InputError("hold", pattern, "matches no parameter (e.g. 'leg1.encoder_zero_m', '*.base_axis.*')")
        out += found
    return tuple(sorted(set(out)))


def identify(
    nominal: HexapodGeometry,
    data: MeasuredPoses,
    noise: Noise = Noise(),
    *,
    encoder_scale: bool = False,
    hold: tuple[str, ...] = (),
    max_sigma: float = 1.0,
    sensors: bool = True,
) -> Identification:
    """Identify the per-leg geometry and both frames from measured poses.

    Args:
        nominal: the nominal ``cardan`` geometry.
        data: readings and measured poses: six readings a row, or, for a geometry with extra
            sensors, all of ``nominal.reading_names`` (with six a row, the six legs are
            identified and the sensors carried as ``nominal`` has them).
        noise: the stated measurement noise (weights the residuals).
        encoder_scale: also identify each reading's scale error.
        hold: parameter names or ``fnmatch`` patterns to keep at nominal. Offsets that are
            nominally zero (ideal universal joints) are always kept: they cannot be negative.
        max_sigma: a combination whose 1-sigma would exceed this many expected magnitudes is
            held at nominal (see :mod:`~hexapod_model.calibration.identifiability`).
        sensors: use the extra readings the rows carry (``False``: the six-leg fit).

    Raises:
        InputError: readings a row that are neither six nor the geometry's, too few poses for
            the unknowns, a row the nominal hexapod cannot solve, an outlier row (named with
            its error), or data no geometry near nominal explains.
    """
    names = nominal.reading_names
    if data.extra and data.extra != len(names) - 6:
        raise InputError(
            "readings", f"{6 + data.extra} a row", f"{nominal.name} takes 6 or {len(names)} ({', '.join(names)})"
        )
    use = sensors and data.extra > 0
    data = data if use else data.six()
    ps = ParameterSet(nominal, encoder_scale, sensors=use)
    held = _held(ps, hold)
    zero = [k for k, p in enumerate(ps.parameters) if "offset" in p.kind and ps.nominal_values()[k] == 0.0]
    held = tuple(sorted(set(held) | set(zero)))  # an ideal universal joint's offset cannot become negative
    C = ps.gauge_constraints() * ps.scales[None, :]
    per_row = 6 + data.extra
    n_rows, unknowns = len(data.readings), ps.size - len(C) - len(held) + 12
    if per_row * n_rows < EQUATIONS_PER_UNKNOWN * unknowns:
        need = math.ceil(EQUATIONS_PER_UNKNOWN * unknowns / per_row)
        raise InputError(
            "poses",
            n_rows,
            f"{per_row * n_rows} equations for {unknowns} unknowns: need at least {need} measured poses",
        )
    model, P, qs, Gs = solve_nominal(ps, data)
    frames = fit_frames(P, data.measured, noise)
    whitening = sensor_whitening(model, P, qs, Gs) if use else None
    result, delta = None, np.zeros(ps.size)
    if whitening is not None:  # start from the sensors fitted alone at the nominal poses
        delta = fit_sensors(ps, model.hexapod.home_pose, P, data.readings[:, 6:], whitening, held)
    combinations: list[Combination] = []
    for _ in range(3):
        Jg, Jf = jacobians(model, P, qs, Gs, *frames, data.measured, noise, whitening)
        ana = analyse(Jg * ps.scales[None, :], Jf, C, ps.names, max_sigma, held)
        combinations += ana.combinations
        if result is not None and set(ana.held) == set(held):
            break
        held = ana.held
        problem = Problem(ps, data, noise, ana.basis, frames, qs, whitening)
        x0 = np.concatenate([ana.basis.T @ (delta / ps.scales), np.zeros(12)])  # from the previous fit
        result = least_squares(problem.fun, x0, jac=problem.jac, method="lm", xtol=1e-10, ftol=1e-10, gtol=1e-10)
        model, P, qs, Gs, _, T_mb, T_pm = problem.state(result.x)
        frames, delta = (T_mb, T_pm), problem.unpack(result.x)[0]
        problem = Problem(ps, data, noise, ana.basis, frames, qs, whitening)  # frames re-centred on the solution
        result.x = np.concatenate([result.x[: ana.basis.shape[1]], np.zeros(12)])
    assert result is not None
    return _finish(ps, data, noise, problem, result, replace(ana, combinations=tuple(combinations)))


def _finish(ps, data, noise, problem, result, ana) -> Identification:
    """Covariance, outlier and plausibility checks, the :class:`Identification`."""
    delta, T_mb, T_pm, _, _ = problem.unpack(result.x)
    r, e = problem.rows(result.x)
    rms = np.sqrt(np.mean(np.hstack([r, e]) ** 2, axis=1))
    median = float(np.median(rms))
    worst = int(np.argmax(rms))
    if rms[worst] > OUTLIER_RMS and rms[worst] > OUTLIER_MEDIAN * median:
        dp = np.linalg.norm(r[worst, :3]) * noise.position_m * 1e3
        dr = math.degrees(np.linalg.norm(r[worst, 3:]) * noise.rotation_rad)
        extra = f" and its extra readings {np.sqrt(np.mean(e[worst] ** 2)):.3g} sigmas" if e.size else ""
        raise InputError(
            "measured row",
            data.line(worst),
            f"{data.source}: an outlier: after calibration its pose is still {dp:.3g} mm / {dr:.3g} deg off{extra}, "
            f"{rms[worst] / median:.0f} times the median row; check or remove it",
        )
    if median > EXPLAINED_RMS:
        raise InputError(
            "measured data",
            data.source,
            f"no geometry near nominal explains the readings: after calibration the median row is {median:.0f} "
            f"stated sigmas off ({noise.position_m * 1e3:g} mm / {math.degrees(noise.rotation_rad):g} deg); "
            "check NOMINAL, the leg order and the units (m)",
        )
    far = np.abs(delta) > NEAR_NOMINAL * ps.scales
    if far.any():
        k = int(np.argmax(np.abs(delta) / ps.scales))
        raise InputError(
            ps.names[k],
            float(delta[k]),
            f"correction beyond {NEAR_NOMINAL:g} x {ps.scales[k]:g}: no geometry near nominal explains the data",
        )
    J = problem.jac(result.x)
    dof = max(r.size + e.size - J.shape[1], 1)
    s0 = float(np.sqrt((np.sum(r**2) + np.sum(e**2)) / dof))
    _, s, Vt = np.linalg.svd(np.linalg.qr(J, mode="r"))  # QR first: a small SVD
    cov = s0**2 * (Vt.T / s**2) @ Vt
    held = list(ana.held)
    if held:  # the held parameters are only known to their tolerance: add what that does to the rest
        model, P, qs, Gs, _, T_mb, T_pm = problem.state(result.x)
        Jh = jacobians(model, P, qs, Gs, T_mb, T_pm, data.measured, noise, problem.whitening)[0][:, held]
        Jh = Jh * ps.scales[held]
        sensitivity = (Vt.T / s**2) @ Vt @ (J.T @ Jh)
        cov = cov + sensitivity @ sensitivity.T
    n = problem.D.shape[1]
    cov_delta = problem.D @ cov[:n, :n] @ problem.D.T
    sigma = np.sqrt(np.clip(np.diag(cov_delta), 0, None))
    identifiable = np.ones(ps.size, bool)
    identifiable[list(ana.held)] = False
    sigma[~identifiable] = np.nan
    delta[~identifiable] = 0.0
    frame_sigma = FRAME_SCALE * np.sqrt(np.clip(np.diag(cov[n:, n:]), 0, None))
    return Identification(
        ps,
        delta,
        sigma,
        identifiable,
        T_mb,
        T_pm,
        frame_sigma,
        ana.combinations,
        ana.spectrum,
        s0,
        problem.evaluations,
        float(np.sqrt(np.mean(e**2))) if e.size else None,
    )
