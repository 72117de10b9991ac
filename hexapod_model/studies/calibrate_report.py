"""What ``hexapod calibrate`` reports: the JSON document and the text report.

JSON keys (scripts rely on them): ``before``, ``after`` and, for a simulation,
``true_geometry`` (each with :data:`~hexapod_model.calibration.frames.ERROR_KEYS`);
``measuring_frame`` (4x4: the base frame in the measuring device's frame), ``marker_frame``
(4x4: the measured frame in the platform frame), ``parameters`` (a list of ``{"name",
"nominal", "identified", "sigma", "identifiable"}``, SI units as the names say; ``sigma`` is
``null`` for a parameter held at nominal). Also: ``poses``, ``validation``,
``identifiability``, ``decision`` (whether the calibrated geometry predicts held-out poses
better than nominal beyond the uncertainty, both figures, and whether the file was written)
and, for a simulation, ``truth``. For a geometry with extra sensors: ``extra_sensors``
(their reading names, whether their readings were equations of the fit, the RMS of their
whitened residuals) and, when they were, ``after_without_extra_sensors`` (the held-out errors
of the same folds fitted from the six legs alone, :data:`~hexapod_model.calibration.frames.ERROR_KEYS`)
beside ``after`` (the fit with them).
"""

from __future__ import annotations

import math

import numpy as np

from ..calibration.frames import ERROR_KEYS, Noise, error_stats
from ..calibration.validation import IMPROVEMENT_SIGMAS, verdict
from ..lie import log3
from .calibrate import CalibrationResult

SIGMA_LIMIT = 3.0  # the simulated study's check: identified parameters within this many sigma of the truth


def truth_check(result: CalibrationResult) -> dict | None:
    """How the identifiable parameters compare with the simulated truth (``None`` without one)."""
    if result.truth is None:
        return None
    ident = result.identification
    z = (ident.delta - result.truth) / ident.sigma
    k = int(np.nanargmax(np.abs(z)))
    ok = np.abs(z[ident.identifiable]) <= SIGMA_LIMIT
    return {
        "identifiable": int(ident.identifiable.sum()),
        "within_3_sigma": int(ok.sum()),
        "worst": {"name": ident.parameters.names[k], "error_over_sigma": float(z[k])},
    }


def report_json(result: CalibrationResult, written: bool | None = None) -> dict:
    """The ``--json`` document (see the module doc); ``written``: whether the geometry file was written."""
    ident, val = result.identification, result.validation
    ps = ident.parameters
    nominal, values = ps.nominal_values(), ps.values(ident.delta)
    out: dict = {
        "poses": len(result.data.readings),
        "before": error_stats(val.before),
        "after": error_stats(val.after),
    }
    if val.after_without_sensors is not None:
        out["after_without_extra_sensors"] = error_stats(val.after_without_sensors)
    if result.true_errors is not None:
        out["true_geometry"] = error_stats(result.true_errors)
    if ps.nominal.redundant:
        out["extra_sensors"] = {
            "readings": list(ps.nominal.reading_names[6:]),
            "used": ident.sensors,
            "residual_rms_sigmas": ident.sensor_rms,
        }
    out["measuring_frame"] = ident.measuring_frame.tolist()
    out["marker_frame"] = ident.marker_frame.tolist()
    out["parameters"] = [
        {
            "name": name,
            "nominal": float(nominal[k]),
            "identified": float(values[k]),
            "sigma": None if not ident.identifiable[k] else float(ident.sigma[k]),
            "identifiable": bool(ident.identifiable[k]),
        }
        for k, name in enumerate(ps.names)
    ]
    out["validation"] = {"folds": val.folds, "held_out": "every pose once, predicted by the other folds' fit"}
    out["identifiability"] = {
        "singular_values": ident.spectrum.tolist(),
        "held": [c.describe() for c in ident.combinations],
        "noise_factor": ident.noise_factor,
    }
    v = verdict(val)
    out["decision"] = {
        "better_than_nominal": v.better,
        "held_out_translation_mean_mm": {"nominal": v.before_mm, "calibrated": v.after_mm},
        "held_out_rotation_mean_deg": {"nominal": v.before_deg, "calibrated": v.after_deg},
        "uncertainty_mm": v.uncertainty_mm,
        "uncertainty_deg": v.uncertainty_deg,
        "rule": f"better: the mean drops by more than {IMPROVEMENT_SIGMAS:g} standard errors of the paired "
        "difference (translation) and the rotation mean does not rise by more than as many",
        "written": written,
    }
    check = truth_check(result)
    if check is not None:
        out["truth"] = check
    return out


def _row(label: str, stats: dict) -> str:
    return (
        f"{label:34s}"
        + "".join(f"{stats[k]:9.4f}" for k in ERROR_KEYS[:3])
        + "  |"
        + "".join(f"{stats[k]:9.4f}" for k in ERROR_KEYS[3:])
    )


def format_report(result: CalibrationResult, noise: Noise, details: bool = False) -> str:
    """The text report (``details``: every parameter, the singular values and all held combinations)."""
    ident, val = result.identification, result.validation
    ps = ident.parameters
    n = len(result.data.readings)
    lines = [
        f"{ps.nominal.name}: {n} poses from {result.data.source}; stated noise {noise.position_m * 1e3:g} mm, "
        f"{math.degrees(noise.rotation_rad):g} deg (a-posteriori factor {ident.noise_factor:.3f})",
        f"{'pose errors, held out (' + str(val.folds) + '-fold)':34s}{'mean':>9s}{'std':>9s}{'max':>9s}  |"
        f"{'mean':>9s}{'std':>9s}{'max':>9s}",
        f"{'':34s}{'[mm]':>27s}  |{'[deg]':>27s}",
        _row("before: nominal, frames fitted", error_stats(val.before)),
    ]
    if val.after_without_sensors is None:
        lines.append(_row("after: calibrated", error_stats(val.after)))
    else:
        lines.append(_row("after: calibrated, extra readings", error_stats(val.after)))
        lines.append(_row("after: calibrated, six legs only", error_stats(val.after_without_sensors)))
    if result.true_errors is not None:
        lines.append(_row("true geometry (same data)", error_stats(result.true_errors)))
    if ps.nominal.redundant:
        extra = ", ".join(ps.nominal.reading_names[6:])
        lines.append(
            f"extra sensors ({extra}): their readings are equations of the fit (residual RMS "
            f"{ident.sensor_rms:.3f} of their standard deviations)"
            if ident.sensors and ident.sensor_rms is not None
            else f"extra sensors ({extra}): no readings in the data; identified from the six legs, sensors kept nominal"
        )
    held = int((~ident.identifiable).sum())
    kind = "joint and sensor" if ident.sensors else "joint"
    lines.append(
        f"identified {ps.size - held} of {ps.size} {kind} parameters and both frames; {held} held at nominal "
        "(combinations the data cannot determine to their tolerance):"
    )
    shown = ident.combinations if details else ident.combinations[:6]
    lines += [f"  {c.describe()}" for c in shown]
    if len(shown) < len(ident.combinations):
        lines.append(f"  ... {len(ident.combinations) - len(shown)} more (--report DIR lists them all)")
    check = truth_check(result)
    if check is not None:
        worst = check["worst"]
        lines.append(
            f"against the simulated truth: {check['within_3_sigma']} of {check['identifiable']} identified "
            f"parameters within 3 sigma (worst {worst['name']}: {worst['error_over_sigma']:+.2f} sigma)"
        )
    for label, T in (("measuring frame (base in device)", ident.measuring_frame), ("marker frame", ident.marker_frame)):
        rot = np.degrees(log3(T[:3, :3]))
        xyz = np.round(T[:3, 3], 5).tolist()
        lines.append(f"{label}: xyz {xyz} m, rotation vector {np.round(rot, 4).tolist()} deg")
    if details:
        lines.append(f"{'parameter':34s}{'nominal':>14s}{'identified':>14s}{'1-sigma':>12s}")
        for k, name in enumerate(ps.names):
            value = ps.values(ident.delta)[k]
            sigma = f"{ident.sigma[k]:12.3g}" if ident.identifiable[k] else f"{'held':>12s}"
            lines.append(f"{name:34s}{ps.nominal_values()[k]:14.7g}{value:14.7g}{sigma}")
        lines.append("singular values (scaled, gauge fixed): " + " ".join(f"{s:.3g}" for s in ident.spectrum))
    if result.seconds:
        lines.append(f"identification and {val.folds}-fold validation: {result.seconds:.1f} s")
    return "\n".join(lines)
