"""A calibration with the extra sensors' readings as equations: the simulated study on reference7 and reference_tilt."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

import hexapod_model as hm
from hexapod_model.calibration.gauge import regauge
from hexapod_model.calibration.identify import identify
from hexapod_model.calibration.validation import cross_validate
from hexapod_model.description.sensors import Inclinometer
from hexapod_model.studies.calibrate import simulate

Z_LIMIT = 4.0  # an identified parameter within this many of its 1-sigma of the truth


@pytest.fixture(scope="module", params=["reference7", "reference_tilt"])
def study(request):
    """60 poses of a perturbed truth (six legs, sensors, frames), fitted with and without the extra readings."""
    sim = simulate(hm.get_preset(request.param), 60, seed=1)
    return sim, identify(sim.nominal, sim.data), identify(sim.nominal, sim.data, sensors=False)


def test_the_extra_sensors_perturbed_parameters_are_recovered(study):
    sim, found, _ = study
    ps = found.parameters
    assert found.sensors and ps.sensor_index.size
    geom, _, _ = regauge(ps, sim.true_geometry, sim.measuring_frame, sim.marker_frame)
    truth = ps.delta_of(geom)
    extra = ps.sensor_index
    assert found.identifiable[extra].all(), [c.describe() for c in found.combinations]
    # the perturbation is of the order of the tolerance; what is identified is known better than that ...
    assert np.all(found.sigma[extra] < ps.scales[extra])
    assert np.max(np.abs(truth[extra]) / ps.scales[extra]) > 0.5
    # ... and recovered within its 1-sigma, derived from the stated noise (and the a-posteriori factor)
    z = (found.delta - truth) / found.sigma
    ok = found.identifiable
    assert np.all(np.abs(z[ok]) < Z_LIMIT), np.array(ps.names)[ok][np.abs(z[ok]) >= Z_LIMIT]
    # every row is whitened by its stated noise: the a-posteriori factor is about 1; the extra rows'
    # RMS is below 1 by what the unknowns they determine absorb, not above it
    assert 0.8 < found.noise_factor < 1.2
    assert found.sensor_rms is not None and 0.5 < found.sensor_rms < 1.1


def test_the_extra_equations_determine_more_of_the_six_legs(study):
    """More rows can only raise J^T J: no fewer of the six legs' parameters are identified."""
    _, found, six = study
    n = six.parameters.size
    assert not six.sensors and six.geometry.measuring_legs == six.parameters.nominal.measuring_legs
    assert found.identifiable[:n].sum() >= six.identifiable.sum()


def test_the_held_out_error_is_reported_with_and_without_the_extra_sensors(study):
    sim, _, _ = study
    val = cross_validate(sim.nominal, sim.data, folds=2, seed=0)
    assert val.after_without_sensors is not None
    for errors in (val.before, val.after, val.after_without_sensors):
        assert all(e.shape == (60,) and np.all(np.isfinite(e)) and np.all(e >= 0) for e in errors)
    six = cross_validate(sim.nominal, sim.data.six(), folds=2, seed=0)
    assert six.after_without_sensors is None  # six readings a row: the six-leg fit only ...
    np.testing.assert_array_equal(six.after[0], val.after_without_sensors[0])  # ... the same one


def test_a_sensor_the_data_cannot_calibrate_is_named_and_held_not_fitted():
    """An inclinometer of 0.1 rad noise cannot place its 0.3 deg mounting rotation: reported and held at nominal."""
    coarse = replace(hm.get_preset("reference_tilt"), inclinometer=Inclinometer(sigma=0.1))
    sim = simulate(coarse, 40, seed=3)
    found = identify(coarse, sim.data)
    ps = found.parameters
    mount = [ps.index(f"inclinometer.mount.{c}_rad") for c in "xyz"]
    assert found.sensors and not found.identifiable[mount].any()
    assert np.all(found.delta[mount] == 0.0) and np.all(np.isnan(found.sigma[mount]))
    assert found.geometry.inclinometer == coarse.inclinometer
    held = {c.held: c for c in found.combinations}
    for k in mount:
        assert held[ps.names[k]].sigma > 1.0  # its 1-sigma if identified: beyond its tolerance
        assert ps.names[k] in held[ps.names[k]].describe()
